// The plane preconditioner of the implicit solves (port of bf41571:fmu_src/wetcloth/kernels/plane.py).
//
// In each particle's frame (t1, t2, n): the t1 and t2 components each get a scalar matrix
// M + h^2 L_c (L_c the springs' graph Laplacian weighted by rest stiffness times the share of their
// direction in c), factored only when h or the masses have changed much.  The normal component gets
// the system matrix itself restricted to the particles' normals, n_i^T A_ij n_j, at every Newton
// iteration: across a cloth under tension (a hanging sheet at frame-long steps) it is a stiff
// Laplacian, which its diagonal alone preconditioned poorly (CG iterations growing in proportion to
// the step).  All three are solved by banded Cholesky factors on small grids, by one multigrid
// V-cycle (banded factors on its coarsest level) on large ones.
#include "wetcloth/plane.hpp"

#include <cmath>
#include <vector>

#include "wetcloth/band.hpp"
#include "wetcloth/multigrid.hpp"
#include "wetcloth/plane_parts.hpp"

namespace wc {

namespace {

//: Component c's stencils on every level and its coarsest banded factors, from its level-0 stencil.
//: Returns 0, or band_factor's info.
Index factor_component(Plane& plane, Index c) {
    Hierarchy& grid = plane.grid;
    const Index coarsest = grid.level_count - 1;
    for (Index level = 0; level < coarsest; ++level) galerkin(grid, level, c, c + 1);
    const Index size = grid.size, width = plane.kd + 1;
    const Index start = level_value(grid.levels, coarsest, START), pad = level_value(grid.levels, coarsest, PAD_X);
    const double* coef = grid.coef + c * 9 * size;
    double* band = plane.bands + c * plane.coarse_n * width;
    for (Index e = 0; e < plane.coarse_n * width; ++e) band[e] = 0.0;
    for (Index position = 0; position < plane.coarse_n; ++position) {
        const Index p = plane.order[position];
        band[position * width] = coef[CENTRE * size + p];
        for (Index k = 0; k < 9; ++k) {
            const Index other = plane.rank[p + (k / 3 - 1) * pad + k % 3 - 1 - start];
            if (other > position) band[position * width + other - position] = coef[k * size + p];
        }
    }
    return band_factor(band, plane.rows + c * plane.coarse_n * width, plane.coarse_n, plane.kd);
}

//: Zero component c's level-0 stencil and put diagonal (n) on its centre.
void diagonal_stencil(Plane& plane, Index n, Index c, const double* diagonal) {
    Hierarchy& grid = plane.grid;
    const Index size = grid.size, grid_x = level_value(grid.levels, 0, NX);
    const Index level0_end = level_value(grid.levels, 0, PAD_X) * (level_value(grid.levels, 0, NY) + 3);
    double* coef = grid.coef + c * 9 * size;
    for (Index k = 0; k < 9; ++k)
        for (Index p = 0; p < level0_end; ++p) coef[k * size + p] = 0.0;
    double* centre = coef + CENTRE * size;
    for (Index first = 0; first < n; first += grid_x) {
        const Index row = padded_index(grid.levels, 0, 0, first / grid_x) - first;
        for (Index i = first; i < first + grid_x; ++i) centre[row + i] = diagonal[i];
    }
}

//: Build and factor M + scale L_c for c = t1, t2, L_c the Laplacian of the springs weighted by
//: `weights` (F, n) times each family's share in c: the stencils of every level and the banded
//: Cholesky factors of the coarsest.  Returns 0, or band_factor's info if a matrix was not positive
//: definite.
Index factor(Plane& plane, const Cloth& cloth, const double* mass, double scale, const double* weights) {
    if (mesh_plane(plane)) return mesh_factor(plane, cloth, mass, scale, weights);
    const Index n = cloth.n;
    Hierarchy& grid = plane.grid;
    const Index* levels = grid.levels;
    const Index size = grid.size;
    const Index grid_x = level_value(levels, 0, NX);
    for (Index c = 0; c < 2; ++c) {
        diagonal_stencil(plane, n, c, mass);
        double* coef = grid.coef + c * 9 * size;
        for (Index f = 0; f < cloth.families; ++f) {
            const Index k = plane.slots[f];
            if (k < 0) continue;
            const Index off = cloth.offsets[f];
            const double share = scale * plane.shares[c * plane.families + f];
            const double* w_f = weights + f * n;
            // (ix, iy) and (jx, jy): the grid points of i and i + off, counted along
            Index ix = 0, iy = 0, jx = off % grid_x, jy = off / grid_x;
            for (Index i = 0; i < n - off; ++i, ++ix, ++jx) {
                if (ix == grid_x) ix = 0, ++iy;
                if (jx == grid_x) jx = 0, ++jy;
                const double w = share * w_f[i];
                if (w == 0.0) continue;
                const Index p = padded_index(levels, 0, ix, iy);
                const Index q = padded_index(levels, 0, jx, jy);
                coef[CENTRE * size + p] += w;
                coef[CENTRE * size + q] += w;
                coef[k * size + p] -= w;
                coef[(8 - k) * size + q] -= w;
            }
        }
    }
    for (Index c = 0; c < 2; ++c) {
        const Index info = factor_component(plane, c);
        if (info != 0) return info;
    }
    return 0;
}

}  // namespace

Index refresh(Plane& plane, const Cloth& cloth, const double* mass, double scale) {
    double* ref = plane.reference;
    const Index n = cloth.n;
    if (ref[1] == 1.0) {
        const double ratio = scale / ref[0];
        if (1.0 / REFACTOR_SCALE <= ratio && ratio <= REFACTOR_SCALE) {
            bool close = true;
            for (Index i = 0; i < n; ++i) {
                if (std::abs(mass[i] / plane.reference_mass[i] - 1.0) > REFACTOR_CHANGE) {
                    close = false;
                    break;
                }
            }
            if (close) return 0;
        }
    }
    if (factor(plane, cloth, mass, scale, plane.stiffness) != 0) {
        ref[1] = 0.0;
        return -1;
    }
    ref[0] = scale;
    ref[1] = 1.0;
    ref[2] = 0.0;
    for (Index i = 0; i < n; ++i) plane.reference_mass[i] = mass[i];
    return 1;
}

bool jacobian_refresh_pays(const Plane& plane, double iterations) {
    // On banded grids and meshes only: a multigrid hierarchy's Galerkin products would cost more.  On a
    // mesh's algebraic hierarchy (10k-vertex disc, 0.4 s landing; 0.25 s hanging) refreshing after every
    // solve of more than 1 CG iteration cut the CG iterations by 21 % (10 %) but took 12 % (10 %) more time.
    return banded(plane) && iterations > JACOBIAN_REFRESH_AFTER * 0.25 * static_cast<double>(plane.kd);
}

bool buckling_mesh_refresh_pays(const Plane& plane, const Cloth& cloth, double iterations) {
    return mesh_plane(plane) && !banded(plane) && cloth.pair_buckling_count > 0 && iterations > MESH_REFRESH_AFTER;
}

Index refresh_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const double* along) {
    const Index n = cloth.n;
    const Index count = mesh_plane(plane) ? cloth.pair_count : cloth.families * n;
    for (Index e = 0; e < count; ++e) plane.jacobian_along[e] = along[e];
    for (Index i = 0; i < n; ++i) plane.jacobian_mass[i] = mass[i];
    if (factor(plane, cloth, mass, 1.0, plane.jacobian_along) != 0) {
        plane.reference[1] = 0.0;
        return -1;
    }
    plane.reference[2] = 1.0;
    return 1;
}

