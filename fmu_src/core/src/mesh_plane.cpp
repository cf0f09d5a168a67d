// The plane preconditioner on a mesh (wetcloth/plane_parts.hpp): the same three components in each
// particle's frame as on a grid (plane.cpp), each a scalar system over the mesh's tension-only springs,
// stored as band matrices in the order that narrows their band (reverse Cuthill-McKee, computed when
// the cloth is built), factored by band.cpp.
#include <cmath>
#include <vector>

#include "wetcloth/band.hpp"
#include "wetcloth/plane.hpp"
#include "wetcloth/plane_parts.hpp"

namespace wc {
namespace {

//: Band storage of component c: row p holds entries (p, p) .. (p, p + kd) of the band order.
inline double* band_of(Plane& plane, Index c) { return plane.bands + c * plane.coarse_n * (plane.kd + 1); }
inline double* rows_of(Plane& plane, Index c) { return plane.rows + c * plane.coarse_n * (plane.kd + 1); }

//: Component c's band zeroed, diagonal (n) on its diagonal.
void diagonal_band(Plane& plane, Index n, Index c, const double* diagonal) {
    const Index width = plane.kd + 1;
    double* band = band_of(plane, c);
    for (Index e = 0; e < n * width; ++e) band[e] = 0.0;
    for (Index i = 0; i < n; ++i) band[plane.rank[i] * width] = diagonal[i];
}

//: Add value to entry (i, j) of component c's band, i != j particles.
inline void add_between(Plane& plane, Index c, Index i, Index j, double value) {
    const Index p = plane.rank[i], q = plane.rank[j];
    const Index lo = p < q ? p : q, hi = p < q ? q : p;
    band_of(plane, c)[lo * (plane.kd + 1) + hi - lo] += value;
}

inline void add_diagonal(Plane& plane, Index c, Index i, double value) {
    band_of(plane, c)[plane.rank[i] * (plane.kd + 1)] += value;
}

//: Factor component c's band; returns band_factor's info.
Index factor_band(Plane& plane, Index c) {
    return band_factor(band_of(plane, c), rows_of(plane, c), plane.coarse_n, plane.kd);
}

}  // namespace

Index mesh_factor(Plane& plane, const Cloth& cloth, const double* mass, double scale, const double* weights) {
    const Index n = cloth.n, count = cloth.pair_count, width = plane.kd + 1;
    diagonal_band(plane, n, 0, mass);
    for (Index k = 0; k < cloth.pair_tension_count; ++k) {
        const double w = 0.5 * scale * weights[k];
        const Index i = cloth.pairs[k], j = cloth.pairs[count + k];
        add_diagonal(plane, 0, i, w);
        add_diagonal(plane, 0, j, w);
        add_between(plane, 0, i, j, -w);
    }
    const Index info = factor_band(plane, 0);
    if (info != 0) return info;
    for (Index e = 0; e < n * width; ++e) {  // t2's system is t1's
        band_of(plane, 1)[e] = band_of(plane, 0)[e];
        rows_of(plane, 1)[e] = rows_of(plane, 0)[e];
    }
    return 0;
}

void mesh_follow_cloth(Plane& plane, const Cloth& cloth, const double* pos) {
    const Index n = cloth.n;
    double* frame = plane.frame;  // frame[(3 r + c) n + i]
    double* normal = frame + 6 * n;
    for (Index e = 0; e < 3 * n; ++e) normal[e] = 0.0;
    for (Index t = 0; t < cloth.triangle_count; ++t) {
        const Index* v = cloth.triangles + 3 * t;
        double e1[3], e2[3];
        for (Index c = 0; c < 3; ++c) {
            e1[c] = pos[c * n + v[1]] - pos[c * n + v[0]];
            e2[c] = pos[c * n + v[2]] - pos[c * n + v[0]];
        }
        const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
        for (Index corner = 0; corner < 3; ++corner)
            for (Index c = 0; c < 3; ++c) normal[c * n + v[corner]] += cross[c];
    }
    for (Index i = 0; i < n; ++i) {
        double x = normal[i], y = normal[n + i], z = normal[2 * n + i];
        const double length = std::sqrt(x * x + y * y + z * z);
        if (length > 0.0) {
            x /= length, y /= length, z /= length;
        } else {  // crumpled past telling: the axes
            x = 0.0, y = 0.0, z = 1.0;
        }
        normal[i] = x, normal[n + i] = y, normal[2 * n + i] = z;
        const double sign = std::copysign(1.0, z);
        const double a = -1.0 / (sign + z), b = x * y * a;
        frame[i] = 1.0 + sign * x * x * a, frame[n + i] = sign * b, frame[2 * n + i] = -sign * x;
        frame[3 * n + i] = b, frame[4 * n + i] = sign + y * y * a, frame[5 * n + i] = -y;
    }
}

Index mesh_systems_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const Work& work) {
    const Index n = cloth.n, count = cloth.pair_count;
    plane.reference[1] = plane.reference[2] = 0.0;  // the rest-stiffness factors are overwritten
    plane.reference[3] = 1.0;
    Index result = 1;
    std::vector<double> in_plane(static_cast<std::size_t>(n));
    const double* u = work.pair_direction;
    for (Index c = 0; c < COMPONENTS; ++c) {
        double* diagonal = c == NORMAL ? plane.normal : in_plane.data();
        axis_diagonal<false>(plane, n, c, mass, nullptr, work.blocks, diagonal);
        diagonal_band(plane, n, c, diagonal);
        const double* t = plane.frame + 3 * c * n;
        for (Index k = 0; k < cloth.pair_tension_count; ++k) {  // bending left out whole, as on a grid
            const Index i = cloth.pairs[k], j = cloth.pairs[count + k];
            const double along = work.pair_along[k], across = work.pair_across[k];
            if (along == 0.0 && across == 0.0) continue;
            const Coupling s = spring_coupling(t[i], t[n + i], t[2 * n + i], t[j], t[n + j], t[2 * n + j], u[k],
                                               u[count + k], u[2 * count + k], along, across);
            add_diagonal(plane, c, i, s.at_i);
            add_diagonal(plane, c, j, s.at_j);
            if (cloth.free[i] != 0.0 && cloth.free[j] != 0.0) add_between(plane, c, i, j, s.between);
        }
        if (factor_band(plane, c) == 0) continue;
        diagonal_band(plane, n, c, diagonal);  // not positive definite (round-off on a crumpled cloth)
        if (factor_band(plane, c) != 0) result = -1;
    }
    return result;
}

