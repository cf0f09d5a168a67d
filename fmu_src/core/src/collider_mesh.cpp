// Mesh colliders' geometry (wetcloth/collider_mesh.hpp): nearest triangles and segment crossings,
// through each mesh's uniform grid of cells.
#include "wetcloth/collider_mesh.hpp"

#include <algorithm>
#include <cmath>

namespace wc {
namespace {

struct V3 {
    double x, y, z;
};
inline V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 add(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 scale(V3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

inline V3 vertex(const ColliderMeshes& m, Index v) {
    return {m.vertices[v], m.vertices[m.vertex_count + v], m.vertices[2 * m.vertex_count + v]};
}
inline V3 row3(const double* a, Index k) { return {a[3 * k], a[3 * k + 1], a[3 * k + 2]}; }

//: The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5) and its
//: feature: 0 the face, 1..3 the edge from corner (f - 1) to f, 4..6 the vertex f - 4.
struct Closest {
    V3 point;
    int feature;
};
Closest closest_on_triangle(V3 p, V3 a, V3 b, V3 c) {
    const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return {a, 4};
    const V3 bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return {b, 5};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {add(a, scale(ab, d1 / (d1 - d3))), 1};
    const V3 cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return {c, 6};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {add(a, scale(ac, d2 / (d2 - d6))), 3};
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return {add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))), 2};
    const double denom = 1.0 / (va + vb + vc);
    return {add(a, add(scale(ab, vb * denom), scale(ac, vc * denom))), 0};
}

//: The cells of mesh `mesh` that the box [lo, hi] overlaps, as index ranges (false if none).
struct CellRange {
    Index lo[3], hi[3];
};
bool cells_of(const double* header, const double* lo, const double* hi, CellRange& r) {
    for (Index c = 0; c < 3; ++c) {
        if (hi[c] < header[M_LO_X + c] || lo[c] > header[M_HI_X + c]) return false;
        const double origin = header[M_ORIGIN_X + c], side = header[M_CELL];
        const Index last = static_cast<Index>(header[M_CELLS_X + c]) - 1;
        r.lo[c] = std::clamp<Index>(static_cast<Index>(std::floor((lo[c] - origin) / side)), 0, last);
        r.hi[c] = std::clamp<Index>(static_cast<Index>(std::floor((hi[c] - origin) / side)), 0, last);
    }
    return true;
}

//: Calls stop(from, to) for each row of cells of range r, its cells numbered from..to (inclusive, consecutive:
//: their lists lie together in cell_items), until stop returns true; returns whether one did.
template <class Stop>
bool any_row(const double* header, const CellRange& r, Stop&& stop) {
    const Index nx = static_cast<Index>(header[M_CELLS_X]), ny = static_cast<Index>(header[M_CELLS_Y]);
    const Index first = static_cast<Index>(header[M_FIRST_CELL]);
    for (Index z = r.lo[2]; z <= r.hi[2]; ++z)
        for (Index y = r.lo[1]; y <= r.hi[1]; ++y) {
            const Index row = first + (z * ny + y) * nx;
            if (stop(row + r.lo[0], row + r.hi[0])) return true;
        }
    return false;
}

//: Calls visit(t) for every triangle listed in the cells of range r (a triangle in several cells more than once).
template <class Visit>
void for_each_triangle(const ColliderMeshes& m, const double* header, const CellRange& r, Visit&& visit) {
    any_row(header, r, [&](Index from, Index to) {
        for (Index k = m.cell_start[from]; k < m.cell_start[to + 1]; ++k) visit(m.cell_items[k]);
        return false;
    });
}

//: The pseudo-normal of triangle t's feature (Baerentzen and Aanaes 2005): its face's, an edge's, a vertex's.
V3 pseudo_normal(const ColliderMeshes& m, Index t, int feature) {
    if (feature == 0) return row3(m.face_normals, t);
    if (feature <= 3) return row3(m.edge_normals, 3 * t + (feature - 1));
    return row3(m.vertex_normals, m.triangles[3 * t + (feature - 4)]);
}

}  // namespace

double mesh_distance(const ColliderMeshes& m, Index mesh, const double* p, double reach, double* normal) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    const double lo[3] = {p[0] - reach, p[1] - reach, p[2] - reach}, hi[3] = {p[0] + reach, p[1] + reach, p[2] + reach};
    CellRange r;
    if (!cells_of(header, lo, hi, r)) return reach;
    const V3 q = {p[0], p[1], p[2]};
    double best = reach * reach;
    Index best_t = -1;
    Closest best_c{};
    for_each_triangle(m, header, r, [&](Index t) {
        const Index* v = m.triangles + 3 * t;
        const Closest c = closest_on_triangle(q, vertex(m, v[0]), vertex(m, v[1]), vertex(m, v[2]));
        const V3 d = sub(q, c.point);
        const double d2 = dot(d, d);
        if (d2 < best) {
            best = d2;
            best_t = t;
            best_c = c;
        }
    });
    if (best_t < 0) return reach;
    const double dist = std::sqrt(best);
    const V3 feature = pseudo_normal(m, best_t, best_c.feature);
    const V3 away = sub(q, best_c.point);
    const double side = header[M_SOLID] != 0.0 && dot(away, feature) < 0.0 ? -1.0 : 1.0;  // inside a solid
    V3 n = dist > 0.0 ? scale(away, side / dist) : feature;
    const double length = std::sqrt(dot(n, n));
    n = scale(n, 1.0 / length);
    normal[0] = n.x, normal[1] = n.y, normal[2] = n.z;
    return side * dist;
}

