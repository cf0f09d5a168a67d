// Candidate pairs from a spatial hash, kept while the cloth's motion allows (port of
// bf41571:fmu_src/wetcloth/kernels/self_contact/broad_phase.py).
#include "wetcloth/self_contact/broad_phase.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/elements.hpp"
#include "wetcloth/self_contact/far_pairs.hpp"
#include "wetcloth/self_contact/flat_windows.hpp"
#include "wetcloth/self_contact/geometry.hpp"
#include "wetcloth/self_contact/tiers.hpp"

namespace wc::self_contact {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr std::uint64_t HASH_X = 73856093, HASH_Y = 19349663, HASH_Z = 83492791;  // Teschner et al. 2003

//: The margin (m) of a list built for a step of `motion` (m): twice that, at least least_margin.
inline double margin_for(const Contact& contact, double motion) { return py_max(contact.least_margin, 2.0 * motion); }

//: The widest margin (m) of a list built where the last one was empty: its reach (thickness + 2 margins) is
//: WIDE_REACH of the rest sheet's nearest non-adjacent elements' distance, at least least_margin.
inline double widest_margin(const Contact& contact, double thickness) {
    return py_max(contact.least_margin, 0.5 * (WIDE_REACH * contact.rest_gap - thickness));
}

//: The widest allowance (m) of a particle of the finest tier: its pairs' reach (thickness + 2 allowances) is
//: WIDE_REACH of the rest sheet's typical gap (Contact::typical_gap).  Particles of a mesh away from its
//: smallest triangles then may move as far as a grid's of the same spacing; on a grid, or a mesh whose
//: triangles are alike, no farther than widest_margin (then the particles have no allowances of their own).
inline double particle_widest(const Contact& contact, double thickness) {
    return 0.5 * (WIDE_REACH * contact.typical_gap - thickness);
}

struct Grid {
    double origin[3];
    double cell;
};

inline Index cell_of(double v, double origin, double cell) { return static_cast<Index>(std::floor((v - origin) / cell)); }

//: The hash cells that box [lo - pad, hi + pad] of element e overlaps: first and last along x, y, z.
struct Cells {
    Index first[3], last[3];
};

inline Cells box_cells(const Boxes& b, Index e, double pad, const Grid& g) {
    Cells k;
    for (int c = 0; c < 3; ++c) k.first[c] = cell_of(b.low(c, e) - pad, g.origin[c], g.cell);
    for (int c = 0; c < 3; ++c) k.last[c] = cell_of(b.high(c, e) + pad, g.origin[c], g.cell);
    return k;
}

inline Index cell_count(const Cells& k) {
    return (k.last[0] - k.first[0] + 1) * (k.last[1] - k.first[1] + 1) * (k.last[2] - k.first[2] + 1);
}

//: Write the hash buckets of a box's cells to out; returns how many.  (Products wrap modulo 2^64, as
//: numba's int64 arithmetic does.)
inline Index buckets(const Cells& k, Index mask, Index* out) {
    Index count = 0;
    const std::uint64_t m = static_cast<std::uint64_t>(mask);
    for (Index ix = k.first[0]; ix <= k.last[0]; ++ix) {
        const std::uint64_t hx = static_cast<std::uint64_t>(ix) * HASH_X;
        for (Index iy = k.first[1]; iy <= k.last[1]; ++iy) {
            const std::uint64_t hxy = hx ^ (static_cast<std::uint64_t>(iy) * HASH_Y);
            for (Index iz = k.first[2]; iz <= k.last[2]; ++iz) {
                out[count] = static_cast<Index>((hxy ^ (static_cast<std::uint64_t>(iz) * HASH_Z)) & m);
                count += 1;
            }
        }
    }
    return count;
}

//: Hash mask: a power of two at least the entries (and at least 2), minus one.
inline Index table_mask(Index entries) {
    Index size = 2;
    while (size < entries) size *= 2;
    return size - 1;
}

//: Whether a pair at distance `gap` (m) is a candidate at `reach` (m): the one test of the search and of
//: narrowing a list (within).
inline bool kept(const Boxes& p, Index a, const Boxes& q, Index b, double gap, double reach) {
    return boxes_overlap(p, a, q, b, reach) && gap < reach;
}

//: Whether element e of the first (`second` false: a particle or an edge) or second (a triangle or an edge) kind
//: has all its particles inside (`inside` null: every element has).
template <int KIND>
inline bool within_marked(const Contact& contact, const char* inside, Index e, bool second) {
    if (inside == nullptr) return true;
    if (KIND == POINT_TRIANGLE && !second) return inside[e] != 0;
    const int width = KIND == POINT_TRIANGLE ? 3 : 2;
    const Index* p = KIND == POINT_TRIANGLE ? contact.triangles + 3 * e : contact.edges + 2 * e;
    for (int k = 0; k < width; ++k)
        if (!inside[p[k]]) return false;
    return true;
}

//: The candidate pairs of one kind: (a, e) for element a of `first` (particles for POINT_TRIANGLE, edges
//: for EDGE_EDGE) and e of `second` (triangles, or the same edges: then each pair once, a < e), found
//: through a spatial hash of the second elements' boxes grown by `reach`, appended to `records` as
//: (a, e, bits of the distance) in ascending order of (a, e), whatever the hash.  Returns the smallest
//: distance found (m; infinity if none).  With `inside` (n) not null, only the pairs of elements whose
//: particles are all inside and that fit one window of the finest tier.  (numba's _hash, _pairs and
//: _search; the records grow instead of the search starting again with twice the room, which finds the
//: same pairs.)
template <int KIND>
double search(const Contact& contact, Index n, const double* x, const Boxes& first, const Boxes& second,
              double reach, double thickness, const Grid& g, std::vector<Index>& scratch,
              std::vector<Index>& records, const char* inside = nullptr) {
    const Tier finest = tier_of(contact, n, 0);
    // The hash of the second boxes: bucket b holds items[start[b]:start[b + 1]], ascending.
    Index entries = 0;
    for (Index e = 0; e < second.count; ++e)
        if (within_marked<KIND>(contact, inside, e, true)) entries += cell_count(box_cells(second, e, reach, g));
    const Index mask = table_mask(entries);
    scratch.resize(static_cast<std::size_t>(MOST_CELLS + second.count + 2 * (mask + 2) + 2 * entries));
    Index* out = scratch.data();
    Index* seen = out + MOST_CELLS;
    Index* start = seen + second.count;
    Index* cursor = start + (mask + 2);
    Index* items = cursor + (mask + 2);
    Index* ids = items + entries;  // each second element's buckets, one element after the other
    for (Index b = 0; b < mask + 2; ++b) cursor[b] = 0;
    Index* next = ids;
    for (Index e = 0; e < second.count; ++e) {
        if (!within_marked<KIND>(contact, inside, e, true)) continue;
        const Index count = buckets(box_cells(second, e, reach, g), mask, next);
        for (Index k = 0; k < count; ++k) cursor[next[k] + 1] += 1;
        next += count;
    }
    for (Index b = 0; b < mask + 1; ++b) cursor[b + 1] += cursor[b];
    for (Index b = 0; b < mask + 2; ++b) start[b] = cursor[b];
    next = ids;
    for (Index e = 0; e < second.count; ++e) {
        if (!within_marked<KIND>(contact, inside, e, true)) continue;
        const Index count = cell_count(box_cells(second, e, reach, g));
        for (Index k = 0; k < count; ++k) items[cursor[next[k]]++] = e;
        next += count;
    }
    // The search.
    const double* rest = contact.rest;
    for (Index e = 0; e < second.count; ++e) seen[e] = -1;
    double nearest = INF;
    for (Index a = 0; a < first.count; ++a) {
        if (!within_marked<KIND>(contact, inside, a, false)) continue;
        const std::size_t found = records.size();
        const Index count = buckets(box_cells(first, a, 0.0, g), mask, out);
        for (Index q = 0; q < count; ++q) {
            const Index b = out[q];
            for (Index k = start[b + 1] - 1; k > start[b] - 1; --k) {  // a bucket's items ascend
                const Index e = items[k];
                if (KIND == EDGE_EDGE && e <= a) break;  // each edge-edge pair once, from its lower edge
                if (seen[e] == a) continue;
                seen[e] = a;
                if (share_a_particle<KIND>(contact, a, e) || !boxes_overlap(first, a, second, e, reach)) continue;
                Index idx[4];
                particles<KIND>(contact, a, e, idx);
                if (inside != nullptr && !fits(finest, idx)) continue;  // (far_pairs_within finds those)
                const double gap = candidate_distance<KIND>(x, rest, n, idx, reach, thickness);
                if (!kept(first, a, second, e, gap, reach)) continue;
                records.push_back(a);
                records.push_back(e);
                records.push_back(gap_bits(gap));
                nearest = py_min(nearest, gap);
            }
        }
        // Sort this element's few partners by the partner, in place, by insertion.
        Index* r = records.data();
        const std::size_t end = records.size();
        for (std::size_t i = found + 3; i < end; i += 3) {
            const Index partner = r[i + 1], bits = r[i + 2];
            std::size_t j = i;
            while (j > found && r[j - 3 + 1] > partner) {
                r[j + 1] = r[j - 3 + 1];
                r[j + 2] = r[j - 3 + 2];
                j -= 3;
            }
            r[j + 1] = partner;
            r[j + 2] = bits;
        }
    }
    return nearest;
}

//: Keep the records that are candidates at the smaller `reach` (m), in the same order (numba's _within).
void within(std::vector<Index>& records, const Boxes& first, const Boxes& second, double reach) {
    Index* r = records.data();
    std::size_t kept_size = 0;
    for (std::size_t k = 0; k < records.size(); k += 3) {
        if (kept(first, r[k], second, r[k + 1], gap_of(r[k + 2]), reach)) {
            r[kept_size] = r[k], r[kept_size + 1] = r[k + 1], r[kept_size + 2] = r[k + 2];
            kept_size += 3;
        }
    }
    records.resize(kept_size);
}

//: Turn records (first, second, bits) into the list's layout (2, count): first row, then second row.
void to_rows(std::vector<Index>& records, std::vector<Index>& scratch) {
    const std::size_t count = records.size() / 3;
    if (scratch.size() < count) scratch.resize(count);
    Index* r = records.data();
    for (std::size_t j = 0; j < count; ++j) scratch[j] = r[3 * j + 1];
    for (std::size_t j = 0; j < count; ++j) r[j] = r[3 * j];
    for (std::size_t j = 0; j < count; ++j) r[count + j] = scratch[j];
    records.resize(2 * count);
}

//: The widest allowance (m) searched for in tier s >= 1: its reach (thickness + 2 allowances) is WIDE_REACH
//: of the least distance in the rest sheet between elements of tier s or coarser (infinite if none can be).
inline double widest_allowance(const Contact& contact, Index n, double thickness, int s) {
    return 0.5 * (WIDE_REACH * rest_distance_beyond(contact, n, s - 1) - thickness);
}

//: Each tier's deviation (m) of the motion from x0 to x1 away from `ref` (all (3, n)), then the least of it
//: and every coarser tier's: what bounds the distance change of the tier's pairs.  NaN if not finite.
void bounds(const Contact& contact, Index n, const double* ref, const double* x0, const double* x1,
            double out[TIERS]) {
    for (int s = 0; s < TIERS; ++s) out[s] = deviation(contact, n, s, ref, x0, x1);
    const double shifted = shifted_deviation(n, ref, x0, x1);
    if (out[TIERS - 1] == out[TIERS - 1]) out[TIERS - 1] = py_min(out[TIERS - 1], shifted);
    for (int s = TIERS - 2; s >= 0; --s) out[s] = out[s] == out[s] ? py_min(out[s], out[s + 1]) : out[s];
}

//: The tier of the pair of particles idx: the finest whose windows it fits.
inline int tier_of_pair(const Contact& contact, Index n, const Index idx[4]) {
    for (int s = 0; s < TIERS - 1; ++s)
        if (fits(tier_of(contact, n, s), idx)) return s;
    return TIERS - 1;
}

//: The least distance among the records (of `kind`) of each tier s >= 1, into nearest[s] (if less); and, if
//: `own` (2, n) is not null, of the finest tier's records at `outside` (m) or farther (those the list leaves
//: out), into own[i] for each of their particles i (if less): the first row for the pairs that fit a window of
//: the fine tier, the second for the others.
void nearest_by_tier(const Contact& contact, Index n, const std::vector<Index>& records, int kind,
                     double nearest[TIERS], double outside, double* own) {
    const Tier fine = tier_of(contact, n, FINE_TIER);
    for (std::size_t k = 0; k < records.size(); k += 3) {
        Index idx[4];
        if (kind == POINT_TRIANGLE) {
            particles<POINT_TRIANGLE>(contact, records[k], records[k + 1], idx);
        } else {
            particles<EDGE_EDGE>(contact, records[k], records[k + 1], idx);
        }
        const int s = tier_of_pair(contact, n, idx);
        const double gap = gap_of(records[k + 2]);
        nearest[s] = py_min(nearest[s], gap);
        if (s == 0 && own != nullptr && gap >= outside) {
            double* row = fits(fine, idx) ? own : own + n;
            for (int j = 0; j < 4; ++j) row[idx[j]] = py_min(row[idx[j]], gap);
        }
    }
}

//: Whether the list holds for the motion from x0 to x1 (covers), and in `shifted` the whole sheet's
//: deviation with a translation alone.  That first (a cloth that does not turn: two passes over the
//: positions), then the tiers from the coarsest: a coarser tier's deviation within a finer one's allowance
//: covers the finer one's pairs too, and the finest tier (the most windows) is the dearest to check.
bool holds(const Contact& contact, Index n, const double* x0, const double* x1, double& shifted) {
    const std::vector<double>& allowance = contact.lists->allowances;
    if (!(contact.margin[0] > 0.0) || allowance.size() != static_cast<std::size_t>(TIERS)) return false;
    shifted = shifted_deviation(n, contact.reference, x0, x1);
    if (!(shifted == shifted)) return false;
    double bound = shifted;  // the least deviation found so far of this tier or a coarser one
    bool found[TIERS] = {};
    const std::vector<double>& own = contact.lists->particle_allowances;
    StepFits fits(contact, n, x0, x1);
    for (int s = TIERS - 1; s >= 0; --s) {
        // The finest tier's pairs, where its particles have allowances of their own: each particle within its
        // own in every window.  Failing that, the tier's own windows within the margin (below) still hold them
        // all: the fine tier's windows, which check the first row, may bend more than the finest tier's (a
        // cloth folding over a table's edge at frame-long steps, whose lists built for the step then never held).
        if (s == 0 && !own.empty() && !(bound <= allowance[0])) {
            if (fits.within_allowances(FINE_TIER, own.data()) && fits.within_allowances(0, own.data() + n))
                break;
        }
        // This tier's windows, then those of the coarser tiers passed over, until one holds the tier's pairs
        // (the same bound as rebuild_for_step's, so that a list holds for the step it was built for).
        for (int t = s; t < TIERS && !(bound <= allowance[s]); ++t) {
            if (found[t]) continue;
            found[t] = true;
            const double d = fits.deviation(t);
            if (!(d == d)) return false;
            bound = py_min(bound, d);
        }
        if (!(bound <= allowance[s])) return false;
    }
    return true;
}

//: Whether a list that holds is not worth keeping (`shifted` as from holds()).  A list whose margin is over
//: LOOSE times what the step needs, unless that margin is the least one (a cloth that never moved fast): a
//: list built for one violent step (a landing) would otherwise hold far-apart pairs for the rest of the
//: run.  An empty list costs nothing however loose, but one the cloth has turned away from is checked
//: window by window: where the cloth now barely moves (a towel afloat), a list built afresh holds through
//: the translation alone.
bool too_loose(const Contact& contact, Index n, const double* x0, const double* x1, double shifted) {
    const double margin = contact.margin[0];
    if (candidate_count(contact) == 0) {
        return !(shifted <= margin) && shifted_deviation(n, x0, x0, x1) < margin / (LOOSE * LOOSE);
    }
    if (margin <= LOOSE * contact.least_margin) return false;
    // The step's deviation from its own midpoint, where it is least: the margin is loose once four times
    // that is under margin / LOOSE.
    std::vector<double>& middle = contact.lists->scratch;
    middle.resize(static_cast<std::size_t>(3 * n));
    for (Index k = 0; k < 3 * n; ++k) middle[k] = 0.5 * (x0[k] + x1[k]);
    const double loose = margin / (2.0 * LOOSE);
    if (2.0 * shifted_deviation(n, middle.data(), x0, x1) < loose) return true;
    for (int s = TIERS - 1; s >= 0; --s) {
        if (2.0 * deviation(contact, n, s, middle.data(), x0, x1) < loose) return true;
    }
    return false;
}

}  // namespace

