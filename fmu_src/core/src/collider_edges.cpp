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
#include <limits>

#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/colliders.hpp"
#include "wetcloth/self_contact/geometry.hpp"
#include "wetcloth/self_contact/response.hpp"

namespace wc {

namespace {

using namespace self_contact;

//: Columns of a pair in ContactLists::collider_pairs: its kind, its four points (a cloth particle i >= 0,
//: a collider vertex v as -1 - v), its collider.
enum PairColumn : Index { P_KIND = 0, P_POINTS = 1, P_COLLIDER = 5, PAIR_COLUMNS = 6 };

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

using Pair = std::array<Index, PAIR_COLUMNS>;
static_assert(std::tuple_size<Pair>::value == 6, "ContactLists::collider_pairs rows");

//: The pairs of the cloth's elements of `width` particles (rows of `elements`, nullptr: the particles) with the
//: features of mesh collider k's triangles whose boxes reach the elements' path boxes grown by pad.
void gather(const Index* elements, Index count, int width, Index k, Index mesh, const ColliderMeshes& m, Index n,
            const double* x0, const double* x1, double pad, std::vector<Index>& near, std::vector<Pair>& pairs) {
    for (Index e = 0; e < count; ++e) {
        const Index* idx = elements ? elements + e * width : &e;
        const Box box = path_box(idx, width, n, x0, x1, pad);
        near.clear();
        mesh_triangles_in(m, mesh, box.lo, box.hi, near);
        if (near.empty()) continue;
        std::sort(near.begin(), near.end());
        near.erase(std::unique(near.begin(), near.end()), near.end());
        for (const Index t : near) {
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
                if (overlap)
                    pairs.push_back({POINT_TRIANGLE, idx[0], vertex_slot(v[0]), vertex_slot(v[1]), vertex_slot(v[2]), k});
            } else if (width == 2) {  // the edge and each of the triangle's edges
                for (int j = 0; j < 3; ++j) {
                    if (!box.meets(p[j], p[(j + 1) % 3])) continue;
                    const Index a = std::min(v[j], v[(j + 1) % 3]), b = std::max(v[j], v[(j + 1) % 3]);
                    pairs.push_back({EDGE_EDGE, idx[0], idx[1], vertex_slot(a), vertex_slot(b), k});
                }
            } else {  // each of the triangle's corners and the cloth triangle
                for (int j = 0; j < 3; ++j) {
                    if (box.holds(p[j])) pairs.push_back({POINT_TRIANGLE, vertex_slot(v[j]), idx[0], idx[1], idx[2], k});
                }
            }
        }
    }
}

//: A pair's start points, motions over the step and inverse masses.
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
        mo.inverse.m[k] = s >= 0 ? free[s] / mass[s] : 0.0;
    }
    return mo;
}

//: When along the step the pair must be treated (time_of_contact), or CLEAR; `near` whether its motion
//: can bring it within `gap` (m) at all.
double contact_when(const Motion& mo, double start, double gap, bool& near) {
    near = start - motion_bound(mo.kind, mo.p[0], mo.p[1], mo.p[2], mo.p[3]) < gap;
    if (!near) return CLEAR;
    const double minimum = py_min(SAFE_FRACTION * gap, 0.5 * start);
    return time_of_contact(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3], mo.p[0], mo.p[1], mo.p[2], mo.p[3], start,
                           minimum);
}

//: Treat one pair if it needs it (as self-collision's settle_pair, at distance gap); returns whether it did.
bool settle_pair(const Pair& pair, double start, const Physics& phys, double gap, Index n, const double* mass,
                 const double* free, const double* x0, double* x1, double* v1) {
    const Motion mo = motion_of(pair, phys.meshes, n, mass, free, x0, x1);
    if (mo.inverse.sum() == 0.0) return false;
    bool near = false;
    const double when = contact_when(mo, start, gap, near);
    if (!near) return false;
    const double t = when == CLEAR ? 1.0 : when;
    Vec3 q[4];
    for (int k = 0; k < 4; ++k) q[k] = along(mo.x[k], t, mo.p[k]);
    const Weights w = closest(mo.kind, q[0], q[1], q[2], q[3]);
    const Vec3 d = combine(w, q[0], q[1], q[2], q[3]);
    const double length = norm(d);
    if (when == CLEAR && length >= (1.0 - SLACK) * gap) return false;
    if (!(length > 0.0)) return false;  // no side to push to: left to the last resort
    const Vec3 normal = {d.x / length, d.y / length, d.z / length};
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
    for (int k = 0; k < 4; ++k) {
        const Index s = pair[P_POINTS + k];
        if (s < 0) continue;
        for (Index c = 0; c < 3; ++c) x1[c * n + s] = x[4 * c + k], v1[c * n + s] = v[4 * c + k];
    }
    return true;
}

}  // namespace