void mesh_apply(Plane& plane, Index n, const double* free, const double* r, double* z) {
    const double* f = plane.frame;
    double* local = plane.local;  // (3, n) in band order
    const bool normal_system = plane.reference[3] != 0.0;
    for (Index i = 0; i < n; ++i) {
        const Index p = plane.rank[i];
        for (Index c = 0; c < COMPONENTS; ++c)
            local[c * n + p] = f[3 * c * n + i] * r[i] + f[(3 * c + 1) * n + i] * r[n + i] + f[(3 * c + 2) * n + i] * r[2 * n + i];
        if (!normal_system) local[NORMAL * n + p] /= plane.normal[i];
    }
    band_solve_two(plane.bands, plane.rows, local, n, plane.kd);
    if (normal_system) band_solve_one(band_of(plane, NORMAL), rows_of(plane, NORMAL), local + NORMAL * n, n, plane.kd);
    for (Index i = 0; i < n; ++i) {
        const Index p = plane.rank[i];
        const double x0 = local[p], x1 = local[n + p], x2 = local[2 * n + p];
        for (Index c = 0; c < 3; ++c) z[c * n + i] = free[i] * (f[c * n + i] * x0 + f[(3 + c) * n + i] * x1 + f[(6 + c) * n + i] * x2);
    }
}

}  // namespace wc
