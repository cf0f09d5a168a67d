// Colliders: rigid shapes with Coulomb friction, kept like the floor (docs/model.md section 6.3): analytic
// (plane, box, sphere, cylinder) or a triangle mesh (collider_mesh.hpp).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Shape codes (column SHAPE of a collider row); wetcloth.scene.COLLIDER_SHAPES in this order.
enum ColliderShape : Index { PLANE = 0, BOX = 1, SPHERE = 2, CYLINDER = 3, MESH = 4 };

//: Columns of a collider row (Physics::colliders, (count, COLLIDER_COLUMNS)): shape code; centre (a point
//: of a plane) m; radius m (sphere, cylinder); height m (cylinder, along z); edge lengths m (box, along
//: x, y, z); unit outward normal (plane: the solid lies behind it); Coulomb friction coefficient.  A mesh
//: collider's centre is where its file's origin went (its vertices are placed already) and its C_RADIUS
//: column holds its index among Physics::meshes.
enum ColliderColumn : Index {
    C_SHAPE = 0, C_X, C_Y, C_Z, C_RADIUS, C_HEIGHT, C_SIZE_X, C_SIZE_Y, C_SIZE_Z, C_NORMAL_X, C_NORMAL_Y, C_NORMAL_Z,
    C_FRICTION, COLLIDER_COLUMNS
};

//: Signed distance (m, negative inside) from point p (3) to the surface of collider k of phys, and the unit
//: outward normal there (normal, 3); a mesh collider's is at most reach (m): farther, it is not looked for.
double collider_distance(const Physics& phys, Index k, const double* p, double reach, double* normal);

//: The pinned particle (free 0) of pos (3, n) nearest a collider's surface, no farther than the thickness / 2
//: that contact keeps the cloth off it: its index, the collider's and its signed distance (m, negative inside);
//: particle and collider -1 where none is that close.  (A blow-up's likely cause: the grip presses it into the
//: collider, and contact pushes it back out at every step, while its neighbours follow.)
struct PinnedPressed {
    Index particle = -1, collider = -1;
    double distance = 0.0;
};
PinnedPressed pinned_pressed(const Physics& phys, Index n, const double* free, const double* pos);

//: As collider_distance, for the collider of row `row` where its row puts it (unmoved), from point p (3).
double table_distance(const Physics& phys, const double* row, const double* p, double reach, double* normal);

//: After a step from start (3, n) to pos (3, n): every particle whose centre is closer than gap =
//: thickness / 2 to a collider is put back at distance gap along the outward normal; one whose path
//: crossed a mesh collider's triangle goes back to the side it came from, gap off that triangle.  Its
//: velocity into the collider is removed and its tangential velocity reduced by friction times that (never
//: reversed); against a moving collider (collider_motion.hpp) the velocity relative to its.  Colliders whose
//: box, grown by gap, the cloth's path does not reach are skipped.  Returns how many particles touched; in
//: kick (m/s, unless null) the largest change of a particle's velocity along a moving collider's surface.
Index collider_contact(Index n, const Physics& phys, const double* start, double* pos, double* vel,
                       double* kick = nullptr);

//: How fast (1/s) the outward normal of the surface at thickness / 2 off collider k turns under a particle
//: with normal nrm (3) there that slides at velocity v (3, m/s, along the surface, relative to it): into
//: turning (3), the surface's shape operator applied to v: a sphere's v / (r + thickness / 2), a cylinder's
//: side (v - (v . axis) axis) / (r + thickness / 2); zero on flat faces (planes, boxes, cylinders' caps,
//: meshes) and on rounded edges and corners.  Returns whether it is not zero.
bool normal_turning(const Physics& phys, Index k, const double* nrm, const double* v, double* turning);

//: The first collider that particle i of pos (3, n) touches: within thickness / 2 of it, up to rounding
//: (where collider_contact puts a particle), and `slack` (m) for a still collider of analytic shape with friction
//: (whose supports the fixed steps' solve sees: collider_analytic_supports.hpp), its normal there into nrm; -1 if
//: none.
Index touched_collider(const Physics& phys, Index n, Index i, const double* pos, double* nrm, double slack = 0.0);

//: At fixed implicit steps a particle still touches a still analytic collider with friction (is held on it, or
//: slides on it with its friction) up to this fraction of thickness / 2 beyond its contact distance (on a frictionless
//: one, where it has no friction to give, a sheet sliding off a ball took twice the steps again, 4 starts of
//: bench/frame_step_energy.py, and stretched its springs by 6-9 % against 4-6 %): the step's solve may leave one
//: that its support caught (collider_analytic_supports.hpp) that far above it, where the line search stopped
//: short of the support's wall, and collider_contact then leaves it there.  Without it a sheet lying on a
//: 15 deg plane of friction 5 hovered 0.3-0.9 um above it for as long as another sheet slid on it, never held,
//: its friction only what each step's first iterate met, and slid 2.2 mm in one frame (bench/layer_friction.py).
inline constexpr double FRAME_TOUCH_SLACK = 0.01;