void follow_cloth(Plane& plane, const Cloth& cloth, const double* pos) {
    if (mesh_plane(plane)) return mesh_follow_cloth(plane, cloth, pos);
    // t1 along the row, n normal to row and column (central differences, one-sided at the edges),
    // t2 = n x t1; the axes where that is degenerate.
    const Index n = cloth.n, grid_x = cloth.grid_x;
    const double* px = pos;
    const double* py = pos + n;
    const double* pz = pos + 2 * n;
    double* frame = plane.frame;  // frame[(3 r + c) n + i]
    for (Index i = 0, col = 0; i < n; ++i, col = col + 1 < grid_x ? col + 1 : 0) {  // col: i % grid_x
        const Index right = col + 1 < grid_x ? i + 1 : i;
        const Index left = col > 0 ? i - 1 : i;
        const Index up = i + grid_x < n ? i + grid_x : i;
        const Index down = i >= grid_x ? i - grid_x : i;
        double ax = px[right] - px[left];
        double ay = py[right] - py[left];
        double az = pz[right] - pz[left];
        const double bx = px[up] - px[down];
        const double by = py[up] - py[down];
        const double bz = pz[up] - pz[down];
        double cx = ay * bz - az * by;
        double cy = az * bx - ax * bz;
        double cz = ax * by - ay * bx;
        const double a_norm = std::sqrt(ax * ax + ay * ay + az * az);
        const double c_norm = std::sqrt(cx * cx + cy * cy + cz * cz);
        if (!(c_norm > 1e-12 * a_norm * a_norm && a_norm > 0.0)) {  // crumpled past telling: the axes
            for (Index r = 0; r < 3; ++r)
                for (Index c = 0; c < 3; ++c) frame[(3 * r + c) * n + i] = r == c ? 1.0 : 0.0;
            continue;
        }
        ax /= a_norm;
        ay /= a_norm;
        az /= a_norm;
        cx /= c_norm;
        cy /= c_norm;
        cz /= c_norm;
        frame[0 * n + i] = ax;
        frame[1 * n + i] = ay;
        frame[2 * n + i] = az;
        frame[6 * n + i] = cx;
        frame[7 * n + i] = cy;
        frame[8 * n + i] = cz;
        frame[3 * n + i] = cy * az - cz * ay;
        frame[4 * n + i] = cz * ax - cx * az;
        frame[5 * n + i] = cx * ay - cy * ax;
    }
}

