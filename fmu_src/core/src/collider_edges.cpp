// The cloth's elements against mesh colliders' features (wetcloth/collider_edges.hpp; docs/model.md
// section 6.3).  A pair is four points, as self-collision's are (self_contact/geometry.hpp), each a cloth
// particle or a collider vertex (immovable: inverse mass 0): a particle and a collider triangle and a
// collider vertex and a cloth triangle (POINT_TRIANGLE), a cloth edge and a collider edge (EDGE_EDGE).
// If the cloth's start positions are kept apart from the collider by a positive distance and no pair
// comes closer than a positive distance along the step's straight-line motion, no cloth edge crosses a
// collider triangle and no collider edge a cloth triangle at its end: a crossing can only begin where a
// vertex meets a triangle or an edge meets an edge.
#include "wetcloth/collider_edges.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_supports.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"
#include "wetcloth/floor.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/elements.hpp"
#include "wetcloth/self_contact/geometry.hpp"
#include "wetcloth/self_contact/response.hpp"

namespace wc {

namespace {

using namespace self_contact;

//: Columns of a pair in ContactLists::collider_pairs: its kind, its four points (a cloth particle i >= 0,
//: a collider vertex v as -1 - v), its collider, the bits of its distance at the step's start (m; in a kept
//: list, at the list's reference).
enum PairColumn : Index { P_KIND = 0, P_POINTS = 1, P_COLLIDER = 5, P_START = 6, PAIR_COLUMNS = 7 };
using Pair = decltype(ContactLists::collider_pairs)::value_type;
static_assert(std::tuple_size<Pair>::value == PAIR_COLUMNS, "ContactLists::collider_pairs rows");

inline Index vertex_slot(Index v) { return -1 - v; }

//: Point s of a pair at positions x (3, n): a particle's, or a collider vertex's.
inline Vec3 at(const ColliderMeshes& m, const double* x, Index n, Index s) {
    if (s >= 0) return point(x, n, s);
    const Index v = -1 - s;
    return {m.vertices[v], m.vertices[m.vertex_count + v], m.vertices[2 * m.vertex_count + v]};
}

//: A box (lo, hi (3), m).
struct Box {
    double lo[3], hi[3];
    bool holds(const Vec3& p) const {
        return p.x >= lo[0] && p.x <= hi[0] && p.y >= lo[1] && p.y <= hi[1] && p.z >= lo[2] && p.z <= hi[2];
    }
    bool meets(const Vec3& a, const Vec3& b) const {  // the box of segment ab overlaps this one
        return std::max(a.x, b.x) >= lo[0] && std::min(a.x, b.x) <= hi[0] && std::max(a.y, b.y) >= lo[1] &&
               std::min(a.y, b.y) <= hi[1] && std::max(a.z, b.z) >= lo[2] && std::min(a.z, b.z) <= hi[2];
    }
};

//: The box of the paths from x0 to x1 of `width` particles idx (nullptr: particles 0 .. width - 1), grown
//: by pad (m).
Box path_box(const Index* idx, Index width, Index n, const double* x0, const double* x1, double pad) {
    Box b{};
    for (Index c = 0; c < 3; ++c) {
        b.lo[c] = std::numeric_limits<double>::infinity();
        b.hi[c] = -b.lo[c];
        for (Index k = 0; k < width; ++k) {
            const Index i = idx ? idx[k] : k;
            const double a = x0[c * n + i], e = x1[c * n + i];
            b.lo[c] = std::min(b.lo[c], std::min(a, e));
            b.hi[c] = std::max(b.hi[c], std::max(a, e));
        }
        b.lo[c] -= pad, b.hi[c] += pad;
    }
    return b;
}

//: The distance the pass keeps a cloth edge from a collider edge and a collider vertex from a cloth
//: triangle, as a fraction of thickness / 2 (a particle and a collider triangle: thickness / 2, the
//: particles' own rule): where the cloth lies on a curved collider, its edges between particles kept
//: thickness / 2 off dip closer by their sagitta (0.7 mm for particles 3 cm apart on a sphere of radius
//: 15 cm), which the pass leaves alone.
inline constexpr double EDGE_GAP = 0.1;

//: The distance (m) pair is kept apart: reach (thickness / 2, m) for a particle and a triangle, else
//: EDGE_GAP times that.
inline double target_of(const Pair& pair, double reach) {
    return pair[P_KIND] == POINT_TRIANGLE && pair[P_POINTS] >= 0 ? reach : EDGE_GAP * reach;
}

//: The colliders a pass covers and the frame it runs in: the still meshes in the world (shift null), or the
//: moving mesh collider `collider` in its table frame (shift its motion row, collider_motion.hpp), where it
//: stands still: the cloth's start through its start place, its end and velocities (relative to its
//: surface's) through its end place.
struct Frame {
    Index collider;
    const double* shift;
    bool covers(const Physics& phys, Index k) const {
        if (static_cast<Index>(phys.colliders[k * COLLIDER_COLUMNS + C_SHAPE]) != MESH) return false;
        return shift == nullptr ? !collider_moves(phys, k) : k == collider;
    }
    //: Whether its pairs' time of contact looks no further than the step's end (time_of_contact): a moving
    //: mesh's pairs approach at its speed (1 m/s, 12 mm in a step, a particle falling onto a box's top that
    //: stops 2 mm above it), where a look past the end would stop the particle in mid-air as a last
    //: resort.  (A still mesh's keep the look past it, as self-collision's: their results unchanged.)
    bool within_step() const { return shift != nullptr; }
};

//: A pair's start points, motions over the step and inverse masses (0 without mass, kg, and free).
struct Motion {
    int kind;
    Vec3 x[4], p[4];
    Inverse inverse;
};

Motion motion_of(const Pair& pair, const ColliderMeshes& m, Index n, const double* mass, const double* free,
                 const double* x0, const double* x1) {
    Motion mo{static_cast<int>(pair[P_KIND]), {}, {}, {{0.0, 0.0, 0.0, 0.0}}};
    for (int k = 0; k < 4; ++k) {
        const Index s = pair[P_POINTS + k];
        mo.x[k] = at(m, x0, n, s);
        mo.p[k] = s >= 0 ? sub(point(x1, n, s), mo.x[k]) : Vec3{0.0, 0.0, 0.0};
        mo.inverse.m[k] = s >= 0 && mass ? free[s] / mass[s] : 0.0;
    }
    return mo;
}

//: A lower bound (m) on the distance of a pair's points x[0..3] (kind's): that of the boxes of its two sides.
double box_gap(int kind, const Vec3 x[4]) {
    const int split = kind == POINT_TRIANGLE ? 1 : 2;  // points [0, split) against [split, 4)
    double gap2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        auto coord = [&](int k) { return c == 0 ? x[k].x : c == 1 ? x[k].y : x[k].z; };
        double alo = coord(0), ahi = alo, blo = coord(3), bhi = blo;
        for (int k = 1; k < split; ++k) alo = std::min(alo, coord(k)), ahi = std::max(ahi, coord(k));
        for (int k = split; k < 3; ++k) blo = std::min(blo, coord(k)), bhi = std::max(bhi, coord(k));
        const double g = std::max(0.0, std::max(blo - ahi, alo - bhi));
        gap2 += g * g;
    }
    return std::sqrt(gap2);
}

//: What pairs_for_step adds to a pair's bounds for the rounding of distances, as a fraction of thickness / 2
//: (a nanometre for 2 mm cloth; rounding errs by about 1e-15 m).
inline constexpr double ROUNDING_SLACK = 1e-6;

//: A bound on a pair's motion_bound over its cloth points' largest motion M, for a cloth element of `width`
//: particles (the collider's points still, motion_bound's mean of the four motions m): a particle and a
//: collider triangle |p - m| + |m| = M; a cloth edge and a collider edge |3 p0 - p1| / 4 + |p0 + p1| / 4
//: <= 1.5 M; a collider vertex and a cloth triangle |p1 + p2 + p3| / 4 + |3 p1 - p2 - p3| / 4 <= 2 M.
inline double bound_factor(int width) { return width == 1 ? 1.0 : width == 2 ? 1.5 : 2.0; }

//: The largest of values (n) over an element's `width` particles idx.
inline double element_largest(const Index* idx, int width, const double* values) {
    double a = values[idx[0]];
    for (int k = 1; k < width; ++k) a = py_max(a, values[idx[k]]);
    return a;
}

//: The pairs of the cloth's elements of `width` particles (rows of `elements`, nullptr: the particles) with the
//: features of mesh collider k's triangles near them at positions x: those nearer than their distance
//: (target_of, from reach, m) plus reach plus the element's largest allowance and bound_factor times its largest
//: stride (allowance, stride: (n) m; and a nanometre for rounding), from the triangles whose boxes reach the
//: element's box grown by reach more (a cloth triangle's: the vertices in it, from vertex_cells,
//: mesh_vertex_cells's).  stamp, vertex_stamp: scratch, the last element that saw each triangle, and each
//: vertex as a cloth edge's lower end (+ 1): a collider edge is paired with a cloth edge once, though both its
//: triangles meet it (edge_list: scratch, the cloth edge's collider edges from each lower end).
void gather(const Index* elements, Index count, int width, Index k, Index mesh, const ColliderMeshes& m, Index n,
            const double* x, double reach, const double* allowance, const double* stride,
            const std::vector<std::pair<Index, Index>>& vertex_cells, std::vector<Index>& near, std::vector<Index>& stamp,
            std::vector<Index>& vertex_stamp, std::vector<Index>& edge_list, std::vector<Pair>& pairs,
            const char* only = nullptr) {
    double extra = 0.0;  // the element's: reach + its allowance + bound_factor strides, m
    auto add = [&](const Pair& pair) {
        const Motion mo = motion_of(pair, m, n, nullptr, nullptr, x, x);
        const double d = distance(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        if (d < target_of(pair, reach) + extra) {
            pairs.push_back(pair);
            pairs.back()[P_START] = gap_bits(d);
        }
    };
    std::fill(stamp.begin(), stamp.end(), 0);
    if (width == 2) vertex_stamp.assign(static_cast<std::size_t>(m.vertex_count), 0);
    // A cloth edge's collider edges: edge_list's first vertex_count slots hold each lower end's latest entry
    // (valid where vertex_stamp holds the element), its entries (upper end, the entry before) follow.
    auto first_sight = [&](Index e, Index a, Index b) {  // whether edge (a, b) (a < b) is new to element e
        const std::size_t end = static_cast<std::size_t>(a);
        if (vertex_stamp[end] != e + 1) {
            vertex_stamp[end] = e + 1;
            edge_list[end] = -1;
        }
        for (Index entry = edge_list[end]; entry >= 0; entry = edge_list[static_cast<std::size_t>(entry + 1)]) {
            if (edge_list[static_cast<std::size_t>(entry)] == b) return false;
        }
        edge_list.push_back(b);
        edge_list.push_back(edge_list[end]);
        edge_list[end] = static_cast<Index>(edge_list.size()) - 2;
        return true;
    };
    for (Index e = 0; e < count; ++e) {
        if (only != nullptr && only[e] == 0) continue;
        const Index* idx = elements ? elements + e * width : &e;
        extra = reach + ((element_largest(idx, width, allowance) + bound_factor(width) * element_largest(idx, width, stride)) +
                         ROUNDING_SLACK * reach);
        const Box box = path_box(idx, width, n, x, x, reach + extra);  // the farthest a pair kept can be
        near.clear();
        if (width == 3) {  // each collider vertex in the box and the cloth triangle
            mesh_vertices_in(m, mesh, vertex_cells, box.lo, box.hi, near);
            for (const Index v : near) {
                if (box.holds(at(m, nullptr, 0, vertex_slot(v)))) add({POINT_TRIANGLE, vertex_slot(v), idx[0], idx[1], idx[2], k, 0});
            }
            continue;
        }
        mesh_triangles_in(m, mesh, box.lo, box.hi, near);
        if (width == 2) edge_list.resize(static_cast<std::size_t>(m.vertex_count));
        for (const Index t : near) {
            if (static_cast<Index>(stamp.size()) <= t) stamp.resize(static_cast<std::size_t>(t + 1), 0);
            if (stamp[static_cast<std::size_t>(t)] == e + 1) continue;  // seen through another cell
            stamp[static_cast<std::size_t>(t)] = e + 1;
            const Index* v = m.triangles + 3 * t;
            const Vec3 p[3] = {at(m, nullptr, 0, vertex_slot(v[0])), at(m, nullptr, 0, vertex_slot(v[1])),
                               at(m, nullptr, 0, vertex_slot(v[2]))};
            if (width == 1) {  // a particle and the triangle
                Box tb{{p[0].x, p[0].y, p[0].z}, {p[0].x, p[0].y, p[0].z}};
                for (int j = 1; j < 3; ++j) {
                    const double q[3] = {p[j].x, p[j].y, p[j].z};
                    for (Index c = 0; c < 3; ++c) tb.lo[c] = std::min(tb.lo[c], q[c]), tb.hi[c] = std::max(tb.hi[c], q[c]);
                }
                const bool overlap = tb.lo[0] <= box.hi[0] && tb.hi[0] >= box.lo[0] && tb.lo[1] <= box.hi[1] &&
                                     tb.hi[1] >= box.lo[1] && tb.lo[2] <= box.hi[2] && tb.hi[2] >= box.lo[2];
                if (overlap) add({POINT_TRIANGLE, idx[0], vertex_slot(v[0]), vertex_slot(v[1]), vertex_slot(v[2]), k, 0});
            } else {  // the edge and each of the triangle's edges
                for (int j = 0; j < 3; ++j) {
                    if (!box.meets(p[j], p[(j + 1) % 3])) continue;
                    const Index a = std::min(v[j], v[(j + 1) % 3]), b = std::max(v[j], v[(j + 1) % 3]);
                    if (!first_sight(e, a, b)) continue;
                    add({EDGE_EDGE, idx[0], idx[1], vertex_slot(a), vertex_slot(b), k, 0});
                }
            }
        }
    }
}

//: What settle_pair did with a pair: nothing, its motion shown safe (the last resort would pass it too, while
//: its particles' ends stay); pushed it apart; nothing, left to the last resort.
enum Settled : int { SAFE = 0, TREATED = 1, LEFT = 2 };

//: Treat one pair if it needs it (as self-collision's settle_pair, at distance gap).
Settled settle_pair(const Pair& pair, double start, const Physics& phys, const Frame& frame, double gap, Index n,
                 const double* mass, const double* free, const double* x0, double* x1, double* v1, ContactLists& lists) {
    const Motion mo = motion_of(pair, phys.meshes, n, mass, free, x0, x1);
    if (mo.inverse.sum() == 0.0) return LEFT;
    const ContactTime ct = contact_time(mo.kind, mo.x, mo.p, start, gap, frame.within_step());
    if (!ct.near) return SAFE;
    const double when = ct.when;
    const double t = when == CLEAR ? 1.0 : when;
    Vec3 q[4];
    for (int k = 0; k < 4; ++k) q[k] = along(mo.x[k], t, mo.p[k]);
    const Weights w = closest(mo.kind, q[0], q[1], q[2], q[3]);
    const Vec3 d = combine(w, q[0], q[1], q[2], q[3]);
    const double length = norm(d);
    if (when == CLEAR && length >= (1.0 - SLACK) * gap) return SAFE;
    if (!(length > 0.0)) return LEFT;  // no side to push to: left to the last resort
    const Vec3 normal = {d.x / length, d.y / length, d.z / length};
    double world[3] = {normal.x, normal.y, normal.z};  // the push's direction in the world
    if (frame.shift != nullptr) world_direction(frame.shift, world);
    // The four points as particles 0..3 of their own (3, 4) arrays, the collider's at rest.
    double x[12], v[12];
    for (int k = 0; k < 4; ++k) {
        const Index s = pair[P_POINTS + k];
        const Vec3 e = s >= 0 ? point(x1, n, s) : mo.x[k];
        x[k] = e.x, x[4 + k] = e.y, x[8 + k] = e.z;
        for (Index c = 0; c < 3; ++c) v[4 * c + k] = s >= 0 ? v1[c * n + s] : 0.0;
    }
    const Index idx[4] = {0, 1, 2, 3};
    const double friction = phys.colliders[pair[P_COLLIDER] * COLLIDER_COLUMNS + C_FRICTION];
    push_apart(idx, w, normal, gap, mo.inverse, friction, phys.floor_z, 4, x, v);
    const double side[4] = {w.w0, w.w1, w.w2, w.w3};
    for (int k = 0; k < 4; ++k) {
        const Index s = pair[P_POINTS + k];
        if (s < 0) continue;
        for (Index c = 0; c < 3; ++c) x1[c * n + s] = x[4 * c + k], v1[c * n + s] = v[4 * c + k];
        if (side[k] == 0.0 || mo.inverse.m[k] == 0.0) continue;
        const double sign = side[k] > 0.0 ? 1.0 : -1.0;  // the point side moves along the normal, the other against it
        lists.collider_pushed[static_cast<std::size_t>(s)] = 1;
        lists.collider_normals[static_cast<std::size_t>(s)] = sign * world[0];
        lists.collider_normals[static_cast<std::size_t>(n + s)] = sign * world[1];
        lists.collider_normals[static_cast<std::size_t>(2 * n + s)] = sign * world[2];
    }
    return TREATED;
}

//: The kept list (ContactLists::collider_list) holds every pair nearer at the reference positions than its
//: distance plus reach plus the largest allowance of its cloth points and bound_factor times their largest
//: stride.  While no particle starts a step farther than its allowance from its reference nor moves more
//: than its stride in it, a pair's start distance is at most that allowance less than there and its motion's
//: bound at most bound_factor of that stride: the list holds every pair pairs_for_step would keep (and the
//: supports' pairs, within 1.5 reach at the start: the least stride's bound_factor exceeds 0.4 reach).  A
//: particle whose elements' boxes are farther than 2 reach + LIST_MARGINS far margins from every mesh
//: triangle's cell may have the far margin as both.
inline constexpr double LIST_MARGINS = 3.0;  // 1 + the largest bound_factor
//: The least allowance and stride, and the far margin, as fractions of thickness / 2: a cloth lying still keeps
//: its list while its parts away from the mesh swing.
inline constexpr double LEAST_MARGIN = 1.0;
inline constexpr double FAR_MARGIN = 4.0;
//: A moving mesh's least allowance and stride: the cloth moves against it, and its lists were gathered again every 4
//: steps at LEAST_MARGIN (the sweep's mesh ball: 2599 lists in 9671 steps; 984 at this margin).
inline constexpr double MOVING_LEAST_MARGIN = 3.0;
//: A particle's stride (how far it may move in a step) over its motion: room for a slightly faster step and
//: the pushes' changes.
inline constexpr double MOTION_ROOM = 1.1;
//: How far a particle may start a later step from the reference, as a fraction of its stride (at least the
//: least or far margin): a list mostly serves the step it was gathered for (at 1 it held two steps at a
//: steady pace but its reach was 1.6 times as long: the sweep's mesh ball at frame steps 2.3 against 1.5 s).
inline constexpr double START_ROOM = 0.25;
//: A list that no longer holds is renewed for the particles past RENEW_FRACTION of their allowance or stride
//: (renew_list), those it does not hold and those about to leave it, unless they are more than RENEW_SHARE of the
//: cloth: then it is gathered again wholly.  The sheet on the icosphere of bench/collider_cost.py --part lying:
//: renewed for those it does not hold alone, the list was renewed six times as often, for no gain; at 0.5 as
//: often as when wholly gathered, 0.8x the time (0.25: the same).
inline constexpr double RENEW_FRACTION = 0.5;
inline constexpr double RENEW_SHARE = 0.25;

//: The squared distance (m^2) of particle i of x (3, n) from its place in y (3, n).
inline double moved2(Index n, Index i, const double* x, const double* y) {
    double d2 = 0.0;
    for (Index c = 0; c < 3; ++c) d2 += (x[c * n + i] - y[c * n + i]) * (x[c * n + i] - y[c * n + i]);
    return d2;
}

//: The largest distance (m) of a particle of x (3, n) from its place in y (3, n).
double largest_move(Index n, const double* x, const double* y) {
    double most2 = 0.0;
    for (Index i = 0; i < n; ++i) most2 = py_max(most2, moved2(n, i, x, y));
    return std::sqrt(most2);
}

//: Whether the kept list, gathered from phys's meshes, holds for a step from x0 to x1 (3, n; x1 null: at x0
//: alone): no particle farther at x0 from its reference than its allowance, nor moving more than its stride.
bool list_holds(const ColliderPairList& kept, const Physics& phys, Index n, const double* x0, const double* x1) {
    if (!(kept.margin > 0.0) || kept.key[0] != phys.meshes.vertices || kept.key[1] != phys.colliders) return false;
    const double* ref = kept.reference.data();
    const double* allowance = kept.allowance.data();
    const double* stride = kept.stride.data();
    for (Index i = 0; i < n; ++i) {
        const double d2 = moved2(n, i, x0, ref), p2 = x1 ? moved2(n, i, x1, x0) : 0.0;
        if (!(d2 <= allowance[i] * allowance[i] && p2 <= stride[i] * stride[i])) return false;
    }
    return true;
}

//: Mark (near = 1) the particles of the cloth's elements of `width` particles (as gather's) whose boxes at x,
//: grown by pad (m), overlap a cell of mesh `mesh` that lists a triangle.
void mark_near(const Index* elements, Index count, int width, Index mesh, const ColliderMeshes& m, Index n,
               const double* x, double pad, std::vector<double>& near, const char* only = nullptr) {
    for (Index e = 0; e < count; ++e) {
        if (only != nullptr && only[e] == 0) continue;
        const Index* idx = elements ? elements + e * width : &e;
        const Box box = path_box(idx, width, n, x, x, pad);
        if (!mesh_lists_triangles_in(m, mesh, box.lo, box.hi)) continue;
        for (int k = 0; k < width; ++k) near[static_cast<std::size_t>(idx[k])] = 1.0;
    }
}

//: Sort pairs (with vertex_count collider vertices, n particles) into their rows' lexicographic order, as
//: std::sort would: by kind and first point (a counting sort), then each run of a kind and first point (a
//: few pairs) by its whole rows.
void sort_pairs(std::vector<Pair>& pairs, Index vertex_count, Index n) {
    static_assert(POINT_TRIANGLE == 0 && EDGE_EDGE == 1, "the kinds' buckets");
    const Index span = vertex_count + n;  // first points -vertex_count .. n - 1
    auto bucket = [&](const Pair& pair) {
        return static_cast<std::size_t>(pair[P_KIND] * span + pair[P_POINTS] + vertex_count);
    };
    std::vector<std::size_t> start(2 * static_cast<std::size_t>(span) + 1, 0);
    for (const Pair& pair : pairs) start[bucket(pair) + 1] += 1;
    for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    std::vector<Pair> sorted(pairs.size());
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (const Pair& pair : pairs) sorted[next[bucket(pair)]++] = pair;
    for (std::size_t b = 0; b + 1 < start.size(); ++b) {
        if (start[b + 1] - start[b] > 1) std::sort(sorted.begin() + start[b], sorted.begin() + start[b + 1]);
    }
    pairs.swap(sorted);
}

//: Gather the kept list for the step from x0 to x1 (x1 = x0 where no step is in hand): its reference x0; each
//: particle's stride MOTION_ROOM times the larger of its motion from x0 to x1 and over the last step the pass
//: looked at (kept.motion; each particle's own: one moving fast elsewhere widens no other's reach), its
//: allowance START_ROOM of that; both at least LEAST_MARGIN of reach (thickness / 2, m; MOVING_LEAST_MARGIN in
//: a moving mesh's frame) near a mesh, FAR_MARGIN of reach elsewhere.  A cloth whose box is far from every
//: mesh's box keeps an empty list while no particle moves more than what that distance allows (if this
//: step's motion fits in it).  Each pair keeps the bits of its distance at the reference (P_START).
//: With `renew` (n: 1 for the particles to renew, renew_list's), only those particles get a new reference,
//: stride and allowance, and only the pairs of the cloth's elements that have one of them are gathered again
//: (the others', gathered at their own particles' references, still hold every pair they must: a list holds a
//: pair while each of its particles stays within its own allowance of its own reference).
void keep_list(const Contact& contact, ContactLists& lists, ColliderPairList& kept, const Physics& phys,
               const Frame& frame, Index n, const double* x0, const double* x1, double reach,
               const char* renew = nullptr) {
    const std::size_t size = static_cast<std::size_t>(n);
    auto renewed = [&](Index i) { return renew == nullptr || renew[i] != 0; };
    std::vector<double>& x = kept.reference;
    if (renew == nullptr) {
        x.assign(x0, x0 + 3 * n);
    } else {
        for (Index c = 0; c < 3; ++c)
            for (Index i = 0; i < n; ++i)
                if (renew[i] != 0) x[static_cast<std::size_t>(c * n + i)] = x0[c * n + i];
    }
    std::vector<Index>& found = lists.collider_items;
    std::vector<Pair>& pairs = kept.pairs;
    kept.key[0] = phys.meshes.vertices;
    kept.key[1] = phys.colliders;
    // Each particle's motion: over this step, and over the last one the pass looked at.
    std::vector<double> motion(size, 0.0);
    const bool seen = kept.motion.size() == size;
    double fastest = 0.0;
    for (Index i = 0; i < n; ++i) {
        motion[static_cast<std::size_t>(i)] =
            py_max(std::sqrt(moved2(n, i, x1, x0)), seen ? kept.motion[static_cast<std::size_t>(i)] : 0.0);
        fastest = py_max(fastest, motion[static_cast<std::size_t>(i)]);
    }
    // The elements gathered: all, or those with a renewed particle (masks over particles, edges, triangles).
    std::vector<char> element_masks;
    const char* only[3] = {nullptr, nullptr, nullptr};
    if (renew != nullptr) {
        element_masks.assign(size + static_cast<std::size_t>(contact.edge_count + contact.triangle_count), 0);
        char* mask = element_masks.data();
        for (Index i = 0; i < n; ++i) mask[i] = renew[i];
        for (Index e = 0; e < contact.edge_count; ++e)
            mask[n + e] = static_cast<char>(renew[contact.edges[2 * e]] | renew[contact.edges[2 * e + 1]]);
        for (Index t = 0; t < contact.triangle_count; ++t) {
            const Index* v = contact.triangles + 3 * t;
            mask[n + contact.edge_count + t] = static_cast<char>(renew[v[0]] | renew[v[1]] | renew[v[2]]);
        }
        only[0] = mask, only[1] = mask + n, only[2] = mask + n + contact.edge_count;
        // The pairs of those elements go: a pair's cloth points are its element's particles.
        pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                                   [&](const Pair& pair) {
                                       for (int k = 0; k < 4; ++k) {
                                           const Index q = pair[P_POINTS + k];
                                           if (q >= 0 && renew[q] != 0) return true;
                                       }
                                       return false;
                                   }),
                    pairs.end());
    } else {
        pairs.clear();
    }
    std::vector<double> near(size, 0.0);  // 1 for the particles near a mesh (of those renewed)
    if (renew == nullptr) {
        // Far from every mesh's box (no pair within 2 reach + LIST_MARGINS allowances): no pairs, and every
        // particle has that allowance and stride.
        const Box whole = path_box(nullptr, n, n, x.data(), x.data(), 0.0);
        double gap = std::numeric_limits<double>::infinity();
        for (Index k = 0; k < phys.collider_count; ++k) {
            const double* row = phys.colliders + k * COLLIDER_COLUMNS;
            if (!frame.covers(phys, k)) continue;
            const double* header = phys.meshes.headers + static_cast<Index>(row[C_RADIUS]) * MESH_COLUMNS;
            double gap2 = 0.0;
            for (Index c = 0; c < 3; ++c) {
                const double g = py_max(0.0, py_max(header[M_LO_X + c] - whole.hi[c], whole.lo[c] - header[M_HI_X + c]));
                gap2 += g * g;
            }
            gap = py_min(gap, std::sqrt(gap2));
        }
        const double clear = (gap - 2.0 * reach) / LIST_MARGINS;
        kept.clear = clear >= py_max(LEAST_MARGIN * reach, fastest);
        if (kept.clear) {  // (and it holds for this step)
            kept.allowance.assign(size, py_min(clear, std::numeric_limits<double>::max()));
            kept.stride = kept.allowance;
            kept.margin = kept.allowance[0];
            return;
        }
        kept.allowance.assign(size, 0.0);
        kept.stride.assign(size, 0.0);
    }
    // The particles near a mesh: of an element whose box, grown by the far pad, meets a cell of it that lists
    // a triangle.
    const double far = FAR_MARGIN * reach;
    const double far_pad = 2.0 * reach + LIST_MARGINS * far;
    auto meshes_met = [&](double pad, std::vector<Index>& met) {  // the meshes the cloth's box grown by pad meets
        const Box cloth = path_box(nullptr, n, n, x.data(), x.data(), pad);
        met.clear();
        for (Index k = 0; k < phys.collider_count; ++k) {
            const double* row = phys.colliders + k * COLLIDER_COLUMNS;
            if (!frame.covers(phys, k)) continue;
            const double* header = phys.meshes.headers + static_cast<Index>(row[C_RADIUS]) * MESH_COLUMNS;
            bool meets = true;
            for (Index c = 0; c < 3; ++c) meets = meets && cloth.hi[c] >= header[M_LO_X + c] && cloth.lo[c] <= header[M_HI_X + c];
            if (meets) met.push_back(k);
        }
    };
    std::vector<Index> reached, edge_list;
    std::vector<std::pair<Index, Index>> vertex_cells;
    meshes_met(far_pad, reached);
    for (const Index k : reached) {
        const Index mesh = static_cast<Index>(phys.colliders[k * COLLIDER_COLUMNS + C_RADIUS]);
        mark_near(nullptr, n, 1, mesh, phys.meshes, n, x.data(), far_pad, near, only[0]);
        mark_near(contact.edges, contact.edge_count, 2, mesh, phys.meshes, n, x.data(), far_pad, near, only[1]);
        mark_near(contact.triangles, contact.triangle_count, 3, mesh, phys.meshes, n, x.data(), far_pad, near, only[2]);
    }
    const double least = (frame.shift != nullptr ? MOVING_LEAST_MARGIN : LEAST_MARGIN) * reach;
    double widest = 0.0;
    std::vector<double>& allowance = kept.allowance;
    std::vector<double>& stride = kept.stride;
    for (Index i = 0; i < n; ++i) {
        const std::size_t j = static_cast<std::size_t>(i);
        if (renewed(i)) {
            const double base = near[j] != 0.0 ? least : far;
            stride[j] = py_max(base, MOTION_ROOM * motion[j]);
            allowance[j] = py_max(base, START_ROOM * stride[j]);
        }
        widest = py_max(widest, allowance[j] + 2.0 * stride[j]);
    }
    // The meshes an element's pairs may reach with the widest allowances (a particle moving fast far away).
    meshes_met(2.0 * reach + (widest + ROUNDING_SLACK * reach), reached);
    for (const Index k : reached) {
        const Index mesh = static_cast<Index>(phys.colliders[k * COLLIDER_COLUMNS + C_RADIUS]);
        std::vector<Index>& stamp = lists.collider_stamp;
        std::vector<Index>& taken = lists.collider_vertex_stamp;
        mesh_vertex_cells(phys.meshes, mesh, vertex_cells);
        gather(nullptr, n, 1, k, mesh, phys.meshes, n, x.data(), reach, allowance.data(), stride.data(), vertex_cells,
               found, stamp, taken, edge_list, pairs, only[0]);
        gather(contact.edges, contact.edge_count, 2, k, mesh, phys.meshes, n, x.data(), reach, allowance.data(),
               stride.data(), vertex_cells, found, stamp, taken, edge_list, pairs, only[1]);
        gather(contact.triangles, contact.triangle_count, 3, k, mesh, phys.meshes, n, x.data(), reach, allowance.data(),
               stride.data(), vertex_cells, found, stamp, taken, edge_list, pairs, only[2]);
    }
    sort_pairs(pairs, phys.meshes.vertex_count, n);  // (a pair found twice has the same distance: one copy kept)
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    kept.margin = *std::min_element(allowance.begin(), allowance.end());
}