bool mesh_crossing(const ColliderMeshes& m, Index mesh, const double* a, const double* b, double* hit,
                   double* normal) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    double lo[3], hi[3];
    for (Index c = 0; c < 3; ++c) lo[c] = std::min(a[c], b[c]), hi[c] = std::max(a[c], b[c]);
    CellRange r;
    if (!cells_of(header, lo, hi, r)) return false;
    const V3 start = {a[0], a[1], a[2]}, along = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double first = 2.0;
    Index first_t = -1;
    for_each_triangle(m, header, r, [&](Index t) {  // Moller-Trumbore, the segment's parameter in [0, 1]
        const Index* v = m.triangles + 3 * t;
        const V3 p0 = vertex(m, v[0]), e1 = sub(vertex(m, v[1]), p0), e2 = sub(vertex(m, v[2]), p0);
        const V3 h = cross(along, e2);
        const double det = dot(e1, h);
        if (det == 0.0) return;  // the segment lies in the triangle's plane (or has no length)
        const double inv = 1.0 / det;
        const V3 s = sub(start, p0);
        const double u = inv * dot(s, h);
        if (u < 0.0 || u > 1.0) return;
        const V3 q = cross(s, e1);
        const double w = inv * dot(along, q);
        if (w < 0.0 || u + w > 1.0) return;
        const double t_hit = inv * dot(e2, q);
        if (t_hit >= 0.0 && t_hit <= 1.0 && t_hit < first) {
            first = t_hit;
            first_t = t;
        }
    });
    if (first_t < 0) return false;
    const V3 point = add(start, scale(along, first));
    V3 n = row3(m.face_normals, first_t);
    if (dot(sub(start, point), n) < 0.0) n = scale(n, -1.0);
    hit[0] = point.x, hit[1] = point.y, hit[2] = point.z;
    normal[0] = n.x, normal[1] = n.y, normal[2] = n.z;
    return true;
}

void mesh_triangles_in(const ColliderMeshes& m, Index mesh, const double* lo, const double* hi,
                       std::vector<Index>& out) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    CellRange r;
    if (cells_of(header, lo, hi, r)) for_each_triangle(m, header, r, [&](Index t) { out.push_back(t); });
}

bool mesh_lists_triangles_in(const ColliderMeshes& m, Index mesh, const double* lo, const double* hi) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    CellRange r;
    return cells_of(header, lo, hi, r) &&
           any_row(header, r, [&](Index from, Index to) { return m.cell_start[to + 1] > m.cell_start[from]; });
}

void mesh_vertex_cells(const ColliderMeshes& m, Index mesh, std::vector<std::pair<Index, Index>>& out) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    const Index nx = static_cast<Index>(header[M_CELLS_X]), ny = static_cast<Index>(header[M_CELLS_Y]);
    const Index first = static_cast<Index>(header[M_FIRST_CELL]);
    const Index cells = nx * ny * static_cast<Index>(header[M_CELLS_Z]);
    std::vector<char> seen(static_cast<std::size_t>(m.vertex_count), 0);
    out.clear();
    for (Index k = m.cell_start[first]; k < m.cell_start[first + cells]; ++k) {  // the mesh's triangles
        const Index* corners = m.triangles + 3 * m.cell_items[k];
        for (int j = 0; j < 3; ++j) {
            const Index v = corners[j];
            if (seen[static_cast<std::size_t>(v)] != 0) continue;
            seen[static_cast<std::size_t>(v)] = 1;
            const double p[3] = {m.vertices[v], m.vertices[m.vertex_count + v], m.vertices[2 * m.vertex_count + v]};
            CellRange r{};
            cells_of(header, p, p, r);  // (inside the mesh's box: a vertex is)
            out.emplace_back(first + (r.lo[2] * ny + r.lo[1]) * nx + r.lo[0], v);
        }
    }
    std::sort(out.begin(), out.end());
}

void mesh_vertices_in(const ColliderMeshes& m, Index mesh, const std::vector<std::pair<Index, Index>>& cells,
                      const double* lo, const double* hi, std::vector<Index>& out) {
    const double* header = m.headers + mesh * MESH_COLUMNS;
    CellRange r;
    if (!cells_of(header, lo, hi, r)) return;
    any_row(header, r, [&](Index from, Index to) {
        auto k = std::lower_bound(cells.begin(), cells.end(), std::pair<Index, Index>{from, -1});
        for (; k != cells.end() && k->first <= to; ++k) out.push_back(k->second);
        return false;
    });
}

}  // namespace wc