bool collider_edge_contact(const Contact& contact, ContactLists& lists, const Physics& phys, Index n,
                           const double* mass, const double* free, const double* x0, double* x1, double* v1) {
    if (phys.meshes.count == 0 || n == 0) return false;
    const double gap = 0.5 * phys.thickness;
    std::vector<Pair>& pairs = lists.collider_pairs;
    pairs.clear();
    const Box cloth = path_box(nullptr, n, n, x0, x1, gap);  // a mesh it does not reach costs this pass
    for (Index k = 0; k < phys.collider_count; ++k) {
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        if (static_cast<Index>(row[C_SHAPE]) != MESH) continue;
        const Index mesh = static_cast<Index>(row[C_RADIUS]);
        const double* header = phys.meshes.headers + mesh * MESH_COLUMNS;
        bool reached = true;
        for (Index c = 0; c < 3; ++c)
            reached = reached && cloth.hi[c] >= header[M_LO_X + c] && cloth.lo[c] <= header[M_HI_X + c];
        if (!reached) continue;
        gather(nullptr, n, 1, k, mesh, phys.meshes, n, x0, x1, gap, lists.collider_items, pairs);
        gather(contact.edges, contact.edge_count, 2, k, mesh, phys.meshes, n, x0, x1, gap, lists.collider_items, pairs);
        gather(contact.triangles, contact.triangle_count, 3, k, mesh, phys.meshes, n, x0, x1, gap,
               lists.collider_items, pairs);
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    if (pairs.empty()) return false;
    std::vector<double>& start = lists.collider_start;
    start.resize(pairs.size());
    for (std::size_t j = 0; j < pairs.size(); ++j) {
        const Motion mo = motion_of(pairs[j], phys.meshes, n, mass, free, x0, x1);
        start[j] = distance(mo.kind, mo.x[0], mo.x[1], mo.x[2], mo.x[3]);
    }
    bool changed = false;
    for (int pass = 0; pass < PASSES_MAX; ++pass) {
        Index treated = 0;
        for (std::size_t j = 0; j < pairs.size(); ++j)
            treated += settle_pair(pairs[j], start[j], phys, gap, n, mass, free, x0, x1, v1);
        changed = changed || treated > 0;
        if (treated == 0) break;
    }
    // The last resort: the particles of a pair whose motion is still not shown safe stay where they started.
    std::vector<Index>& stopped = lists.collider_items;
    stopped.assign(static_cast<std::size_t>(n), 0);
    for (Index round = 0; round < n; ++round) {
        Index unsafe = 0;
        for (std::size_t j = 0; j < pairs.size(); ++j) {
            const Pair& pair = pairs[j];
            bool movable = false;
            for (int k = 0; k < 4; ++k) {
                const Index s = pair[P_POINTS + k];
                movable = movable || (s >= 0 && free[s] != 0.0 && stopped[static_cast<std::size_t>(s)] == 0);
            }
            if (!movable) continue;
            bool near = false;
            const Motion mo = motion_of(pair, phys.meshes, n, mass, free, x0, x1);
            if (contact_when(mo, start[j], gap, near) == CLEAR) continue;
            unsafe += 1;
            for (int k = 0; k < 4; ++k) {
                const Index s = pair[P_POINTS + k];
                if (s < 0 || free[s] == 0.0) continue;
                stopped[static_cast<std::size_t>(s)] = 1;
                for (Index c = 0; c < 3; ++c) x1[c * n + s] = x0[c * n + s], v1[c * n + s] = 0.0;
            }
        }
        if (unsafe == 0) break;
        changed = true;
    }
    return changed;
}

}  // namespace wc
