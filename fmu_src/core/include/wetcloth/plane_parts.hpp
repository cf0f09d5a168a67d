// Pieces the grid's plane preconditioner (plane.cpp) and a mesh's (mesh_plane.cpp) share, and the
// mesh's entry points, which plane.cpp's public functions call for a mesh's Plane.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Whether a Plane is a mesh's: no grid hierarchy but an algebraic one (core.hpp's Algebraic), whose
//: coarsest level's points the band positions order (order (n_c), rank (n_c) each point's position).
inline bool mesh_plane(const Plane& plane) { return plane.grid.level_count == 0; }

//: out[i] = mass_i + t_i^T (D_i + B_i) t_i for the frame's axis c (t1, t2, n); without WITH_SPRINGS
//: D (the springs' part of the diagonal blocks) is left out.
template <bool WITH_SPRINGS>
inline void axis_diagonal(const Plane& plane, Index n, Index c, const double* mass, const double* diagonal_blocks,
                   const double* blocks, double* __restrict out) {
    const double* __restrict t0 = plane.frame + (3 * c) * n;
    const double* __restrict t1 = plane.frame + (3 * c + 1) * n;
    const double* __restrict t2 = plane.frame + (3 * c + 2) * n;
    const double* __restrict d = diagonal_blocks;
    const double* __restrict b = blocks;
    for (Index i = 0; i < n; ++i) {
        double e[6];
        for (Index slot = 0; slot < 6; ++slot) e[slot] = WITH_SPRINGS ? d[slot * n + i] + b[slot * n + i] : b[slot * n + i];
        out[i] = mass[i] + block_quadratic(e, t0[i], t1[i], t2[i]);
    }
}

//: A spring's part of one frame component's system, from its block S = across I + (along - across) u u^T
//: and the component's axes t_i, t_j at its ends: t_i^T S t_i and t_j^T S t_j on the diagonal,
//: -t_i^T S t_j between the ends.
struct Coupling {
    double at_i, at_j, between;
};
inline Coupling spring_coupling(double tix, double tiy, double tiz, double tjx, double tjy, double tjz, double ux,
                                double uy, double uz, double along, double across) {
    const double ti_u = tix * ux + tiy * uy + tiz * uz;
    const double tj_u = tjx * ux + tjy * uy + tjz * uz;
    const double ti_tj = tix * tjx + tiy * tjy + tiz * tjz;
    const double ti_ti = tix * tix + tiy * tiy + tiz * tiz;
    const double tj_tj = tjx * tjx + tjy * tjy + tjz * tjz;
    const double stiff = along - across;
    return {across * ti_ti + stiff * ti_u * ti_u, across * tj_tj + stiff * tj_u * tj_u,
            -(across * ti_tj + stiff * ti_u * tj_u)};
}

//: A mesh's M + scale L / 2 (L the Laplacian of its in-plane springs weighted by `weights` (S),
//: bending left out as on the grid), its coarse levels and coarsest band factors, for both in-plane
//: components: half of every spring's stiffness in each, whatever its direction.  Returns 0, or
//: band_factor's info.
Index mesh_factor(Plane& plane, const Cloth& cloth, const double* mass, double scale, const double* weights);

//: Each particle's frame: n the normal of its triangles (area-weighted), t1, t2 completing it
//: (Duff et al. 2017's basis; the in-plane systems do not depend on their turn about n).
void mesh_follow_cloth(Plane& plane, const Cloth& cloth, const double* pos);

//: set_systems_from_jacobian for a mesh.
Index mesh_systems_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const Work& work);

//: apply for a mesh: held particles (free 0) are zero rows of its cycle's finest level.
void mesh_apply(Plane& plane, Index n, const double* free, const double* r, double* z);

}  // namespace wc