//: The value of Buffers::held for a particle collider k holds (the floor's is 1, a layer's 2).
inline double collider_held(Index k) { return 3.0 + static_cast<double>(k); }

//: As the floor's hold_resting: the free particles on a collider (within gap m) with zero velocity
//: (friction stopped them) are held for the coming step (free 0, held collider_held(k)); on a moving collider
//: at its surface's velocity there, on a turning one within |omega| |omega x r| last_step (s) of it (the
//: change of the surface's velocity over the last step's travel, which a step stopping a particle on it
//: leaves); touching as touched_collider's with `slack` (m).  Returns how many.
Index hold_on_colliders(Index n, const Physics& phys, const double* pos, const double* vel, double* free, double* held,
                        double last_step = 0.0, double slack = 0.0);

//: Into out (3, n): the outward normal of the collider each particle lies on through a step from pos (3, n),
//: held on it (held (n): collider_held(k)) or sliding on it (sliding, null if none); zero for the others.
//: Returns how many have one.
Index supported_normals(Index n, const Physics& phys, const double* pos, const double* held, const Sliding* sliding,
                        double* out);

//: As the floor's release_slipping: release the particles held on a collider that the step's force (N,
//: (3, n)) lifts off it or pushes along it above cone times friction times the force into it (on a turning
//: collider the force less mass (kg, (n)) times the surface's centripetal acceleration); with `still_only`, only
//: those on colliders that do not move and have friction.  Returns how many.
Index release_from_colliders(Index n, const Physics& phys, const double* pos, const double* force, const double* mass,
                             double* free, double* held, double cone = 1.0, bool still_only = false);

//: Put particle i, which a step moved along a tangent plane of collider k where it curves (a sphere, a
//: cylinder's side), exactly back onto it (at reach m along its normal there) and turn its velocity relative
//: to the surface along the surface there, keeping its speed; pos (3, n) is the step's end, seen with the
//: collider where the step started (end_collider_motion comes after).  A turning collider other than a
//: sphere is left alone.  Returns how far it moved (m).
double onto_surface(const Physics& phys, Index k, Index n, Index i, double reach, double h, double* pos, double* vel);

//: Instead of taking the step again: the particles held on the floor or a collider that the step's force
//: (N, (3, n)) would have slipped or lifted (release_slipping's and release_from_colliders's test) move
//: as they would have from rest over the step of h s under the force's excess beyond friction
//: (slip_force; a = excess / m_e): pos (3, n) by a h^2 / 2 and vel by a h (they stay marked held: the step's
//: end releases every hold, and a step taken again for its error holds them again, as its first try did); provided
//: each of them moves at most `limit` m (the error the step may make) and a collider's is still on it (a
//: moving collider's looked at where it held the particle: pos less its motion over the step, or its
//: start (3, n) on a turning one, whose force is less mass times the surface's centripetal acceleration).
//: m_e (kg) is the particle's effective mass along the excess in the step's own matrix: its mass (n)
//: plus e^T (D_i + B_i) e, e the excess's direction, D_i its springs' part of its diagonal block
//: (diagonal_blocks (6, n)) and B_i its own (blocks (6, n): drag, buoyancy), as the implicit step left
//: them (docs/model.md section 6.1); the mass alone when diagonal_blocks is null (explicit schemes).  One
//: that slips over a curved collider is put back onto it (onto_surface) and turned along it.
//: Returns the farthest such move (m, 0 if none slips), or -1 with nothing changed when one would move
//: farther (the step is then to be taken again).  Layers' holds are not looked at.
double slip_on_supports(Index n, const Physics& phys, const double* force, const double* mass,
                        const double* diagonal_blocks, const double* blocks, double h, double limit,
                        const double* held, const double* start, double* pos, double* vel);

//: The particles on a collider (within gap m, where collider_contact left them) get the history of a
//: straight motion along its normal (as the floor's agree_history), but for those marked in on_path (n, or
//: null: none), which keep their own (mark_curved_paths).  Returns how many got it.
Index collider_history(Index n, const Physics& phys, const char* on_path, const double* pos, const double* vel,
                       double* prev_pos, double* prev_vel, double h);

}  // namespace wc
