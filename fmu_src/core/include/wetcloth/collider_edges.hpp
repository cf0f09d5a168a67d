// The cloth's edges and triangles against mesh colliders' edges and vertices (docs/model.md section 6.3):
// the particles' contact (colliders.hpp) keeps every particle off a mesh, but a sharp collider edge (a
// bucket's rim) can still pass between two particles and slice the cloth.  This pass treats the three
// kinds of pair between a cloth element and a collider feature as self-collision treats its pairs
// (self_contact/geometry.hpp, response.hpp), the collider immovable: a particle and a collider triangle, a
// cloth edge and a collider edge, a collider vertex and a cloth triangle.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: After collider_contact, for the step from x0 to x1 (both (3, n), m; x1 and the end velocities v1 (m/s)
//: changed in place; mass (n) kg, free (n)): every pair of the cloth's elements (contact's edges and
//: triangles) and a mesh collider's features that the straight-line motion brings closer than
//: thickness / 2 is treated as self-collision treats a pair, at the thickness / 2: pushed apart (the
//: collider not moving), its approaching velocity removed, its sliding reduced by the collider's friction
//: times that.  Pairs whose motion still comes closer than a tenth of that (or half their start distance)
//: then have their particles stay where they started, at rest.  Colliders whose box, grown by thickness
//: / 2, the elements' paths do not reach are skipped.  Returns whether it changed x1 or v1; lists holds
//: the pairs and scratch.
bool collider_edge_contact(const Contact& contact, ContactLists& lists, const Physics& phys, Index n,
                           const double* mass, const double* free, const double* x0, double* x1, double* v1);

}  // namespace wc