namespace {

//: Each spring's part of one component's stencil (spring_coupling) for the m springs i -> i + off:
//: at_i, at_j and, between ends both free (free 1, else 0), between.  A spring with no block (along =
//: across = 0) or with a pinned end then gives +-0 (the frame and u are finite), and adding +-0 changes
//: no entry (none is -0): the entries of skipping them, with no branch in the loop (which vectorises).
void couplings_loop(Index m, const double* __restrict tx, const double* __restrict ty, const double* __restrict tz,
                    const double* __restrict txj, const double* __restrict tyj, const double* __restrict tzj,
                    const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                    const double* __restrict along, const double* __restrict across, const double* __restrict free_i,
                    const double* __restrict free_j, double* __restrict at_i, double* __restrict at_j,
                    double* __restrict between) {
    for (Index i = 0; i < m; ++i) {
        const Coupling s = spring_coupling(tx[i], ty[i], tz[i], txj[i], tyj[i], tzj[i], ux[i], uy[i], uz[i], along[i],
                                           across[i]);
        at_i[i] = s.at_i;
        at_j[i] = s.at_j;
        between[i] = free_i[i] * free_j[i] * s.between;  // a pinned end holds: no coupling (Dirichlet)
    }
}

//: centre[s] += at[s], side[s] += between[s] over m points.
void add_couplings(Index m, const double* __restrict at, const double* __restrict between, double* __restrict centre,
                   double* __restrict side) {
    for (Index s = 0; s < m; ++s) {
        centre[s] += at[s];
        side[s] += between[s];
    }
}

//: Component c's level-0 stencil from the Jacobian: on the diagonal `diagonal` (the mass and the
//: particle's own blocks) plus t_i^T S t_i of each spring the stencil reaches, and between its ends
//: -t_i^T S t_j, S = across I + (along - across) u u^T the spring's block.  Springs it does not reach
//: (bending) are left out whole: their diagonal part alone would make smooth modes far too stiff.
//: scratch: 3 n.  Each entry takes its springs' parts family after family, spring after spring (a
//: particle's part as a second end before its part as a first end), row by row of the grid.
void jacobian_stencil(Plane& plane, const Cloth& cloth, const Work& work, Index c, const double* diagonal,
                      double* scratch) {
    const Index n = cloth.n;
    diagonal_stencil(plane, n, c, diagonal);
    Hierarchy& grid = plane.grid;
    const Index size = grid.size, grid_x = cloth.grid_x;
    double* coef = grid.coef + c * 9 * size;
    const double* t = plane.frame + (3 * c) * n;
    const double* free = cloth.free;
    double* at_i = scratch;
    double* at_j = scratch + n;
    double* between = scratch + 2 * n;
    for (Index f = 0; f < cloth.families; ++f) {
        const Index k = plane.slots[f];
        if (k < 0) continue;  // a family the stencil does not reach: its diagonal part stays
        const Index off = cloth.offsets[f];
        const Index m = n - off;
        if (m <= 0) continue;
        const double* u = work.direction + (3 * f) * n;
        couplings_loop(m, t, t + n, t + 2 * n, t + off, t + n + off, t + 2 * n + off, u, u + n, u + 2 * n,
                       work.along + f * n, work.across + f * n, free, free + off, at_i, at_j, between);
        for (Index first = 0; first < n; first += grid_x) {
            const Index end = first + grid_x;
            const Index row = padded_index(grid.levels, 0, 0, first / grid_x) - first;  // + x: x's point
            double* centre = coef + CENTRE * size + row;
            if (end > off) {  // particles x >= off: second ends of springs x - off
                const Index from = first > off ? first : off;
                add_couplings(end - from, at_j + from - off, between + from - off, centre + from,
                              coef + (8 - k) * size + row + from);
            }
            if (first < m) {  // particles x < m: first ends of springs x
                const Index to = end < m ? end : m;
                add_couplings(to - first, at_i + first, between + first, centre + first, coef + k * size + row + first);
            }
        }
    }
}

}  // namespace