//: Renew the kept list for a step from x0 to x1 that it does not hold (list_holds false): for the particles past
//: RENEW_FRACTION of their allowance or stride alone, where they are few (at most RENEW_SHARE of the cloth) and
//: the list was gathered from these meshes with pairs near (not the far cloth's empty list); else wholly.
void renew_list(const Contact& contact, ContactLists& lists, ColliderPairList& kept, const Physics& phys,
                const Frame& frame, Index n, const double* x0, const double* x1, double reach) {
    const bool whole = !(kept.margin > 0.0) || kept.clear || kept.key[0] != phys.meshes.vertices ||
                       kept.key[1] != phys.colliders || kept.reference.size() != 3 * static_cast<std::size_t>(n);
    if (whole) return keep_list(contact, lists, kept, phys, frame, n, x0, x1, reach);
    std::vector<char> renew(static_cast<std::size_t>(n), 0);
    Index count = 0;
    const double f2 = RENEW_FRACTION * RENEW_FRACTION;
    for (Index i = 0; i < n; ++i) {
        const double a = kept.allowance[static_cast<std::size_t>(i)], s = kept.stride[static_cast<std::size_t>(i)];
        const double d2 = moved2(n, i, x0, kept.reference.data()), p2 = x1 ? moved2(n, i, x1, x0) : 0.0;
        if (!(d2 <= f2 * a * a && p2 <= f2 * s * s)) renew[static_cast<std::size_t>(i)] = 1, count += 1;
    }
    if (static_cast<double>(count) > RENEW_SHARE * static_cast<double>(n)) {
        return keep_list(contact, lists, kept, phys, frame, n, x0, x1, reach);
    }
    keep_list(contact, lists, kept, phys, frame, n, x0, x1, reach, renew.data());
}

