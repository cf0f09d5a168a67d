// A mesh's listed springs (wetcloth/listed_springs.hpp): one loop over the springs, each gathering its
// ends' positions and velocities and scattering its force and blocks back to them.
#include "wetcloth/listed_springs.hpp"

#include "wetcloth/spring_law.hpp"

namespace wc {
namespace {

using namespace spring_law;

//: The ends (i, j) of listed spring k.
struct Ends {
    Index i, j;
};
inline Ends ends(const Cloth& cloth, Index k) { return {cloth.pairs[k], cloth.pairs[cloth.pair_count + k]}; }

//: Spring k's geometry from pos (3, n) and the saturations.
inline Geometry geometry(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                         Index k, Ends e) {
    const Index n = cloth.n;
    return spring_geometry(pos[e.i], pos[n + e.i], pos[2 * n + e.i], pos[e.j], pos[n + e.j], pos[2 * n + e.j],
                           cloth.pair_stiffness[k], saturation[e.i], saturation[e.j], phys.wet_factor);
}

//: out[i] += a, out[j] -= a for each row of out (3, n).
inline void add_to_ends(Index n, Ends e, double ax, double ay, double az, double* out) {
    out[e.i] += ax;
    out[n + e.i] += ay;
    out[2 * n + e.i] += az;
    out[e.j] -= ax;
    out[n + e.j] -= ay;
    out[2 * n + e.j] -= az;
}

//: Spring k's force on its first end: t (x_i - x_j), minus c (v_i - v_j) for the thesis damping.
inline void add_force(const Cloth& cloth, const Physics& phys, const double* vel, Index k, Ends e, const Geometry& g,
                      double t, double* force) {
    const Index n = cloth.n;
    double fx = t * g.dx, fy = t * g.dy, fz = t * g.dz;
    if (!phys.projected) {
        const double c = cloth.pair_damping[k];
        fx -= c * (vel[e.i] - vel[e.j]);
        fy -= c * (vel[n + e.i] - vel[n + e.j]);
        fz -= c * (vel[2 * n + e.i] - vel[2 * n + e.j]);
    }
    add_to_ends(n, e, fx, fy, fz, force);
}

template <Law L>
void forces_of(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
               const double* vel, Index first, Index last, double* force) {
    const Index n = cloth.n;
    const double damp = phys.projected ? 1.0 : 0.0;
    for (Index k = first; k < last; ++k) {
        const Ends e = ends(cloth, k);
        const Geometry g = geometry(cloth, phys, saturation, pos, k, e);
        const double rate = (vel[e.i] - vel[e.j]) * g.dx + (vel[n + e.i] - vel[n + e.j]) * g.dy +
                            (vel[2 * n + e.i] - vel[2 * n + e.j]) * g.dz;
        const double l0 = cloth.pair_rest[k];
        add_force(cloth, phys, vel, k, e, g, tension<L>(g, l0, TENSION_ROUNDING * l0, damp, cloth.pair_damping[k], rate),
                  force);
    }
}

template <Law L>
void blocks_of(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos, const double* vel,
               double h, double slack_slope, Index first, Index last, Work& work) {
    const Index n = cloth.n, count = cloth.pair_count;
    double* d = work.diagonal_blocks;
    for (Index k = first; k < last; ++k) {
        const Ends e = ends(cloth, k);
        const Geometry g = geometry(cloth, phys, saturation, pos, k, e);
        const double dvx = vel[e.i] - vel[e.j], dvy = vel[n + e.i] - vel[n + e.j];
        const double dvz = vel[2 * n + e.i] - vel[2 * n + e.j];
        const double l0 = cloth.pair_rest[k], cf = cloth.pair_damping[k];
        const Coefficients c =
            spring_law::coefficients<L>(g, l0, TENSION_ROUNDING * l0, phys.projected, h, slack_slope, cf, dvx, dvy, dvz);
        work.pair_direction[k] = c.ux;
        work.pair_direction[count + k] = c.uy;
        work.pair_direction[2 * count + k] = c.uz;
        work.pair_along[k] = c.along;
        work.pair_across[k] = c.across;
        add_force(cloth, phys, vel, k, e, g, c.t, work.force);
        const Block b = spring_block(c.along, c.across, c.ux, c.uy, c.uz);
        const double slots[6] = {b.xx, b.yy, b.zz, b.xy, b.xz, b.yz};
        for (Index s = 0; s < 6; ++s) {
            d[s * n + e.i] += slots[s];
            d[s * n + e.j] += slots[s];
        }
    }
}

}  // namespace

void listed_spring_forces(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                          const double* vel, double* force) {
    forces_of<Law::CLAMPED>(cloth, phys, saturation, pos, vel, 0, cloth.pair_tension_count, force);
    forces_of<Law::BOTH_WAYS>(cloth, phys, saturation, pos, vel, cloth.pair_tension_count, cloth.pair_count, force);
}

void listed_spring_forces_and_blocks(const Cloth& cloth, const Physics& phys, const double* saturation,
                                     const double* pos, const double* vel, double h, double slack_slope, Work& work) {
    blocks_of<Law::CLAMPED>(cloth, phys, saturation, pos, vel, h, slack_slope, 0, cloth.pair_tension_count, work);
    blocks_of<Law::BOTH_WAYS>(cloth, phys, saturation, pos, vel, h, slack_slope, cloth.pair_tension_count,
                              cloth.pair_count, work);
}

void listed_spring_matvec(const Cloth& cloth, const Work& work, const double* p, double* out) {
    const Index n = cloth.n, count = cloth.pair_count;
    const double* ux = work.pair_direction;
    const double* uy = ux + count;
    const double* uz = uy + count;
    for (Index k = 0; k < count; ++k) {
        const Ends e = ends(cloth, k);
        const double dx = p[e.i] - p[e.j], dy = p[n + e.i] - p[n + e.j], dz = p[2 * n + e.i] - p[2 * n + e.j];
        const double across = work.pair_across[k];
        const double proj = (work.pair_along[k] - across) * (ux[k] * dx + uy[k] * dy + uz[k] * dz);
        add_to_ends(n, e, across * dx + proj * ux[k], across * dy + proj * uy[k], across * dz + proj * uz[k], out);
    }
}

}  // namespace wc
