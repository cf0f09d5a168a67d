// The nearest pair of a coarse tier (see tiers.hpp): elements far apart in the rest sheet that lie near each
// other in space where the cloth folds.  Its distance sets how far the tier's windows may move before the
// candidate list must be rebuilt (broad_phase.cpp); the pairs themselves are never needed, since the list
// holds none of the tier's pairs closer than the nearest one beyond the margin's reach.
//
// Found through the cells of the finer tier, not the elements: two cells WINDOW or more apart along an axis
// hold only pairs of coarser tiers, and the pairs of the nearest cells come first, so that the search stops
// as soon as no cell left can hold a nearer pair.  In a sheet without folds the cells are farther apart than
// the reach, and the search costs one pass over the cells' boxes.
#pragma once

#include <vector>

#include "wetcloth/core.hpp"
#include "wetcloth/self_contact/elements.hpp"

namespace wc::self_contact {

//: The least distance (m) at x (3, n) of the pairs of tier finer + 1 (their particles fit one window of it
//: but not one of tier `finer`) that are not closer than `thickness` (m) in the rest sheet, if less than
//: `reach` (m); infinity if none is.  `triangles` and `edges` are the elements' boxes at x.
double nearest_far_pair(const Contact& contact, Index n, const double* x, int finer, double reach, double thickness,
                        const Boxes& triangles, const Boxes& edges);

//: The candidate pairs at x (3, n) within `reach` (m) whose particles do not fit one window of tier `finer`,
//: added to the records (first, second, bits of the distance) of `point_triangle` and `edge_edge`, which then
//: hold each of theirs and these once, ascending in (first, second); returns the least distance of these (m;
//: infinity if none).  `triangles` and `edges` are the elements' boxes at x.
double far_pairs_within(const Contact& contact, Index n, const double* x, int finer, double reach, double thickness,
                        const Boxes& triangles, const Boxes& edges, std::vector<Index>& point_triangle,
                        std::vector<Index>& edge_edge);

//: Sort records (first, second, bits) ascending in (first, second) and drop repeats.
void sort_records(std::vector<Index>& records);

}  // namespace wc::self_contact
