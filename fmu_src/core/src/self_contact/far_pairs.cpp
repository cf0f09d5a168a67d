// The nearest pair of a coarse tier, through the cells of the finer one (see
// wetcloth/self_contact/far_pairs.hpp).
#include "wetcloth/self_contact/far_pairs.hpp"

#include <algorithm>
#include <limits>

#include "wetcloth/self_contact/tiers.hpp"

namespace wc::self_contact {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

//: The elements (`width` particles each) touching each cell of tier t: cell c's are items[start[c]:start[c+1]],
//: ascending; `start` has cells + 1 entries, `items` up to width per element.
void touching(const Tier& t, const Index* elements, Index count, int width, Index* start, Index* items) {
    const Index cells = t.nx * t.ny;
    for (Index c = 0; c <= cells; ++c) start[c] = 0;
    auto each_cell = [&](Index e, auto&& visit) {
        Index seen[3];
        int distinct = 0;
        for (int k = 0; k < width; ++k) {
            const Index c = t.cell[elements[e * width + k]];
            bool again = false;
            for (int j = 0; j < distinct; ++j) again = again || seen[j] == c;
            if (!again) {
                seen[distinct++] = c;
                visit(c);
            }
        }
    };
    for (Index e = 0; e < count; ++e) each_cell(e, [&](Index c) { start[c + 1] += 1; });
    for (Index c = 0; c < cells; ++c) start[c + 1] += start[c];
    // start[c] serves as cell c's cursor, then goes back to where the range begins.
    for (Index e = 0; e < count; ++e) each_cell(e, [&](Index c) { items[start[c]++] = e; });
    for (Index c = cells; c > 0; --c) start[c] = start[c - 1];
    start[0] = 0;
}

//: The elements of each cell of a tier, as far as the search needs them: the triangles and the edges touching
//: it (as touching() lists them), and the particles of the cell and of those elements (each once): whose
//: positions bound every element touching the cell.
struct CellElements {
    const Index *triangle_start, *triangle_items, *edge_start, *edge_items, *particle_start, *particle_items;
};

//: Tier t's (tier `s`) CellElements, listed once for the tiers as cut (the rest sheet's, not the positions').
CellElements cell_elements(const Contact& contact, Index n, int s, const Tier& t) {
    ContactLists& lists = *contact.lists;
    if (lists.far_cells_made != lists.tiers_made) {
        lists.far_cells.assign(TIERS, {});
        lists.far_cells_made = lists.tiers_made;
    }
    std::vector<Index>& out = lists.far_cells[s];
    const Index cells = t.nx * t.ny, m = contact.triangle_count, k = contact.edge_count;
    if (out.empty()) {
        out.resize(static_cast<std::size_t>(3 * (cells + 1) + 3 * m + 2 * k));
        Index* triangle_start = out.data();
        Index* triangle_items = triangle_start + cells + 1;
        Index* edge_start = triangle_items + 3 * m;
        Index* edge_items = edge_start + cells + 1;
        Index* particle_start = edge_items + 2 * k;
        touching(t, contact.triangles, m, 3, triangle_start, triangle_items);
        touching(t, contact.edges, k, 2, edge_start, edge_items);
        std::vector<Index> stamp(static_cast<std::size_t>(n), -1);
        std::vector<Index> particles;
        for (Index c = 0; c < cells; ++c) {
            particle_start[c] = static_cast<Index>(particles.size());
            auto take = [&](Index i) {
                if (stamp[i] != c) stamp[i] = c, particles.push_back(i);
            };
            for (Index q = t.start[c]; q < t.start[c + 1]; ++q) take(t.members[q]);
            for (Index q = triangle_start[c]; q < triangle_start[c + 1]; ++q)
                for (int j = 0; j < 3; ++j) take(contact.triangles[3 * triangle_items[q] + j]);
            for (Index q = edge_start[c]; q < edge_start[c + 1]; ++q)
                for (int j = 0; j < 2; ++j) take(contact.edges[2 * edge_items[q] + j]);
        }
        particle_start[cells] = static_cast<Index>(particles.size());
        out.insert(out.end(), particles.begin(), particles.end());
    }
    const Index* triangle_start = out.data();
    const Index* edge_start = triangle_start + cells + 1 + 3 * m;
    const Index* particle_start = edge_start + cells + 1 + 2 * k;
    return {triangle_start, triangle_start + cells + 1, edge_start, edge_start + cells + 1, particle_start,
            particle_start + cells + 1};
}

//: Whether cells a and b of tier t lie WINDOW or more apart along an axis.
inline bool apart(const Tier& t, Index a, Index b) {
    const Index dx = a % t.nx - b % t.nx, dy = a / t.nx - b / t.nx;
    return dx >= WINDOW || -dx >= WINDOW || dy >= WINDOW || -dy >= WINDOW;
}

//: The least distance (m) along any axis between box a and box b of `boxes` (0 if they overlap): no point of
//: one is nearer to a point of the other.
inline double box_gap(const Boxes& b, Index u, Index v) {
    double gap = 0.0;
    for (int d = 0; d < 3; ++d) gap = py_max(gap, py_max(b.low(d, v) - b.high(d, u), b.low(d, u) - b.high(d, v)));
    return gap;
}

//: The search over the pairs that do not fit a window of tier `finer`: for the nearest one of tier `coarser`
//: (`records` null: `bound`, the distance looked within, shrinks to the nearest so far), or for all within
//: `bound` (appended to records[KIND]).
struct Search {
    const Contact& contact;
    Index n;
    const double* x;
    Tier finer, coarser;
    double thickness;
    double bound;
    std::vector<Index>* const* records;
    double nearest = INF;