void set_normal_diagonal(Plane& plane, Index n, const double* mass, const double* diagonal_blocks,
                         const double* blocks) {
    axis_diagonal<true>(plane, n, NORMAL, mass, diagonal_blocks, blocks, plane.normal);
    plane.reference[3] = 0.0;
}

Index set_systems_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const Work& work,
                                Index components) {
    if (mesh_plane(plane)) return mesh_systems_from_jacobian(plane, cloth, mass, work);
    const Index n = cloth.n;
    plane.reference[1] = plane.reference[2] = 0.0;  // the rest-stiffness factors are overwritten
    plane.reference[3] = components == COMPONENTS ? 1.0 : 0.0;
    Index result = 1;
    std::vector<double> scratch(static_cast<std::size_t>(4 * n));  // the in-plane diagonal, then jacobian_stencil's
    double* in_plane = scratch.data();
    for (Index c = 0; c < components; ++c) {
        double* diagonal = c == NORMAL ? plane.normal : in_plane;
        axis_diagonal<false>(plane, n, c, mass, nullptr, work.blocks, diagonal);
        jacobian_stencil(plane, cloth, work, c, diagonal, in_plane + n);
        if (factor_component(plane, c) == 0) continue;
        diagonal_stencil(plane, n, c, diagonal);  // not positive definite (round-off on a crumpled cloth)
        if (factor_component(plane, c) != 0) result = -1;
    }
    return result;
}


