// The cloth's edges and triangles against mesh colliders' edges and vertices (docs/model.md section 6.3):
// the particles' contact (colliders.hpp) keeps every particle off a mesh, but a sharp collider edge (a
// bucket's rim) can still pass between two particles and slice the cloth.  This pass treats the three
// kinds of pair between a cloth element and a collider feature as self-collision treats its pairs
// (self_contact/geometry.hpp, response.hpp), the collider immovable: a particle and a collider triangle, a
// cloth edge and a collider edge, a collider vertex and a cloth triangle.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: What collider_edge_contact did: nothing, pushed particles (collider_edge_history then gives them the
//: history of a motion along their push), or, as a last resort, kept particles where they started.
enum EdgeContact : int { UNTOUCHED = 0, PUSHED = 1, STOPPED = 2 };

//: After collider_contact, for the step from x0 to x1 (both (3, n), m; x1 and the end velocities v1 (m/s)
//: changed in place; mass (n) kg, free (n)): every pair of the cloth's elements (contact's edges and
//: triangles) and a mesh collider's features that the straight-line motion brings closer than its distance
//: (a particle and a collider triangle thickness / 2, the others EDGE_GAP times that) is treated as
//: self-collision treats a pair at the thickness: pushed apart to that distance (the collider not moving),
//: its approaching velocity removed, its sliding reduced by the collider's friction times that.  Pairs whose
//: motion still comes closer than a tenth of it (or half their start distance) then have their particles
//: stay where they started, at rest.  A collider moved by keys (collider_motion.hpp) is treated so in its
//: table frame, where it stands still: the start through its place at the step's start, the end through
//: its place at the step's end, the velocities relative to its surface's; the results turned back (a
//: particle that stays where it started is carried with it).  The pairs come from lists kept across steps
//: (one for the still meshes, one for each moving one in its frame; gathered again when a particle moves
//: beyond its allowance; docs/model.md section 6.3), which changes no result; a cloth far from every mesh's
//: box costs a look at each particle's move.  Particles with free 0 (pinned, or held for the step) are not
//: moved by a still mesh, those with model_free 0 (pinned) not by a moving one (which may come onto a
//: particle held on the floor).  Returns EdgeContact flags; lists holds the pairs, the pushes and scratch.
int collider_edge_contact(const Contact& contact, ContactLists& lists, const Physics& phys, Index n,
                          const double* mass, const double* free, const double* model_free, const double* x0,
                          double* x1, double* v1);

//: Before a step from pos (3, n, m): the pairs of each moving mesh collider's features and the cloth's
//: elements (a collider vertex and a cloth triangle, a collider edge and a cloth edge) nearer than within (m)
//: at the step's start, from its kept list in its table frame, and with ahead > 0 (s: fixed steps' max_step)
//: the still meshes' from their kept list in the world, nearer than within plus ahead times the fastest start
//: speed (vel (3, n), m/s) of the pair's cloth particles, as the terms of supports (collider_supports.hpp):
//: each with its closest-point weights, its contact normal and its collider points' weighted sum there;
//: features that lie flat (all their faces in one plane) are left out.  Returns how many.
Index gather_supports(const Contact& contact, ContactLists& lists, const Physics& phys, Index n, const double* pos,
                      const double* vel, double within, double ahead, Supports& supports);

//: The value of Buffers::held for a particle resting on a mesh collider's edge or vertex (the floor's is 1,
//: a layer's 2, an analytic or mesh collider k's surface 3 + k).
inline constexpr double EDGE_HELD = -1.0;

//: Before a step from pos (3, n, m) at vel (3, n, m/s): the free particles of the cloth's edges and
//: triangles (contact's) that lie on a still mesh collider's edge or vertex (a moving one's pushes alone
//: keep them off it), within twice their distance (the
//: edge-edge and vertex-triangle pairs collider_edge_contact keeps apart), at rest there or coming onto it
//: slowly enough that the collider's friction stops them (comes_to_rest), are held for the step as the
//: floor holds its particles (free 0, held EDGE_HELD), each with the direction a push would move it
//: and the collider's friction, in lists.  Returns how many.
Index hold_on_collider_edges(const Contact& contact, ContactLists& lists, const Physics& phys, Index n, const double* pos,
                             const double* vel, double* free, double* held);

//: Release the particles hold_on_collider_edges held that the step's force (N, (3, n)) lifts off their
//: support or pushes along it beyond cone times its friction times the force into it.  Returns how many.
Index release_from_collider_edges(const ContactLists& lists, Index n, const double* force, double* free, double* held,
                                  double cone = 1.0);

//: After an accepted step (pos, vel (3, n) its end): the particles hold_on_collider_edges held that the step's
//: force slides along their support, slid as slip_on_supports slides the floor's (the excess over
//: friction on their inertia, mass and blocks as there, for the step h), and freed for the edges' pass
//: that follows (they moved).  Returns the farthest slide (m), or -1 without moving any if one would
//: slide farther than limit (m) or the force lifts it off: the step is then taken again without them.
double slip_on_collider_edges(const ContactLists& lists, Index n, const double* force, const double* mass,
                              const double* diagonal_blocks, const double* blocks, double h, double limit,
                              double* free, double* held, double* pos, double* vel);

//: After the step is taken (pos, vel its end, prev_pos, prev_vel its start, (3, n)): the particles that
//: collider_edge_contact pushed get the history of a straight motion along their last push (as the
//: floor's normal_history), so that BDF2 goes on.
void collider_edge_history(const ContactLists& lists, Index n, const double* pos, const double* vel, double* prev_pos,
                           double* prev_vel, double h);

}  // namespace wc