bool covers(const Contact& contact, Index n, const double* x0, const double* x1) {
    double shifted = INF;
    return holds(contact, n, x0, x1, shifted);
}

bool expired(const Contact& contact, Index n, const double* x0, const double* x1) {
    double shifted = INF;
    return !holds(contact, n, x0, x1, shifted) || too_loose(contact, n, x0, x1, shifted);
}

bool rebuild_for_step(Contact& contact, Index n, double thickness, const double* x0, const double* x1) {
    for (Index k = 0; k < 3 * n; ++k)
        if (!std::isfinite(x0[k]) || !std::isfinite(x1[k])) return false;  // the guard after this stage refuses it
    for (Index k = 0; k < 3 * n; ++k) contact.reference[k] = 0.5 * (x0[k] + x1[k]);
    prepare_tiers(contact, n);
    double bound[TIERS];
    bounds(contact, n, contact.reference, x0, x1, bound);
    // Twice the step's motion in the finest tier (its deviation from the midpoint, doubled: room for the
    // next steps), but no wider than keeps the fabric's neighbours out of the list, unless the step itself
    // needs it.
    const double widest = widest_margin(contact, thickness);
    const double margin = py_max(bound[0], py_min(margin_for(contact, 2.0 * bound[0]), widest));
    if (candidate_count(contact) == 0) {
        build_lists(contact, n, thickness, margin, py_max(margin, widest));
    } else {
        build_lists(contact, n, thickness, margin, margin);
    }
    // A coarser tier whose allowance cannot hold the step (a violent one): the margin that just holds it,
    // in every tier (the list has room for this step alone; the next is likely as violent).
    double need = 0.0;
    for (int s = 1; s < TIERS; ++s)
        if (!(bound[s] <= contact.lists->allowances[s])) need = py_max(need, bound[s]);
    if (need > 0.0) {
        const double held = py_max(contact.margin[0], need);
        build_lists(contact, n, thickness, held, held);
    }
    return true;
}