    template <int KIND>
    void pair(Index a, Index e, const Boxes& first, const Boxes& second) {
        if (share_a_particle<KIND>(contact, a, e) || !boxes_overlap(first, a, second, e, bound)) return;
        Index idx[4];
        particles<KIND>(contact, a, e, idx);
        if (fits(finer, idx) || (records == nullptr && !fits(coarser, idx))) return;  // a pair of another tier
        const double gap = candidate_distance<KIND>(x, contact.rest, n, idx, bound, thickness);
        if (!(gap < bound)) return;
        nearest = py_min(nearest, gap);
        if (records == nullptr) {
            bound = nearest;
            return;
        }
        std::vector<Index>& out = *records[KIND];
        out.push_back(a);
        out.push_back(e);
        out.push_back(gap_bits(gap));
    }
};

//: Search s through the cells of tier `finer` that lie apart (their pairs fit no window of it) and within its
//: bound of each other, the nearest first.
void search_far_cells(Search& s, int finer, const Boxes& triangles, const Boxes& edges);

}  // namespace

double nearest_far_pair(const Contact& contact, Index n, const double* x, int finer, double reach, double thickness,
                        const Boxes& triangles, const Boxes& edges) {
    const Tier t = tier_of(contact, n, finer);
    if (t.nx <= WINDOW && t.ny <= WINDOW) return INF;  // every pair fits one window of the finer tier
    Search s{contact, n, x, t, tier_of(contact, n, finer + 1), thickness, reach, nullptr};
    search_far_cells(s, finer, triangles, edges);
    return s.nearest < reach ? s.nearest : INF;
}

double far_pairs_within(const Contact& contact, Index n, const double* x, int finer, double reach, double thickness,
                        const Boxes& triangles, const Boxes& edges, std::vector<Index>& point_triangle,
                        std::vector<Index>& edge_edge) {
    const Tier t = tier_of(contact, n, finer);
    if (t.nx <= WINDOW && t.ny <= WINDOW) return INF;
    std::vector<Index>* records[2] = {&point_triangle, &edge_edge};
    static_assert(POINT_TRIANGLE == 0 && EDGE_EDGE == 1, "records by kind");
    Search s{contact, n, x, t, t, thickness, reach, records};
    search_far_cells(s, finer, triangles, edges);
    sort_records(point_triangle);
    sort_records(edge_edge);  // (a pair of elements touching several cells is found through each)
    return s.nearest;
}

void sort_records(std::vector<Index>& records) {
    struct Record {
        Index first, second, bits;
    };
    std::vector<Record> sorted(records.size() / 3);
    for (std::size_t k = 0; k < sorted.size(); ++k) sorted[k] = {records[3 * k], records[3 * k + 1], records[3 * k + 2]};
    std::sort(sorted.begin(), sorted.end(), [](const Record& a, const Record& b) {
        return a.first < b.first || (a.first == b.first && a.second < b.second);
    });
    records.clear();
    for (std::size_t k = 0; k < sorted.size(); ++k) {
        if (k > 0 && sorted[k].first == sorted[k - 1].first && sorted[k].second == sorted[k - 1].second) continue;
        records.push_back(sorted[k].first);
        records.push_back(sorted[k].second);
        records.push_back(sorted[k].bits);
    }
}

