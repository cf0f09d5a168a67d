// A mesh's listed springs (wetcloth/listed_springs.hpp): the springs in chunks, each gathering its
// springs' ends' positions and velocities from their records, running the law over them in one loop
// that vectorises, and scattering forces and blocks to the ends' sums; the product gathers and scatters
// spring by spring.
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

//: out[i] += a, out[j] -= a for each row of out (3, n).
inline void add_to_ends(Index n, Ends e, double ax, double ay, double az, double* out) {
    out[e.i] += ax;
    out[n + e.i] += ay;
    out[2 * n + e.i] += az;
    out[e.j] -= ax;
    out[n + e.j] -= ay;
    out[2 * n + e.j] -= az;
}

//: Springs taken at a time: their ends' values gathered into rows so that the law's loop vectorises
//: over them as over a grid's family, then the results scattered to the ends in the springs' order.
constexpr Index CHUNK = 128;

//: The ends' positions, velocities and saturations of CHUNK springs (rows: x, y, z, vx, vy, vz of
//: end i, the same of end j, then s_i, s_j), and what the law gives back: force (3) and block (6).
struct Chunk {
    double x[6][CHUNK];  // x_i, y_i, z_i, x_j, y_j, z_j
    double v[6][CHUNK];
    double s[2][CHUNK];
    double force[3][CHUNK];
    double block[6][CHUNK];
};

//: Gather springs first .. first + count into the chunk's input rows from the ends' state records.
void gather(const Cloth& cloth, const double* state, Index first, Index count, Chunk& c) {
    for (Index k = 0; k < count; ++k) {
        const Ends e = ends(cloth, first + k);
        const double* a = state + STATE_SLOTS * e.i;
        const double* b = state + STATE_SLOTS * e.j;
        for (Index r = 0; r < 3; ++r) {
            c.x[r][k] = a[STATE_X + r];
            c.x[3 + r][k] = b[STATE_X + r];
            c.v[r][k] = a[STATE_V + r];
            c.v[3 + r][k] = b[STATE_V + r];
        }
        c.s[0][k] = a[STATE_SATURATION];
        c.s[1][k] = b[STATE_SATURATION];
    }
}

//: Spring k's tension force on its first end, t (x_i - x_j), into the chunk's force rows.
inline void chunk_force(Chunk& c, Index k, const Geometry& g, double t) {
    c.force[0][k] = t * g.dx;
    c.force[1][k] = t * g.dy;
    c.force[2][k] = t * g.dz;
}

inline Geometry chunk_geometry(const Chunk& c, Index k, double kf, double wet_factor) {
    return spring_geometry(c.x[0][k], c.x[1][k], c.x[2][k], c.x[3][k], c.x[4][k], c.x[5][k], kf, c.s[0][k], c.s[1][k],
                           wet_factor);
}

//: Add the chunk's forces of its count springs, from spring first on, to their ends' sums, less the
//: thesis damping c (v_i - v_j) unless the damping is projected.
void scatter_forces(const Cloth& cloth, bool projected, const Chunk& c, Index first, Index count,
                    const MeshRecords& records) {
    for (Index k = 0; k < count; ++k) {
        const Ends e = ends(cloth, first + k);
        double fx = c.force[0][k], fy = c.force[1][k], fz = c.force[2][k];
        if (!projected) {
            const double cf = cloth.pair_damping[first + k];
            fx -= cf * (c.v[0][k] - c.v[3][k]);
            fy -= cf * (c.v[1][k] - c.v[4][k]);
            fz -= cf * (c.v[2][k] - c.v[5][k]);
        }
        double* a = records.sums + records.stride * e.i + SUM_FORCE;
        double* b = records.sums + records.stride * e.j + SUM_FORCE;
        a[0] += fx;
        a[1] += fy;
        a[2] += fz;
        b[0] -= fx;
        b[1] -= fy;
        b[2] -= fz;
    }
}

template <Law L>
void forces_of(const Cloth& cloth, const Physics& phys, bool projected, const MeshRecords& records, Index first,
               Index last) {
    const double damp = projected ? 1.0 : 0.0, wet_factor = phys.wet_factor;
    Chunk c;
    for (Index start = first; start < last; start += CHUNK) {
        const Index count = last - start < CHUNK ? last - start : CHUNK;
        gather(cloth, records.state, start, count, c);
        const double* __restrict rest = cloth.pair_rest + start;
        const double* __restrict damping = cloth.pair_damping + start;
        const double* __restrict stiffness = cloth.pair_stiffness + start;
        for (Index k = 0; k < count; ++k) {
            const Geometry g = chunk_geometry(c, k, stiffness[k], wet_factor);
            const double rate = (c.v[0][k] - c.v[3][k]) * g.dx + (c.v[1][k] - c.v[4][k]) * g.dy +
                                (c.v[2][k] - c.v[5][k]) * g.dz;
            const double l0 = rest[k];
            chunk_force(c, k, g, tension<L>(g, l0, TENSION_ROUNDING * l0, damp, damping[k], rate));
        }
        scatter_forces(cloth, projected, c, start, count, records);
    }
}

