// The rest sheet's tiers of windows, and how far the cloth has moved from a reference in each beyond a
// rigid motion: what keeps a candidate list valid (docs/model.md section 6.2).
//
// Distances do not change under a rigid motion.  If every particle of a window lies within d of where
// one rigid motion takes its reference position, every distance between elements of the window differs
// from its reference value by at most 2 d.  A swinging or falling sheet is nearly rigid over a few grid
// spacings while its parts turn far apart, so small windows allow little (their pairs are the fabric's
// neighbours, a grid spacing apart) and larger ones much more (their pairs are far apart in the sheet).
//
// Tier s cuts the flat rest sheet into square cells of TIER_CELLS[s] grid spacings; its windows are the
// blocks of WINDOW x WINDOW cells (stride one cell, all inside the sheet).  A pair whose particles' cells
// span at most WINDOW along both axes lies in one window of the tier; the pairs of tier s are those of
// the finest such tier, and the last tier's one window is the whole sheet.  A pair fits the windows of
// every tier coarser than its own, since each tier's cells are at least twice the last's.
//
// ContactLists::tiers holds, per tier: [cells along x, along y, each particle's cell (n), the cells'
// starts (cells + 1), the particles by cell (n), ascending within each]; tier_of() reads it.
#pragma once

#include <vector>

#include "wetcloth/core.hpp"

namespace wc::self_contact {

//: Cells per window side (a pair spanning more cells along an axis belongs to a coarser tier).
inline constexpr Index WINDOW = 2;
//: The local tiers' cell sides, in grid spacings; then the whole sheet (bench/self_collision.py: on the
//: hanging sheet {3, 6} rebuilt its list 30 times in 0.5 s, {3, 6, 12} 26, {2, 4} 41).
inline constexpr Index TIER_CELLS[] = {3, 6, 12};
inline constexpr int LOCAL_TIERS = sizeof(TIER_CELLS) / sizeof(TIER_CELLS[0]);
inline constexpr int TIERS = LOCAL_TIERS + 1;
//: The fine tier, stored after the others: cells of FINE_CELLS median edge lengths of the rest sheet (the
//: others' spacing is the longest edge's extent).  On a mesh whose particles have allowances of their own, the
//: finest tier's pairs that fit one of its windows are judged in those smaller windows, which bend less
//: (bench/mesh_cost.py, hanging: the disc's lists 118 -> 78 in 0.5 s, the jittered square's 58 -> 28; with 3
//: cells 93 and 41).
inline constexpr int FINE_TIER = TIERS;
inline constexpr Index FINE_CELLS = 2;

//: One tier's cells: cx + nx cy for the cell (cx, cy).
struct Tier {
    Index nx = 1, ny = 1;          // cells along the rest sheet's x and y
    const Index* cell = nullptr;   // (n) each particle's cell
    const Index* start = nullptr;  // (nx ny + 1): cell c holds members[start[c]:start[c + 1]]
    const Index* members = nullptr;
    Index cx(Index i) const { return cell[i] % nx; }
    Index cy(Index i) const { return cell[i] / nx; }
};

//: Cut the rest sheet (contact.rest) into the tiers' cells, into contact.lists->tiers; nothing to do where they
//: were cut from the same rest positions, triangles and edges.
void prepare_tiers(Contact& contact, Index n);

//: Tier s of `tiers` (as ContactLists::tiers holds them) for n particles.
Tier tier_in(const std::vector<Index>& tiers, Index n, int s);

//: Tier s of contact.lists->tiers (prepare_tiers first).
inline Tier tier_of(const Contact& contact, Index n, int s) { return tier_in(contact.lists->tiers, n, s); }

//: Whether the particles idx[0..3] fit one window of tier t: their cells span at most WINDOW along x and y.
inline bool fits(const Tier& t, const Index idx[4]) {
    Index lo_x = t.cx(idx[0]), hi_x = lo_x, lo_y = t.cy(idx[0]), hi_y = lo_y;
    for (int k = 1; k < 4; ++k) {
        const Index x = t.cx(idx[k]), y = t.cy(idx[k]);
        lo_x = x < lo_x ? x : lo_x, hi_x = x > hi_x ? x : hi_x;
        lo_y = y < lo_y ? y : lo_y, hi_y = y > hi_y ? y : hi_y;
    }
    return hi_x - lo_x < WINDOW && hi_y - lo_y < WINDOW;
}

//: The least distance (m) in the flat rest sheet between two elements (particles, edges, triangles) that do
//: not fit one window of tier s: their particles' cells lie WINDOW apart along an axis, so at least
//: (WINDOW - 1) cells and one spacing apart, less a spacing for each element's extent.  Infinite where the
//: tier's cells are too few for such a pair.
double rest_distance_beyond(const Contact& contact, Index n, int s);

//: The largest deviation (m) over tier s's windows of the straight-line motion from x0 to x1 (both (3, n))
//: from a rigid motion of the reference positions `ref` (3, n): for each window and each end, the rotation
//: between the frames (Gram-Schmidt) of the reference's and the end's gradients along the rest sheet's
//: axes (least squares over the window; any rotation gives a valid bound, this one is close to the best
//: fit and needs no iteration; the whole sheet's where the window's frames are degenerate, its particles on
//: a line in the rest sheet) and the translation of the window's centroid; along the motion, the larger
//: of the ends' deviations plus how far the straight lines between the two rotations fall short of a
//: rotation.  NaN if a position is not finite.
double deviation(const Contact& contact, Index n, int s, const double* ref, const double* x0, const double* x1);

//: One step's check of the motion from x0 to x1 (both (3, n)) against rigid motions of contact.reference, tier
//: by tier, with the same figures as deviation() (bit for bit).  Each tier's windows are fitted at either end;
//: the fits at x0 are those a check kept where the last step it checked ended at x0 (compared bit for bit;
//: the reference and the tiers the same), so a step's check usually fits only its end.  When it ends, it
//: keeps its fits at x1 (ContactLists::fits).
class StepFits {
public:
    StepFits(const Contact& contact, Index n, const double* x0, const double* x1);
    ~StepFits();
    StepFits(const StepFits&) = delete;
    StepFits& operator=(const StepFits&) = delete;
    //: deviation(contact, n, s, contact.reference, x0, x1).
    double deviation(int s);
    //: Whether the motion leaves each particle i of every window of tier s within allowance[i] (m) of the
    //: window's rigid motion, as deviation() finds it (the shortfall of the straight lines between the
    //: rotations counted at the particle's own distance from the window's centroid, not the window's
    //: farthest).  False if a position is not finite.
    bool within_allowances(int s, const double* allowance);

private:
    const double* shapes(int s, const Tier& t);
    void fit(int s, const Tier& t, bool visits);
    const Contact& contact_;
    Index n_;
    const double *x0_, *x1_;
    WindowFits& kept_;
};

//: The deviation (m) of the straight-line motion from x0 to x1 (both (3, n)) from a translation of the whole
//: sheet's reference positions `ref` (3, n), the mid-range of each end's displacements (what a cloth that
//: does not turn needs; a bound for the pairs of every tier).  NaN if a position is not finite.
double shifted_deviation(Index n, const double* ref, const double* x0, const double* x1);

}  // namespace wc::self_contact