namespace {

void search_far_cells(Search& s, int finer, const Boxes& triangles, const Boxes& edges) {
    const Contact& contact = s.contact;
    const Index n = s.n;
    const double* x = s.x;
    const double reach = s.bound;
    const Tier t = s.finer;
    const Index cells = t.nx * t.ny;
    const CellElements elements = cell_elements(contact, n, finer, t);
    const Index* triangle_start = elements.triangle_start;
    const Index* triangle_items = elements.triangle_items;
    const Index* edge_start = elements.edge_start;
    const Index* edge_items = elements.edge_items;
    // Integer scratch: the cells in sweep order.
    std::vector<Index>& ints = contact.lists->index_scratch;
    ints.resize(static_cast<std::size_t>(cells));
    Index* order = ints.data();
    // Each cell's box: the box of its elements' particles at x.
    std::vector<double>& reals = contact.lists->tier_scratch;
    reals.assign(static_cast<std::size_t>(6 * cells), 0.0);
    double* lo = reals.data();
    double* hi = lo + 3 * cells;
    const Boxes points{x, x, n};
    for (int d = 0; d < 3; ++d) {
        const double* row = x + d * n;
        for (Index c = 0; c < cells; ++c) {
            double low = INF, high = -INF;
            for (Index q = elements.particle_start[c]; q < elements.particle_start[c + 1]; ++q) {
                const double v = row[elements.particle_items[q]];
                low = py_min(low, v);
                high = py_max(high, v);
            }
            lo[d * cells + c] = low, hi[d * cells + c] = high;
        }
    }
    const Boxes cell_boxes{lo, hi, cells};
    // The cells apart and within reach of each other, by sweeping along the axis of the widest spread.
    int axis = 0;
    double widest = -1.0;
    for (int d = 0; d < 3; ++d) {
        double a = INF, b = -INF;
        for (Index c = 0; c < cells; ++c) {
            if (!(lo[d * cells + c] <= hi[d * cells + c])) continue;
            a = py_min(a, lo[d * cells + c]);
            b = py_max(b, hi[d * cells + c]);
        }
        if (b - a > widest) widest = b - a, axis = d;
    }
    Index used = 0;
    for (Index c = 0; c < cells; ++c)
        if (lo[c] <= hi[c]) order[used++] = c;  // (a cell with no particle has an empty box)
    std::sort(order, order + used, [&](Index a, Index b) {
        const double la = lo[axis * cells + a], lb = lo[axis * cells + b];
        return la < lb || (la == lb && a < b);
    });
    struct Near {
        double gap;
        Index u, v;
    };
    std::vector<Near> close;
    for (Index p = 0; p < used; ++p) {
        const Index u = order[p];
        for (Index q = p + 1; q < used; ++q) {
            const Index v = order[q];
            if (lo[axis * cells + v] > hi[axis * cells + u] + reach) break;
            if (!apart(t, u, v)) continue;
            const double gap = box_gap(cell_boxes, u, v);
            if (gap < reach) close.push_back({gap, u < v ? u : v, u < v ? v : u});
        }
    }
    // The nearest cells first: once a pair is found, farther cells cannot hold a nearer one.
    std::sort(close.begin(), close.end(), [](const Near& a, const Near& b) {
        return a.gap < b.gap || (a.gap == b.gap && (a.u < b.u || (a.u == b.u && a.v < b.v)));
    });
    std::vector<Index> near_points[2], near_triangles[2], near_edges[2];  // each cell's elements near the other
    auto near = [&s](const Boxes& cell, Index other, const Index* items, Index count, const Boxes& of,
                     std::vector<Index>& out) {
        out.clear();
        for (Index q = 0; q < count; ++q)
            if (boxes_overlap(of, items[q], cell, other, s.bound)) out.push_back(items[q]);
    };
    for (const Near& c : close) {
        if (!(c.gap < s.bound)) break;
        const Index u = c.u, v = c.v;
        // Only the elements of each cell that come near the other's box can make a nearer pair (a tilted
        // sheet's cells' boxes overlap where the cells do not).
        near(cell_boxes, v, t.members + t.start[u], t.start[u + 1] - t.start[u], points, near_points[0]);
        near(cell_boxes, u, t.members + t.start[v], t.start[v + 1] - t.start[v], points, near_points[1]);
        near(cell_boxes, v, triangle_items + triangle_start[u], triangle_start[u + 1] - triangle_start[u], triangles,
             near_triangles[0]);
        near(cell_boxes, u, triangle_items + triangle_start[v], triangle_start[v + 1] - triangle_start[v], triangles,
             near_triangles[1]);
        for (int side = 0; side < 2; ++side)
            for (const Index i : near_points[side])
                for (const Index j : near_triangles[1 - side]) s.pair<POINT_TRIANGLE>(i, j, points, triangles);
        // The edges after the points: what the points found narrows them (edges outnumber points).
        near(cell_boxes, v, edge_items + edge_start[u], edge_start[u + 1] - edge_start[u], edges, near_edges[0]);
        near(cell_boxes, u, edge_items + edge_start[v], edge_start[v + 1] - edge_start[v], edges, near_edges[1]);
        for (const Index a : near_edges[0])
            for (const Index b : near_edges[1])
                if (a != b) s.pair<EDGE_EDGE>(a < b ? a : b, a < b ? b : a, edges, edges);
    }
}

}  // namespace

}  // namespace wc::self_contact
