// The finest tier's windows that hold no candidate pair, shown without searching them (broad_phase.cpp's
// build).  A sheet that swings or drapes is smooth over a few grid spacings, and its candidate list is
// mostly empty: searching the fabric's neighbours again at every rebuild is what a rebuild costs.
//
// Project a window's neighbourhood R (its cells and the ring of cells around them, in the rest sheet)
// onto the plane across its mean normal nu.  Projection shortens no distance in that plane's favour: two
// elements at least h apart in it are at least h apart in space.  Two arguments give such an h:
// - The map from the rest sheet to that plane is piecewise linear, with Jacobian J_t on triangle t.  If
//   every J_t lies within eps of one matrix A (spectral norms), then over a convex rest region any two
//   points u1, u2 map at least (sigma_min(A) - eps) |u2 - u1| apart: the map is one to one if
//   sigma_min(A) > eps, and elements at least rest_gap apart at rest (any two that share no particle) lie
//   at least (sigma_min(A) - eps) rest_gap apart in the plane.
// - Where the map is one to one, a particle v away from the sheet's rim has its star (its triangles) laid
//   around it in the plane, covering the disc of radius h(v), the least of its triangles' projected
//   altitudes from v; every element that does not hold v lies outside that star, so at least h(v) from v.
//   Two edges that share no particle are as far apart as the nearest of their ends from the other edge:
//   at least the least h of their particles.  A triangle's projected altitude is at least its altitude in
//   space times the cosine of the angle between its normal and nu.
// A window of the finest tier is shown to hold no pair within `reach` where the first argument gives at least
// reach, or, away from the rim, the map is one to one and the second does.  A window of a coarser tier s
// holds pairs at least rest_distance_beyond(s - 1) apart at rest (those of its own tier): the first
// argument with that distance shows them out of reach.  The bounds are taken over the cells' triangles
// (their mean Jacobians, how far each strays from it, their normals' cone and least altitude), so that a
// window costs a few operations per cell.  R must be convex: where the rest sheet is not (a mesh with a
// notch or a hole), nothing is shown.
#pragma once

#include <vector>

#include "wetcloth/core.hpp"
#include "wetcloth/self_contact/tiers.hpp"

namespace wc::self_contact {

//: The windows shown free of pairs at positions x (3, n) m, within `reach` (m), for one list's build; keeps its
//: figures in contact.lists (flat_*).  prepare_tiers first.
class FlatWindows {
public:
    //: (`tried` false: nothing is shown, judged() is false.)
    FlatWindows(const Contact& contact, Index n, const double* x, double reach, bool tried = true);
    //: Whether windows can be shown: tried, the rest sheet convex and every position finite.
    bool judged() const { return judged_; }
    //: Mark in `inside` (n: 1 for the particles of the finest tier's windows not shown, 0 for the others) and
    //: return how many windows were not shown, of `windows` (judged() first).
    Index unproven(std::vector<char>& inside, Index& windows);
    //: The coarsest local tier s such that every window of tiers 1 to s is shown to hold no pair of its tier
    //: (0 if not every one of tier 1's is): no pair of those tiers lies within reach (judged() first).
    int shown_through();

private:
    const double* cells_of(int s);
    const Contact& contact_;
    Index n_;
    double reach_;
    bool judged_ = false;
    bool figured_[LOCAL_TIERS] = {};
};

}  // namespace wc::self_contact