//: Each particle's distance (m) from its place in the kept list's reference to x (3, n), into `out` (n).
void moves_from_reference(const ColliderPairList& kept, Index n, const double* x, std::vector<double>& out) {
    out.resize(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = std::sqrt(moved2(n, i, x, kept.reference.data()));
}

//: The largest of values (n) over a pair's cloth points.
inline double pair_largest(const Pair& pair, const std::vector<double>& values) {
    double most = 0.0;
    for (int k = 0; k < 4; ++k) {
        const Index s = pair[P_POINTS + k];
        if (s >= 0) most = py_max(most, values[static_cast<std::size_t>(s)]);
    }
    return most;
}

//: The least distance (m) a kept pair can have with its cloth points moved by `moved` (n, m) from the list's
//: reference (its distance there less their largest move, less a nanometre for rounding).
inline double least_gap(const Pair& pair, const std::vector<double>& moved, double reach) {
    return gap_of(pair[P_START]) - (pair_largest(pair, moved) + ROUNDING_SLACK * reach);
}

//: The pairs near enough to need a look over the step from x0 to x1, in lists.collider_pairs with their
//: start distances: those of the kept list (gathered again unless it holds at x0 and x1) nearer than their
//: distance (target_of) plus reach (m) at the start less their motion's bound (pushes that move no particle
//: more than reach / 4 leave the others out of reach).  Which list they come from changes nothing: a pair
//: kept beyond them is never treated.
void pairs_for_step(const Contact& contact, ContactLists& lists, ColliderPairList& kept, const Physics& phys,
                    const Frame& frame, Index n, const double* x0, const double* x1, double reach) {
    if (!list_holds(kept, phys, n, x0, x1)) renew_list(contact, lists, kept, phys, frame, n, x0, x1, reach);
    kept.motion.resize(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) kept.motion[static_cast<std::size_t>(i)] = std::sqrt(moved2(n, i, x1, x0));
    std::vector<Pair>& pairs = lists.collider_pairs;
    pairs.clear();
    // A pair's start distance is at least its distance at the reference less its cloth points' largest
    // move from there, and its motion's bound at most 2.5 times their largest motion over the step (a
    // vertex and a cloth triangle's; a cloth edge's 1.5, a particle's 1): a pair farther at the reference
    // than its distance plus reach plus those two (and a nanometre for rounding) is left out without a look.
    std::vector<double>& moved = lists.collider_moved;
    moves_from_reference(kept, n, x0, moved);
    for (const Pair& pair : kept.pairs) {
        const double unseen = pair_largest(pair, moved) + 2.5 * pair_largest(pair, kept.motion) + ROUNDING_SLACK * reach;
        if (gap_of(pair[P_START]) - unseen >= target_of(pair, reach) + reach) continue;
        const Motion mo = motion_of(pair, phys.meshes, n, nullptr, nullptr, x0, x1);
        const double bound = motion_bound(mo.kind, mo.p[0], mo.p[1], mo.p[2], mo.p[3]);
        const double within = target_of(pair, reach) + reach;
        if (box_gap(mo.kind, mo.x) - bound >= within) continue;  // (the cheap test first)
        const double d = distance(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        if (d - bound >= within) continue;
        pairs.push_back(pair);
        pairs.back()[P_START] = gap_bits(d);
    }
    std::vector<double>& start = lists.collider_start;
    start.resize(pairs.size());
    for (std::size_t j = 0; j < pairs.size(); ++j) start[j] = gap_of(pairs[j][P_START]);
}

//: The pass of collider_edge_contact over frame's colliders, in its frame (x0, x1, v1 there; reach m);
//: fresh: the pushes' marks are not yet cleared in this call (then cleared at the first pair).
int edge_pass(const Contact& contact, ContactLists& lists, ColliderPairList& kept, const Physics& phys,
              const Frame& frame, double reach, Index n, const double* mass, const double* free, const double* x0,
              double* x1, double* v1, bool& fresh) {
    const std::size_t size = static_cast<std::size_t>(n);
    std::vector<double>& gathered = lists.collider_end;
    std::vector<Pair>& pairs = lists.collider_pairs;
    const std::vector<double>& start = lists.collider_start;
    int result = UNTOUCHED;
    // A pair found SAFE whose particles' ends no push or stop has changed since is SAFE again (settle_pair's
    // and the last resort's tests read only its points' starts and ends): it is not looked at again.  changes
    // counts the pushes and stops, changed (n) holds the count at each particle's last, safe_at (pairs) the
    // count when each pair was last found SAFE (-1: not).
    Index changes = 0;
    std::vector<Index> changed(size, 0);
    std::vector<Index> safe_at;
    auto still_safe = [&](const Pair& pair, Index at) {
        if (at < 0) return false;
        for (int k = 0; k < 4; ++k) {
            const Index s = pair[P_POINTS + k];
            if (s >= 0 && changed[static_cast<std::size_t>(s)] > at) return false;
        }
        return true;
    };
    auto mark_changed = [&](const Pair& pair) {
        changes += 1;
        for (int k = 0; k < 4; ++k) {
            const Index s = pair[P_POINTS + k];
            if (s >= 0) changed[static_cast<std::size_t>(s)] = changes;
        }
    };
    // The pairs that may need a push; gathered again if the pushes moved a particle farther than reach / 4
    // from where it was when they were (the pairs left out stay out of reach then).
    for (int attempt = 0; attempt < ATTEMPTS; ++attempt) {
        pairs_for_step(contact, lists, kept, phys, frame, n, x0, x1, reach);
        safe_at.assign(pairs.size(), -1);
        if (pairs.empty()) break;
        if (fresh) {
            lists.collider_pushed.assign(size, 0);
            lists.collider_normals.resize(3 * size);
            fresh = false;
        }
        gathered.assign(x1, x1 + 3 * n);
        for (int pass = 0; pass < PASSES_MAX; ++pass) {
            Index treated = 0;
            for (std::size_t j = 0; j < pairs.size(); ++j) {
                if (still_safe(pairs[j], safe_at[j])) continue;
                const Settled settled = settle_pair(pairs[j], start[j], phys, frame, target_of(pairs[j], reach), n,
                                                    mass, free, x0, x1, v1, lists);
                safe_at[j] = settled == SAFE ? changes : -1;
                if (settled != TREATED) continue;
                treated += 1;
                mark_changed(pairs[j]);
            }
            if (treated == 0) break;
            result |= PUSHED;
        }
        if (largest_move(n, x1, gathered.data()) <= 0.25 * reach) break;  // a pair's motion bound grows by at most 4 times the move
        if (attempt + 1 < ATTEMPTS) continue;
        pairs_for_step(contact, lists, kept, phys, frame, n, x0, x1, reach);  // for the last resort
        safe_at.assign(pairs.size(), -1);
    }
    if (pairs.empty()) return result;
    // The last resort: the particles of a pair whose motion is still not shown safe stay where they started.
    std::vector<Index>& stopped = lists.collider_items;
    stopped.assign(size, 0);
    for (Index round = 0; round < n; ++round) {
        Index unsafe = 0;
        for (std::size_t j = 0; j < pairs.size(); ++j) {
            const Pair& pair = pairs[j];
            bool movable = false;
            for (int k = 0; k < 4; ++k) {
                const Index s = pair[P_POINTS + k];
                movable = movable || (s >= 0 && free[s] != 0.0 && stopped[static_cast<std::size_t>(s)] == 0);
            }
            if (!movable || still_safe(pair, safe_at[j])) continue;
            const Motion mo = motion_of(pair, phys.meshes, n, mass, free, x0, x1);
            if (contact_time(mo.kind, mo.x, mo.p, start[j], target_of(pair, reach), frame.within_step()).when == CLEAR) {
                safe_at[j] = changes;
                continue;
            }
            unsafe += 1;
            for (int k = 0; k < 4; ++k) {
                const Index s = pair[P_POINTS + k];
                if (s < 0 || free[s] == 0.0) continue;
                stopped[static_cast<std::size_t>(s)] = 1;
                lists.collider_pushed[static_cast<std::size_t>(s)] = 0;
                for (Index c = 0; c < 3; ++c) x1[c * n + s] = x0[c * n + s], v1[c * n + s] = 0.0;
            }
            mark_changed(pair);
        }
        if (unsafe == 0) break;
        result |= STOPPED;
    }
    return result;
}

//: The cloth's start x0, end x1 and end velocities v1 (3, n each) in moving collider k's table frame, in
//: frame (3, 3, n): the start through its place at the step's start, the end through its place now, the
//: velocities relative to its surface's there, turned into it.
void into_table_frame(const Physics& phys, Index k, Index n, const double* x0, const double* x1, const double* v1,
                      double* frame) {
    const double* shift = collider_shift(phys, k);
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    double* q0 = frame;
    double* q1 = frame + 3 * n;
    double* w1 = frame + 6 * n;
    for (Index i = 0; i < n; ++i) {
        const double a[3] = {x0[i], x0[n + i], x0[2 * n + i]}, e[3] = {x1[i], x1[n + i], x1[2 * n + i]};
        double from[3], to[3], u[3];
        table_point(shift, centre, a, true, from);
        table_point(shift, centre, e, false, to);
        surface_velocity(phys, k, e, u);
        double r[3] = {v1[i] - u[0], v1[n + i] - u[1], v1[2 * n + i] - u[2]};
        table_direction(shift, r);
        for (Index c = 0; c < 3; ++c) q0[c * n + i] = from[c], q1[c * n + i] = to[c], w1[c * n + i] = r[c];
    }
}

//: Back from moving collider k's table frame: the particles whose end (q1) or velocity (w1) in frame
//: (3, 3, n, into_table_frame's) the pass changed from their world end x1 and velocity v1 get them in the
//: world (their velocities plus the surface's).
void out_of_table_frame(const Physics& phys, Index k, Index n, const double* frame, const double* unchanged,
                        double* x1, double* v1) {
    const double* shift = collider_shift(phys, k);
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    const double* q1 = frame + 3 * n;
    const double* w1 = frame + 6 * n;
    for (Index i = 0; i < n; ++i) {
        bool changed = false;
        for (Index c = 0; c < 3; ++c) {
            changed = changed || q1[c * n + i] != unchanged[c * n + i] || w1[c * n + i] != unchanged[3 * n + c * n + i];
        }
        if (!changed) continue;
        const double q[3] = {q1[i], q1[n + i], q1[2 * n + i]};
        double p[3], u[3], w[3] = {w1[i], w1[n + i], w1[2 * n + i]};
        world_point(shift, centre, q, p);
        world_direction(shift, w);
        surface_velocity(phys, k, p, u);
        for (Index c = 0; c < 3; ++c) x1[c * n + i] = p[c], v1[c * n + i] = w[c] + u[c];
    }
}

//: Faces whose unit normals' dot product is at least this lie in one plane (within 4.5e-5 rad).
inline constexpr double FLAT = 1.0 - 1e-9;

//: Whether the collider feature of the `count` vertices v (a vertex, or an edge's two ends) of mesh `mesh` lies
//: flat: all the faces that hold it in one plane (a box's face's diagonal, a vertex inside a flat region).
//: The particles' contact keeps the cloth off that plane by thickness / 2 already, and the feature cannot poke
//: between them.  found: scratch.
bool flat_feature(const ColliderMeshes& m, Index mesh, const Index* v, int count, std::vector<Index>& found) {
    double lo[3], hi[3];
    for (Index c = 0; c < 3; ++c) {
        lo[c] = hi[c] = m.vertices[c * m.vertex_count + v[0]];
        for (int j = 1; j < count; ++j) {
            const double x = m.vertices[c * m.vertex_count + v[j]];
            lo[c] = py_min(lo[c], x), hi[c] = py_max(hi[c], x);
        }
    }
    found.clear();
    mesh_triangles_in(m, mesh, lo, hi, found);
    const double* first = nullptr;
    for (const Index t : found) {
        const Index* corners = m.triangles + 3 * t;
        bool holds = true;
        for (int j = 0; j < count; ++j) holds = holds && (corners[0] == v[j] || corners[1] == v[j] || corners[2] == v[j]);
        if (!holds) continue;
        const double* normal = m.face_normals + 3 * t;
        if (first == nullptr) {
            first = normal;
        } else if (first[0] * normal[0] + first[1] * normal[1] + first[2] * normal[2] < FLAT) {
            return false;
        }
    }
    return first != nullptr;
}

}  // namespace

int collider_edge_contact(const Contact& contact, ContactLists& lists, const Physics& phys, Index n,
                          const double* mass, const double* free, const double* model_free, const double* x0,
                          double* x1, double* v1) {
    if (phys.meshes.count == 0 || n == 0) return UNTOUCHED;
    const double reach = 0.5 * phys.thickness;  // the particles' contact distance: the pairs are gathered within it
    bool fresh = true;
    int result = edge_pass(contact, lists, lists.collider_kept, phys, Frame{-1, nullptr}, reach, n, mass, free, x0, x1,
                           v1, fresh);
    if (phys.collider_motion == nullptr) return result;
    lists.collider_moving_kept.resize(static_cast<std::size_t>(phys.collider_count));
    for (Index k = 0; k < phys.collider_count; ++k) {  // each moving mesh in its table frame
        const Frame frame{k, collider_shift(phys, k)};
        if (!collider_moves(phys, k) || !frame.covers(phys, k)) continue;
        std::vector<double>& table = lists.collider_frame;
        table.resize(15 * static_cast<std::size_t>(n));  // q0, q1, w1, then q1 and w1 as they came in
        into_table_frame(phys, k, n, x0, x1, v1, table.data());
        std::copy(table.begin() + 3 * n, table.begin() + 9 * n, table.begin() + 9 * n);
        result |= edge_pass(contact, lists, lists.collider_moving_kept[static_cast<std::size_t>(k)], phys, frame, reach,
                            n, mass, model_free, table.data(), table.data() + 3 * n, table.data() + 6 * n, fresh);
        out_of_table_frame(phys, k, n, table.data(), table.data() + 9 * n, x1, v1);
    }
    return result;
}

namespace {

//: Append to supports the pairs of kept (gathered from frame's colliders, the cloth's start q (3, n) in that
//: frame) nearer at q than within (m) plus ahead (s) times the fastest speed (vel (3, n), m/s) of the pair's
//: cloth particles, as gather_supports's terms (reach: thickness / 2, m).
void add_support_terms(const Contact& contact, ContactLists& lists, ColliderPairList& kept, const Physics& phys,
                       const Frame& frame, Index n, const double* q, const double* vel, double ahead, double reach,
                       double within, Supports& supports) {
    if (!list_holds(kept, phys, n, q, nullptr)) renew_list(contact, lists, kept, phys, frame, n, q, q, reach);
    std::vector<double>& moved = lists.collider_moved;
    moves_from_reference(kept, n, q, moved);
    for (const Pair& pair : kept.pairs) {
        if (pair[P_KIND] == POINT_TRIANGLE && pair[P_POINTS] >= 0) continue;  // a particle: the particles' contact
        double fastest = 0.0;  // m/s
        for (int j = 0; ahead > 0.0 && j < 4; ++j) {
            const Index s = pair[P_POINTS + j];
            if (s < 0) continue;
            fastest = py_max(fastest, std::sqrt(vel[s] * vel[s] + vel[n + s] * vel[n + s] + vel[2 * n + s] * vel[2 * n + s]));
        }
        const double near = within + ahead * fastest;
        if (least_gap(pair, moved, reach) >= near) continue;
        const Motion mo = motion_of(pair, phys.meshes, n, nullptr, nullptr, q, q);
        if (box_gap(mo.kind, mo.x) >= near) continue;
        const Weights w = closest(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        const Vec3 d = combine(w, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        const double length = norm(d);
        if (!(length > 0.0 && length < near)) continue;
        const Index k = pair[P_COLLIDER];
        const Index mesh = static_cast<Index>(phys.colliders[k * COLLIDER_COLUMNS + C_RADIUS]);
        const Index ends[2] = {-1 - pair[mo.kind == POINT_TRIANGLE ? P_POINTS : P_POINTS + 2], -1 - pair[P_POINTS + 3]};
        if (flat_feature(phys.meshes, mesh, ends, mo.kind == POINT_TRIANGLE ? 1 : 2, lists.collider_items)) continue;
        const double side[4] = {w.w0, w.w1, w.w2, w.w3};
        Vec3 part{0.0, 0.0, 0.0};  // the collider's points' weighted sum
        Index slots = 0;
        for (int j = 0; j < 4; ++j) {
            const Index s = pair[P_POINTS + j];
            if (s < 0) {
                part = {part.x + side[j] * mo.x[j].x, part.y + side[j] * mo.x[j].y, part.z + side[j] * mo.x[j].z};
            } else {
                supports.points.push_back(s);
                supports.weights.push_back(side[j]);
                slots += 1;
            }
        }
        for (; slots < SUPPORT_POINTS; ++slots) supports.points.push_back(-1), supports.weights.push_back(0.0);
        supports.table_normal.insert(supports.table_normal.end(), {d.x / length, d.y / length, d.z / length});
        supports.table_part.insert(supports.table_part.end(), {part.x, part.y, part.z});
        supports.collider.push_back(k);
    }
}

}  // namespace

Index gather_supports(const Contact& contact, ContactLists& lists, const Physics& phys, Index n, const double* pos,
                      const double* vel, double within, double ahead, Supports& supports) {
    keep_terms(supports, 0);
    if (phys.meshes.count == 0 || n == 0) return 0;
    const double reach = 0.5 * phys.thickness;
    if (ahead > 0.0) {  // the still meshes' features, in the world (their kept list the edges' pass's)
        add_support_terms(contact, lists, lists.collider_kept, phys, Frame{-1, nullptr}, n, pos, vel, ahead, reach,
                          within, supports);
    }
    if (phys.collider_motion == nullptr) return supports.count();
    lists.collider_moving_kept.resize(static_cast<std::size_t>(phys.collider_count));
    for (Index k = 0; k < phys.collider_count; ++k) {
        const Frame frame{k, collider_shift(phys, k)};
        if (!collider_moves(phys, k) || !frame.covers(phys, k)) continue;
        std::vector<double>& table = lists.collider_frame;  // the cloth's start in the table frame
        table.resize(15 * static_cast<std::size_t>(n));
        double* q = table.data();
        const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
        for (Index i = 0; i < n; ++i) {
            const double a[3] = {pos[i], pos[n + i], pos[2 * n + i]};
            double from[3];
            table_point(frame.shift, centre, a, true, from);
            for (Index c = 0; c < 3; ++c) q[c * n + i] = from[c];
        }
        add_support_terms(contact, lists, lists.collider_moving_kept[static_cast<std::size_t>(k)], phys, frame, n, q,
                          vel, 0.0, reach, within, supports);
    }
    return supports.count();
}

Index hold_on_collider_edges(const Contact& contact, ContactLists& lists, const Physics& phys, Index n, const double* pos,
                             const double* vel, double* free, double* held) {
    if (phys.meshes.count == 0 || n == 0) return 0;
    const double reach = 0.5 * phys.thickness;
    ColliderPairList& kept = lists.collider_kept;  // (a moving mesh's edges hold no particle: its pushes keep them off)
    if (!list_holds(kept, phys, n, pos, nullptr)) {
        renew_list(contact, lists, kept, phys, Frame{-1, nullptr}, n, pos, pos, reach);
    }
    lists.collider_rest.resize(4 * static_cast<std::size_t>(n));
    std::vector<double>& moved = lists.collider_moved;
    moves_from_reference(kept, n, pos, moved);
    Index count = 0;
    for (const Pair& pair : kept.pairs) {
        if (pair[P_KIND] == POINT_TRIANGLE && pair[P_POINTS] >= 0) continue;  // a particle: the particles' contact
        const double resting = (1.0 + RESTING_SLACK) * target_of(pair, reach);
        if (least_gap(pair, moved, reach) > resting) continue;
        const Motion mo = motion_of(pair, phys.meshes, n, nullptr, nullptr, pos, pos);
        if (box_gap(mo.kind, mo.x) > resting) continue;
        const Weights w = closest(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        const Vec3 d = combine(w, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
        const double length = norm(d);
        if (!(length > 0.0 && length <= resting)) continue;
        const double friction = phys.colliders[pair[P_COLLIDER] * COLLIDER_COLUMNS + C_FRICTION];
        const double side[4] = {w.w0, w.w1, w.w2, w.w3};
        for (int k = 0; k < 4; ++k) {
            const Index s = pair[P_POINTS + k];
            if (s < 0 || side[k] == 0.0 || free[s] == 0.0) continue;
            const double sign = side[k] > 0.0 ? 1.0 : -1.0;  // the way a push would move it (settle_pair)
            const double normal[3] = {sign * d.x / length, sign * d.y / length, sign * d.z / length};
            const double v[3] = {vel[s], vel[n + s], vel[2 * n + s]};
            if (!comes_to_rest(v, normal, friction)) continue;
            free[s] = 0.0;
            held[s] = EDGE_HELD;
            double* rest = lists.collider_rest.data() + 4 * static_cast<std::size_t>(s);
            rest[0] = normal[0], rest[1] = normal[1], rest[2] = normal[2], rest[3] = friction;
            count += 1;
        }
    }
    return count;
}

Index release_from_collider_edges(const ContactLists& lists, Index n, const double* force, double* free, double* held,
                                  double cone) {
    Index released = 0;
    for (Index i = 0; i < n; ++i) {
        if (held[i] != EDGE_HELD) continue;
        const double* rest = lists.collider_rest.data() + 4 * static_cast<std::size_t>(i);
        const double f[3] = {force[i], force[n + i], force[2 * n + i]};
        if (!slips(f, rest, cone * rest[3])) continue;
        held[i] = 0.0;
        free[i] = 1.0;
        released += 1;
    }
    return released;
}

double slip_on_collider_edges(const ContactLists& lists, Index n, const double* force, const double* mass,
                              const double* diagonal_blocks, const double* blocks, double h, double limit,
                              double* free, double* held, double* pos, double* vel) {
    double farthest = 0.0;
    for (int pass = 0; pass < 2; ++pass) {  // first: how far each would slide; second: slide them
        for (Index i = 0; i < n; ++i) {
            if (held[i] != EDGE_HELD) continue;
            const double* rest = lists.collider_rest.data() + 4 * static_cast<std::size_t>(i);
            const double f[3] = {force[i], force[n + i], force[2 * n + i]};
            if (!slips(f, rest, rest[3])) continue;
            if (f[0] * rest[0] + f[1] * rest[1] + f[2] * rest[2] > 0.0) return -1.0;  // lifted off its support
            const Slide slide = slide_of(n, i, f, rest, rest[3], mass, diagonal_blocks, blocks);
            if (pass == 0) {
                if (!slide.fits(h, limit, farthest)) return -1.0;
                continue;
            }
            slide.apply(n, i, h, pos, vel);
            held[i] = 0.0;
            free[i] = 1.0;
        }
    }
    return farthest;
}

void collider_edge_history(const ContactLists& lists, Index n, const double* pos, const double* vel, double* prev_pos,
                           double* prev_vel, double h) {
    if (static_cast<Index>(lists.collider_pushed.size()) != n) return;
    for (Index i = 0; i < n; ++i) {
        if (lists.collider_pushed[static_cast<std::size_t>(i)] == 0) continue;
        const double normal[3] = {lists.collider_normals[static_cast<std::size_t>(i)],
                                  lists.collider_normals[static_cast<std::size_t>(n + i)],
                                  lists.collider_normals[static_cast<std::size_t>(2 * n + i)]};
        normal_history(n, i, normal, pos, vel, prev_pos, prev_vel, h);
    }
}

}  // namespace wc