void build_widest(Contact& contact, Index n, double thickness, double least, double widest) {
    prepare_tiers(contact, n);
    build_lists(contact, n, thickness, least, widest);
}

void build_lists(Contact& contact, Index n, double thickness, double least, double widest) {
    ContactLists& lists = *contact.lists;
    const double* x = contact.reference;
    // Where the particles have allowances of their own (a mesh whose smallest triangles cap the margin), the
    // search reaches as far as their widest, so that it finds every pair that bounds one.
    const double own_widest = particle_widest(contact, thickness);
    const bool own = own_widest > widest_margin(contact, thickness);
    const double reach = thickness + 2.0 * (own ? py_max(widest, own_widest) : widest);
    const Index m = contact.triangle_count, k = contact.edge_count;
    lists.scratch.resize(static_cast<std::size_t>(6 * (m + k)));
    double* tri_lo = lists.scratch.data();
    double* tri_hi = tri_lo + 3 * m;
    double* edge_lo = tri_hi + 3 * m;
    double* edge_hi = edge_lo + 3 * k;
    boxes(x, n, contact.triangles, m, 3, tri_lo, tri_hi);
    boxes(x, n, contact.edges, k, 2, edge_lo, edge_hi);
    // Cells as large as a typical triangle's box grown by the reach: a box then spans a few cells.  (Cells
    // of at least an eighth of the largest box: no box spans more than 9 cells along an axis.)  The cells
    // start at the lowest grown box, so that a flat sheet's boxes lie in one layer of cells.
    double total = 0.0;
    double largest = 0.0;
    Grid g{{INF, INF, INF}, 0.0};
    for (Index t = 0; t < m; ++t) {
        const double extent = py_max(py_max(tri_hi[t] - tri_lo[t], tri_hi[m + t] - tri_lo[m + t]),
                                     tri_hi[2 * m + t] - tri_lo[2 * m + t]);
        total += extent;
        largest = py_max(largest, extent);
        for (int c = 0; c < 3; ++c) g.origin[c] = py_min(g.origin[c], tri_lo[c * m + t] - reach);
    }
    g.cell = py_max(total / static_cast<double>(m > 1 ? m : 1), 0.125 * largest) + 2.0 * reach;
    const Boxes particle_boxes{x, x, n}, triangle_boxes{tri_lo, tri_hi, m}, edge_boxes{edge_lo, edge_hi, k};
    lists.point_triangle.clear();
    lists.edge_edge.clear();
    // The windows of the finest tier shown to hold no pair within the reach need no search (flat_windows.hpp):
    // the others' pairs are searched, and those of the coarser tiers whose windows are not all shown through
    // their cells; unless most windows are not shown (a crumpled cloth), where the whole search costs less.
    // Not on a mesh whose particles have allowances of their own: its reach is set by its median triangle, and
    // its thinnest triangles leave no window shown (the tablecloth's 81 of 81; 7 % more time a build).
    FlatWindows flat(contact, n, x, reach, !own);
    Index windows = 0;
    const Index unproven = flat.judged() ? flat.unproven(lists.flat_inside, windows) : -1;
    const bool whole = unproven < 0 || MOST_UNPROVEN * static_cast<double>(windows) < static_cast<double>(unproven);
    const char* inside = whole ? nullptr : lists.flat_inside.data();  // (null: every element searched)
    double nearest_pair = INF;
    if (whole || unproven > 0) {
        nearest_pair = py_min(search<POINT_TRIANGLE>(contact, n, x, particle_boxes, triangle_boxes, reach, thickness, g,
                                                     lists.index_scratch, lists.point_triangle, inside),
                              search<EDGE_EDGE>(contact, n, x, edge_boxes, edge_boxes, reach, thickness, g,
                                                lists.index_scratch, lists.edge_edge, inside));
    }
    if (!whole) {  // the pairs of the coarser tiers, beyond those whose windows are all shown
        nearest_pair = py_min(nearest_pair, far_pairs_within(contact, n, x, flat.shown_through(), reach, thickness,
                                                             triangle_boxes, edge_boxes, lists.point_triangle,
                                                             lists.edge_edge));
    }
    // The widest margin whose lists are empty: the nearest pair just out of reach.
    const double margin = py_max(least, py_min(widest, 0.5 * (nearest_pair - thickness)));
    // The nearest pair of each coarser tier among those found (a folded cloth's layers).
    // And each particle's nearest among the finest tier's pairs the list leaves out.
    double nearest[TIERS];
    for (int s = 0; s < TIERS; ++s) nearest[s] = INF;
    std::vector<double>& allowance = lists.particle_allowances;
    allowance.assign(own ? static_cast<std::size_t>(2 * n) : 0, INF);
    double* nearest_own = own ? allowance.data() : nullptr;
    nearest_by_tier(contact, n, lists.point_triangle, POINT_TRIANGLE, nearest, thickness + 2.0 * margin, nearest_own);
    nearest_by_tier(contact, n, lists.edge_edge, EDGE_EDGE, nearest, thickness + 2.0 * margin, nearest_own);
    // A particle's own allowances (for the pairs that fit the fine tier's windows, and for the finest tier's
    // others): half what its nearest such pair left out has beyond the thickness, up to its widest, and at least
    // the margin.  A pair the list leaves out is then at least the sum of its particles' allowances (of its
    // row) beyond the thickness: those within the search's reach bound each of its particles', the
    // others are farther than the widest's reach.
    for (double& a : allowance) a = py_max(margin, py_min(own_widest, 0.5 * (a - thickness)));
    if (thickness + 2.0 * margin < reach) {
        within(lists.point_triangle, particle_boxes, triangle_boxes, thickness + 2.0 * margin);
        within(lists.edge_edge, edge_boxes, edge_boxes, thickness + 2.0 * margin);
    }
    // The coarser tiers: each as wide as keeps its pairs out of the list, up to what their distance in the
    // rest sheet leaves room for, and at least the margin (their pairs within the margin's reach are in the
    // list already).  A tier with a pair found above has its nearest one (a folded cloth's layers); the
    // others are searched as wide as their allowance can be (a sheet without folds, where the cells keep
    // the search cheap).  Either way the allowance is the one build() for the margin kept finds.  A tier
    // without pairs (one window of the finer tier holds the whole sheet) has nothing to keep out: infinite.
    lists.allowances.assign(TIERS, margin);
    for (int s = 1; s < TIERS; ++s) {
        const double wide = widest_allowance(contact, n, thickness, s);
        if (wide == INF) {
            lists.allowances[s] = INF;
            continue;
        }
        if (!(wide > margin)) continue;  // no room beyond the margin
        if (!(nearest[s] < reach)) {
            nearest[s] = nearest_far_pair(contact, n, x, s - 1, thickness + 2.0 * wide, thickness, triangle_boxes,
                                          edge_boxes);
        }
        lists.allowances[s] = py_max(margin, py_min(wide, 0.5 * (nearest[s] - thickness)));
    }
    to_rows(lists.point_triangle, lists.index_scratch);
    to_rows(lists.edge_edge, lists.index_scratch);
    contact.margin[0] = margin;
    contact.counters[REBUILDS] += 1;
}

}  // namespace wc::self_contact

namespace wc {

void build(Contact& contact, Index n, double thickness, double margin) {
    self_contact::build_widest(contact, n, thickness, margin, margin);
}

void invalidate(Contact& contact) {
    contact.margin[0] = 0.0;
    if (contact.lists != nullptr) {
        contact.lists->point_triangle.clear();
        contact.lists->edge_edge.clear();
        contact.lists->allowances.clear();
        contact.lists->particle_allowances.clear();
    }
}

}  // namespace wc
