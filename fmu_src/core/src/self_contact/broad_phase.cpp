// Candidate pairs from a spatial hash, kept while the cloth's motion allows (port of
// bf41571:fmu_src/wetcloth/kernels/self_contact/broad_phase.py).
#include "wetcloth/self_contact/broad_phase.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/geometry.hpp"

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

//: Axis-aligned boxes (3, count) of `count` elements: lo[c * count + e], hi likewise.
struct Boxes {
    const double* lo;
    const double* hi;
    Index count;
    double low(int c, Index e) const { return lo[c * count + e]; }
    double high(int c, Index e) const { return hi[c * count + e]; }
};

//: Each element's (`width` particles, rows of `elements`) box at positions x (3, n).
void boxes(const double* x, Index n, const Index* elements, Index count, int width, double* lo, double* hi) {
    for (Index e = 0; e < count; ++e) {
        for (int c = 0; c < 3; ++c) {
            const double* row = x + c * n;
            double a = INF;
            double b = -INF;
            for (int k = 0; k < width; ++k) {
                const double v = row[elements[e * width + k]];
                a = py_min(a, v);
                b = py_max(b, v);
            }
            lo[c * count + e] = a;
            hi[c * count + e] = b;
        }
    }
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

inline bool boxes_overlap(const Boxes& p, Index a, const Boxes& q, Index b, double pad) {
    return p.low(0, a) <= q.high(0, b) + pad && q.low(0, b) - pad <= p.high(0, a) && p.low(1, a) <= q.high(1, b) + pad &&
           q.low(1, b) - pad <= p.high(1, a) && p.low(2, a) <= q.high(2, b) + pad && q.low(2, b) - pad <= p.high(2, a);
}

//: Whether a pair at distance `gap` (m) is a candidate at `reach` (m): the one test of the search and of
//: narrowing a list (within).
inline bool kept(const Boxes& p, Index a, const Boxes& q, Index b, double gap, double reach) {
    return boxes_overlap(p, a, q, b, reach) && gap < reach;
}

//: A pair's record while a list is searched: first, second element, bits of its distance (m).
inline Index gap_bits(double gap) {
    Index bits;
    std::memcpy(&bits, &gap, sizeof bits);
    return bits;
}
inline double gap_of(Index bits) {
    double gap;
    std::memcpy(&gap, &bits, sizeof gap);
    return gap;
}

//: The four particles (a | b, c, d) of point a and triangle t, or (a, b | c, d) of edges a and e.
template <int KIND>
inline void particles(const Contact& contact, Index a, Index e, Index idx[4]) {
    if (KIND == POINT_TRIANGLE) {
        idx[0] = a;
        for (int j = 0; j < 3; ++j) idx[1 + j] = contact.triangles[3 * e + j];
    } else {
        idx[0] = contact.edges[2 * a], idx[1] = contact.edges[2 * a + 1];
        idx[2] = contact.edges[2 * e], idx[3] = contact.edges[2 * e + 1];
    }
}

//: Whether element a (a particle or an edge) and element e (a triangle or an edge) share a particle.
template <int KIND>
inline bool share_a_particle(const Contact& contact, Index a, Index e) {
    if (KIND == POINT_TRIANGLE) {
        for (int j = 0; j < 3; ++j)
            if (a == contact.triangles[3 * e + j]) return true;
        return false;
    }
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            if (contact.edges[2 * a + i] == contact.edges[2 * e + j]) return true;
    return false;
}

//: The distance (m) at x of the pair's particles if it is a candidate: within `reach` (m), and not already
//: closer than `thickness` (m) in the flat rest sheet (such neighbours are the fabric itself, not two
//: layers); infinity if it is not.
template <int KIND>
inline double candidate_distance(const double* x, const double* rest, Index n, const Index idx[4], double reach,
                                 double thickness) {
    const double gap = distance(KIND, point(x, n, idx[0]), point(x, n, idx[1]), point(x, n, idx[2]),
                                point(x, n, idx[3]));
    if (gap >= reach || distance(KIND, point(rest, n, idx[0]), point(rest, n, idx[1]), point(rest, n, idx[2]),
                                 point(rest, n, idx[3])) < thickness)
        return INF;
    return gap;
}

//: The candidate pairs of one kind: (a, e) for element a of `first` (particles for POINT_TRIANGLE, edges
//: for EDGE_EDGE) and e of `second` (triangles, or the same edges: then each pair once, a < e), found
//: through a spatial hash of the second elements' boxes grown by `reach`, appended to `records` as
//: (a, e, bits of the distance) in ascending order of (a, e), whatever the hash.  Returns the smallest
//: distance found (m; infinity if none).  (numba's _hash, _pairs and _search; the records grow instead
//: of the search starting again with twice the room, which finds the same pairs.)
template <int KIND>
double search(const Contact& contact, Index n, const double* x, const Boxes& first, const Boxes& second,
              double reach, double thickness, const Grid& g, std::vector<Index>& scratch,
              std::vector<Index>& records) {
    // The hash of the second boxes: bucket b holds items[start[b]:start[b + 1]], ascending.
    Index entries = 0;
    for (Index e = 0; e < second.count; ++e) entries += cell_count(box_cells(second, e, reach, g));
    const Index mask = table_mask(entries);
    scratch.resize(static_cast<std::size_t>(MOST_CELLS + second.count + 2 * (mask + 2) + entries));
    Index* out = scratch.data();
    Index* seen = out + MOST_CELLS;
    Index* start = seen + second.count;
    Index* cursor = start + (mask + 2);
    Index* items = cursor + (mask + 2);
    for (Index b = 0; b < mask + 2; ++b) cursor[b] = 0;
    for (Index e = 0; e < second.count; ++e) {
        const Index count = buckets(box_cells(second, e, reach, g), mask, out);
        for (Index k = 0; k < count; ++k) cursor[out[k] + 1] += 1;
    }
    for (Index b = 0; b < mask + 1; ++b) cursor[b + 1] += cursor[b];
    for (Index b = 0; b < mask + 2; ++b) start[b] = cursor[b];
    for (Index e = 0; e < second.count; ++e) {
        const Index count = buckets(box_cells(second, e, reach, g), mask, out);
        for (Index k = 0; k < count; ++k) {
            items[cursor[out[k]]] = e;
            cursor[out[k]] += 1;
        }
    }
    // The search.
    const double* rest = contact.rest;
    for (Index e = 0; e < second.count; ++e) seen[e] = -1;
    double nearest = INF;
    for (Index a = 0; a < first.count; ++a) {
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

}  // namespace

double largest_motion_squared(Index n, const double* x0, const double* x1) {
    double shift[3];
    for (int c = 0; c < 3; ++c) {
        const double* a = x0 + c * n;
        const double* b = x1 + c * n;
        double lo = INF, hi = -INF;
        for (Index i = 0; i < n; ++i) {
            const double d = b[i] - a[i];
            if (!std::isfinite(d)) return std::numeric_limits<double>::quiet_NaN();
            lo = py_min(lo, d);
            hi = py_max(hi, d);
        }
        shift[c] = 0.5 * (lo + hi);
    }
    double largest = 0.0;
    for (Index i = 0; i < n; ++i) {
        const double dx = x1[i] - x0[i] - shift[0];
        const double dy = x1[n + i] - x0[n + i] - shift[1];
        const double dz = x1[2 * n + i] - x0[2 * n + i] - shift[2];
        largest = py_max(largest, dx * dx + dy * dy + dz * dz);
    }
    return largest;
}

bool covers(const Contact& contact, Index n, const double* x) {
    const double margin = contact.margin[0];
    return margin > 0.0 && largest_motion_squared(n, contact.reference, x) <= margin * margin;
}

//: Costs nothing while the margin is the least one (a cloth that never moved fast) or the list is empty (an
//: empty list costs nothing however loose): a list built for one violent step (a landing) would otherwise
//: hold far-apart pairs for the rest of the run.
bool too_loose(const Contact& contact, Index n, const double* x0, const double* x1) {
    const double margin = contact.margin[0];
    if (margin <= LOOSE * contact.least_margin || candidate_count(contact) == 0) return false;
    const double motion = std::sqrt(largest_motion_squared(n, x0, x1));
    return std::isfinite(motion) && margin > LOOSE * margin_for(contact, motion);
}

bool rebuild_for_step(Contact& contact, Index n, double thickness, const double* x0, const double* x1) {
    const double motion = std::sqrt(largest_motion_squared(n, x0, x1));
    if (!std::isfinite(motion)) return false;  // a blown-up step: the guard after this stage refuses it
    for (Index k = 0; k < 3 * n; ++k) contact.reference[k] = 0.5 * (x0[k] + x1[k]);
    const double margin = margin_for(contact, motion);
    if (candidate_count(contact) == 0) {
        build_widest(contact, n, thickness, margin, py_max(margin, widest_margin(contact, thickness)));
    } else {
        build(contact, n, thickness, margin);
    }
    return true;
}

void build_widest(Contact& contact, Index n, double thickness, double least, double widest) {
    ContactLists& lists = *contact.lists;
    const double* x = contact.reference;
    double reach = thickness + 2.0 * widest;
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
    const double point_nearest = search<POINT_TRIANGLE>(contact, n, x, particle_boxes, triangle_boxes, reach,
                                                        thickness, g, lists.index_scratch, lists.point_triangle);
    const double edge_nearest = search<EDGE_EDGE>(contact, n, x, edge_boxes, edge_boxes, reach, thickness, g,
                                                  lists.index_scratch, lists.edge_edge);
    // The widest margin whose lists are empty: the nearest pair just out of reach.
    const double margin = py_max(least, py_min(widest, 0.5 * (py_min(point_nearest, edge_nearest) - thickness)));
    if (margin < widest) {
        reach = thickness + 2.0 * margin;
        within(lists.point_triangle, particle_boxes, triangle_boxes, reach);
        within(lists.edge_edge, edge_boxes, edge_boxes, reach);
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
    }
}

}  // namespace wc
