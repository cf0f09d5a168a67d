// The plane preconditioner of the implicit solves (port of bf41571:fmu_src/wetcloth/kernels/plane.py).
//
// In each particle's frame (t1, t2, n): the t1 and t2 components each get a scalar matrix
// M + h^2 L_c (L_c the springs' graph Laplacian weighted by rest stiffness times the share of their
// direction in c), factored only when h or the masses have changed much; solved by banded Cholesky
// factors on small grids, by one multigrid V-cycle (banded factors on its coarsest level) on large
// ones.  The normal component gets the normal-normal entry of each particle's diagonal block.
#include "wetcloth/plane.hpp"

#include <cmath>

#include "wetcloth/band.hpp"
#include "wetcloth/multigrid.hpp"

namespace wc {

namespace {

//: Build and factor M + scale L_c for c = t1, t2, L_c the Laplacian of the springs weighted by
//: `weights` (F, n) times each family's share in c: the stencils of every level and the banded
//: Cholesky factors of the coarsest.  Returns 0, or band_factor's info if a matrix was not positive
//: definite.
Index factor(Plane& plane, const Cloth& cloth, const double* mass, double scale, const double* weights) {
    const Index n = cloth.n;
    Hierarchy& grid = plane.grid;
    const Index* levels = grid.levels;
    const Index size = grid.size;
    const Index grid_x = level_value(levels, 0, NX);
    const Index level0_end = level_value(levels, 0, PAD_X) * (level_value(levels, 0, NY) + 3);
    for (Index c = 0; c < 2; ++c) {
        double* coef = grid.coef + c * 9 * size;
        for (Index k = 0; k < 9; ++k)
            for (Index p = 0; p < level0_end; ++p) coef[k * size + p] = 0.0;
        for (Index i = 0; i < n; ++i) coef[CENTRE * size + padded_index(levels, 0, i % grid_x, i / grid_x)] = mass[i];
        for (Index f = 0; f < cloth.families; ++f) {
            const Index k = plane.slots[f];
            if (k < 0) continue;
            const Index off = cloth.offsets[f];
            const double share = scale * plane.shares[c * plane.families + f];
            const double* w_f = weights + f * n;
            for (Index i = 0; i < n - off; ++i) {
                const double w = share * w_f[i];
                if (w == 0.0) continue;
                const Index p = padded_index(levels, 0, i % grid_x, i / grid_x);
                const Index q = padded_index(levels, 0, (i + off) % grid_x, (i + off) / grid_x);
                coef[CENTRE * size + p] += w;
                coef[CENTRE * size + q] += w;
                coef[k * size + p] -= w;
                coef[(8 - k) * size + q] -= w;
            }
        }
    }
    const Index coarsest = grid.level_count - 1;
    for (Index level = 0; level < coarsest; ++level) galerkin(grid, level);
    const Index start = level_value(levels, coarsest, START), pad = level_value(levels, coarsest, PAD_X);
    const Index width = plane.kd + 1;
    for (Index c = 0; c < 2; ++c) {
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
        const Index info = band_factor(band, plane.rows + c * plane.coarse_n * width, plane.coarse_n, plane.kd);
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
    // On banded grids only: a multigrid hierarchy's Galerkin products would cost more.
    return banded(plane) && iterations > JACOBIAN_REFRESH_AFTER * 0.25 * static_cast<double>(plane.kd);
}

Index refresh_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const double* along) {
    const Index n = cloth.n;
    for (Index e = 0; e < cloth.families * n; ++e) plane.jacobian_along[e] = along[e];
    for (Index i = 0; i < n; ++i) plane.jacobian_mass[i] = mass[i];
    if (factor(plane, cloth, mass, 1.0, plane.jacobian_along) != 0) {
        plane.reference[1] = 0.0;
        return -1;
    }
    plane.reference[2] = 1.0;
    return 1;
}

void follow_cloth(Plane& plane, const Cloth& cloth, const double* pos) {
    // t1 along the row, n normal to row and column (central differences, one-sided at the edges),
    // t2 = n x t1; the axes where that is degenerate.
    const Index n = cloth.n, grid_x = cloth.grid_x;
    const double* px = pos;
    const double* py = pos + n;
    const double* pz = pos + 2 * n;
    double* frame = plane.frame;  // frame[(3 r + c) n + i]
    for (Index i = 0; i < n; ++i) {
        const Index col = i % grid_x;
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

void set_normal_diagonal(Plane& plane, Index n, const double* mass, const double* diagonal_blocks,
                         const double* blocks) {
    const double* __restrict n0 = plane.frame + 6 * n;
    const double* __restrict n1 = plane.frame + 7 * n;
    const double* __restrict n2 = plane.frame + 8 * n;
    double* __restrict normal = plane.normal;
    const double* __restrict d = diagonal_blocks;
    const double* __restrict b = blocks;
    for (Index i = 0; i < n; ++i) {
        const double nx = n0[i], ny = n1[i], nz = n2[i];
        const double xx = d[i] + b[i];
        const double yy = d[n + i] + b[n + i];
        const double zz = d[2 * n + i] + b[2 * n + i];
        const double xy = d[3 * n + i] + b[3 * n + i];
        const double xz = d[4 * n + i] + b[4 * n + i];
        const double yz = d[5 * n + i] + b[5 * n + i];
        normal[i] = mass[i] + (xx * nx * nx + yy * ny * ny + zz * nz * nz + 2.0 * (xy * nx * ny + xz * nx * nz + yz * ny * nz));
    }
}

namespace {

//: b = t_c . r over a row of m particles (f0, f1, f2 the rows of t_c's components).
void project_row(double* __restrict b, const double* __restrict f0, const double* __restrict f1,
                 const double* __restrict f2, const double* __restrict r0, const double* __restrict r1,
                 const double* __restrict r2, Index m) {
    for (Index s = 0; s < m; ++s) b[s] = f0[s] * r0[s] + f1[s] * r1[s] + f2[s] * r2[s];
}

//: normal = (n . r) / diagonal over a row of m particles.
void normal_row(double* __restrict normal, const double* __restrict n0, const double* __restrict n1,
                const double* __restrict n2, const double* __restrict r0, const double* __restrict r1,
                const double* __restrict r2, const double* __restrict diagonal, Index m) {
    for (Index s = 0; s < m; ++s) normal[s] = (n0[s] * r0[s] + n1[s] * r1[s] + n2[s] * r2[s]) / diagonal[s];
}

//: z_c = free (t1_c x0 + t2_c x1 + n_c normal) over a row of m particles.
void combine_row(double* __restrict zc, const double* __restrict weight, const double* __restrict t1,
                 const double* __restrict t2, const double* __restrict u, const double* __restrict x0,
                 const double* __restrict x1, const double* __restrict normal, Index m) {
    for (Index s = 0; s < m; ++s) zc[s] = weight[s] * (t1[s] * x0[s] + t2[s] * x1[s] + u[s] * normal[s]);
}

}  // namespace

void apply(Plane& plane, Index n, const double* free, const double* r, double* z) {
    // Loops over rows of the grid (vectorised).
    const double* f = plane.frame;  // f[(3 a + c) n + i]
    Hierarchy& grid = plane.grid;
    const Index* levels = grid.levels;
    const Index size = grid.size;
    double* b = grid.b;
    double* x = grid.x;
    double* local = plane.local;
    double* normal = grid.row;
    const Index grid_x = level_value(levels, 0, NX), grid_y = level_value(levels, 0, NY);
    for (Index iy = 0; iy < grid_y; ++iy) {
        const Index first = iy * grid_x, base = padded_index(levels, 0, 0, iy);
        for (Index c = 0; c < 2; ++c)
            project_row(b + c * size + base, f + 3 * c * n + first, f + (3 * c + 1) * n + first,
                        f + (3 * c + 2) * n + first, r + first, r + n + first, r + 2 * n + first, grid_x);
    }
    v_cycle_down(grid);
    const Index coarse_n = plane.coarse_n;
    const Index* order = plane.order;
    for (Index position = 0; position < coarse_n; ++position) {
        local[position] = b[order[position]];
        local[coarse_n + position] = b[size + order[position]];
    }
    band_solve_two(plane.bands, plane.rows, local, coarse_n, plane.kd);
    for (Index position = 0; position < coarse_n; ++position) {
        x[order[position]] = local[position];
        x[size + order[position]] = local[coarse_n + position];
    }
    v_cycle_up(grid);
    for (Index iy = 0; iy < grid_y; ++iy) {
        const Index first = iy * grid_x, base = padded_index(levels, 0, 0, iy);
        normal_row(normal, f + 6 * n + first, f + 7 * n + first, f + 8 * n + first, r + first, r + n + first,
                   r + 2 * n + first, plane.normal + first, grid_x);
        for (Index c = 0; c < 3; ++c)
            combine_row(z + c * n + first, free + first, f + c * n + first, f + (3 + c) * n + first,
                        f + (6 + c) * n + first, x + base, x + size + base, normal, grid_x);
    }
}

}  // namespace wc