//: The law over a chunk's count springs (rest length, damping, stiffness from their first on): their
//: coefficients into ux .. across, forces and blocks into the chunk's rows.  Every array a __restrict
//: parameter, so the loop vectorises (GCC ignores __restrict on locals).
template <Law L>
void coefficients_loop(Index count, double wet_factor, bool projected, double h, double slack_slope,
                       const double* __restrict rest, const double* __restrict damping,
                       const double* __restrict stiffness, Chunk* __restrict c, double* __restrict ux,
                       double* __restrict uy, double* __restrict uz, double* __restrict along,
                       double* __restrict across) {
    for (Index k = 0; k < count; ++k) {
        const Geometry g = chunk_geometry(*c, k, stiffness[k], wet_factor);
        const double l0 = rest[k], cf = damping[k];
        const Coefficients co = spring_law::coefficients<L>(g, l0, TENSION_ROUNDING * l0, projected, h, slack_slope, cf,
                                                            c->v[0][k] - c->v[3][k], c->v[1][k] - c->v[4][k],
                                                            c->v[2][k] - c->v[5][k]);
        ux[k] = co.ux;
        uy[k] = co.uy;
        uz[k] = co.uz;
        along[k] = co.along;
        across[k] = co.across;
        chunk_force(*c, k, g, co.t);
        const Block b = spring_block(co.along, co.across, co.ux, co.uy, co.uz);
        c->block[0][k] = b.xx;
        c->block[1][k] = b.yy;
        c->block[2][k] = b.zz;
        c->block[3][k] = b.xy;
        c->block[4][k] = b.xz;
        c->block[5][k] = b.yz;
    }
}

template <Law L>
void blocks_of(const Cloth& cloth, const Physics& phys, bool projected, const MeshRecords& records, double h,
               double slack_slope, Index first, Index last, Work& work) {
    const Index all = cloth.pair_count;
    double* u = work.pair_direction;
    Chunk c;
    for (Index start = first; start < last; start += CHUNK) {
        const Index count = last - start < CHUNK ? last - start : CHUNK;
        gather(cloth, records.state, start, count, c);
        coefficients_loop<L>(count, phys.wet_factor, projected, h, slack_slope, cloth.pair_rest + start,
                             cloth.pair_damping + start, cloth.pair_stiffness + start, &c, u + start, u + all + start,
                             u + 2 * all + start, work.pair_along + start, work.pair_across + start);
        scatter_forces(cloth, projected, c, start, count, records);
        for (Index k = 0; k < count; ++k) {
            const Ends e = ends(cloth, start + k);
            double* a = records.sums + records.stride * e.i + SUM_DIAGONAL;
            double* b = records.sums + records.stride * e.j + SUM_DIAGONAL;
            for (Index s = 0; s < 6; ++s) {
                a[s] += c.block[s][k];
                b[s] += c.block[s][k];
            }
        }
    }
}

}  // namespace

void listed_spring_forces(const Cloth& cloth, const Physics& phys, const MeshRecords& records) {
    const Index t = cloth.pair_tension_count, b = in_plane_count(cloth), hinges = first_hinge(cloth);
    const bool projected = phys.projected;
    forces_of<Law::CLAMPED>(cloth, phys, projected, records, 0, t);
    forces_of<Law::BUCKLING>(cloth, phys, projected, records, t, b);
    forces_of<Law::BOTH_WAYS>(cloth, phys, projected, records, b, hinges);
    forces_of<Law::BOTH_WAYS>(cloth, phys, false, records, hinges, cloth.pair_count);
}

void listed_spring_forces_and_blocks(const Cloth& cloth, const Physics& phys, const MeshRecords& records, double h,
                                     double slack_slope, Work& work) {
    const Index t = cloth.pair_tension_count, b = in_plane_count(cloth), hinges = first_hinge(cloth);
    const bool projected = phys.projected;
    blocks_of<Law::CLAMPED>(cloth, phys, projected, records, h, slack_slope, 0, t, work);
    blocks_of<Law::BUCKLING>(cloth, phys, projected, records, h, slack_slope, t, b, work);
    blocks_of<Law::BOTH_WAYS>(cloth, phys, projected, records, h, slack_slope, b, hinges, work);
    blocks_of<Law::BOTH_WAYS>(cloth, phys, false, records, h, slack_slope, hinges, cloth.pair_count, work);
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