namespace {

//: b = t_c . r over a row of m particles (f0, f1, f2 the rows of t_c's components).
void project_row(double* __restrict b, const double* __restrict f0, const double* __restrict f1,
                 const double* __restrict f2, const double* __restrict r0, const double* __restrict r1,
                 const double* __restrict r2, Index m) {
    for (Index s = 0; s < m; ++s) b[s] = f0[s] * r0[s] + f1[s] * r1[s] + f2[s] * r2[s];
}

//: out = b / diagonal over a row of m particles.
void divide_row(double* __restrict out, const double* __restrict b, const double* __restrict diagonal, Index m) {
    for (Index s = 0; s < m; ++s) out[s] = b[s] / diagonal[s];
}

//: z_c = free (t1_c x0 + t2_c x1 + n_c normal) over a row of m particles.
void combine_row(double* __restrict zc, const double* __restrict weight, const double* __restrict t1,
                 const double* __restrict t2, const double* __restrict u, const double* __restrict x0,
                 const double* __restrict x1, const double* __restrict normal, Index m) {
    for (Index s = 0; s < m; ++s) zc[s] = weight[s] * (t1[s] * x0[s] + t2[s] * x1[s] + u[s] * normal[s]);
}

}  // namespace

void apply(Plane& plane, Index n, const double* free, const double* r, double* z) {
    if (mesh_plane(plane)) return mesh_apply(plane, n, free, r, z);
    // Loops over rows of the grid (vectorised).  The normal component goes through the cycle and the
    // band solves when it has a system (set_systems_from_jacobian), else it is divided by its diagonal.
    const double* f = plane.frame;  // f[(3 a + c) n + i]
    Hierarchy& grid = plane.grid;
    const Index* levels = grid.levels;
    const Index size = grid.size;
    const Index components = plane.reference[3] != 0.0 ? COMPONENTS : NORMAL;
    double* b = grid.b;
    double* x = grid.x;
    double* local = plane.local;
    const Index grid_x = level_value(levels, 0, NX), grid_y = level_value(levels, 0, NY);
    for (Index iy = 0; iy < grid_y; ++iy) {
        const Index first = iy * grid_x, base = padded_index(levels, 0, 0, iy);
        for (Index c = 0; c < COMPONENTS; ++c)
            project_row(b + c * size + base, f + 3 * c * n + first, f + (3 * c + 1) * n + first,
                        f + (3 * c + 2) * n + first, r + first, r + n + first, r + 2 * n + first, grid_x);
    }
    v_cycle_down(grid, components);
    const Index coarse_n = plane.coarse_n;
    const Index* order = plane.order;
    for (Index c = 0; c < components; ++c)
        for (Index position = 0; position < coarse_n; ++position) local[c * coarse_n + position] = b[c * size + order[position]];
    band_solve_two(plane.bands, plane.rows, local, coarse_n, plane.kd);
    if (components == COMPONENTS) {
        const Index band_size = coarse_n * (plane.kd + 1);
        band_solve_one(plane.bands + NORMAL * band_size, plane.rows + NORMAL * band_size, local + NORMAL * coarse_n,
                       coarse_n, plane.kd);
    }
    for (Index c = 0; c < components; ++c)
        for (Index position = 0; position < coarse_n; ++position) x[c * size + order[position]] = local[c * coarse_n + position];
    v_cycle_up(grid, components);
    double* normal = x + NORMAL * size;
    for (Index iy = 0; iy < grid_y; ++iy) {
        const Index first = iy * grid_x, base = padded_index(levels, 0, 0, iy);
        if (components == NORMAL) divide_row(normal + base, b + NORMAL * size + base, plane.normal + first, grid_x);
        for (Index c = 0; c < 3; ++c)
            combine_row(z + c * n + first, free + first, f + c * n + first, f + (3 + c) * n + first,
                        f + (6 + c) * n + first, x + base, x + size + base, normal + base, grid_x);
    }
}

}  // namespace wc
