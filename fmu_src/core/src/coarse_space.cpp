// Two-level coarse space of aggregate translations (see coarse_space.hpp).
#include "wetcloth/coarse_space.hpp"

#include <algorithm>

#include "wetcloth/band.hpp"

namespace wc {

namespace {

//: Slot (xx, yy, zz, xy, xz, yz) of a symmetric 3x3 block's entry (c, d).
constexpr int SLOT[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};

//: Add s times the symmetric 3x3 block b (six slots) to the coarse matrix's block (I, J), I >= J, and
//: (when I > J) thereby to its transpose (J, I): only the lower band is kept.
inline void add_block(CoarseSpace& coarse, Index I, Index J, double s, const double* b) {
    const Index stride = coarse.width + 1;
    for (Index c = 0; c < 3; ++c) {
        for (Index d = 0; d < 3; ++d) {
            const Index row = 3 * I + c, col = 3 * J + d;
            if (col <= row) coarse.band[col * stride + row - col] += s * b[SLOT[c][d]];
        }
    }
}

}  // namespace

void shape_coarse_space(CoarseSpace& coarse, const Cloth& cloth, Index side) {
    const Index columns = (cloth.grid_x + side - 1) / side;
    const Index rows = (cloth.grid_y + side - 1) / side;
    coarse.side = side;
    coarse.columns = columns;
    coarse.count = columns * rows;
    // Springs reach at most one aggregate further (side >= the longest spring's reach, 2 particles), the
    // diagonal neighbour's last unknown columns + 1 aggregates before.
    coarse.width = 3 * (columns + 1) + 2;
    coarse.aggregate.resize(cloth.n);
    for (Index i = 0; i < cloth.n; ++i) {
        const Index row = i / cloth.grid_x, column = i % cloth.grid_x;
        coarse.aggregate[i] = (row / side) * columns + column / side;
    }
    coarse.band.assign(3 * coarse.count * (coarse.width + 1), 0.0);
    coarse.rows.assign(coarse.band.size(), 0.0);
    coarse.coarse.assign(3 * coarse.count, 0.0);
}

void assemble_coarse_matrix(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work) {
    const Index n = cloth.n;
    const double* free = cloth.free;
    std::fill(coarse.band.begin(), coarse.band.end(), 0.0);
    double b[6];
    for (Index i = 0; i < n; ++i) {  // M + the per-particle blocks
        if (free[i] == 0.0) continue;
        for (Index s = 0; s < 6; ++s) b[s] = work.blocks[s * n + i] + (s < 3 ? mass[i] : 0.0);
        add_block(coarse, coarse.aggregate[i], coarse.aggregate[i], free[i] * free[i], b);
    }
    // A spring i-j with block S adds S to (i, i) and (j, j), -S to (i, j) and (j, i); its aggregates I, J
    // get the same, each end weighted by its free flag (within one aggregate of two free ends: nothing).
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        const double* u = work.direction + f * 3 * n;
        const double* along = work.along + f * n;
        const double* across = work.across + f * n;
        for (Index i = 0; i + off < n; ++i) {
            const Index j = i + off;
            const double fi = free[i], fj = free[j];
            const Index I = coarse.aggregate[i], J = coarse.aggregate[j];
            if (I == J && fi * fj == 1.0) continue;
            if (fi == 0.0 && fj == 0.0) continue;
            const double ux = u[i], uy = u[n + i], uz = u[2 * n + i];
            const double ac = across[i], d = along[i] - across[i];
            b[0] = ac + d * ux * ux, b[1] = ac + d * uy * uy, b[2] = ac + d * uz * uz;
            b[3] = d * ux * uy, b[4] = d * ux * uz, b[5] = d * uy * uz;
            add_block(coarse, I, I, fi * fi, b);
            add_block(coarse, J, J, fj * fj, b);
            if (I != J) add_block(coarse, std::max(I, J), std::min(I, J), -fi * fj, b);
            else add_block(coarse, I, I, -2.0 * fi * fj, b);
        }
    }
}

void build_coarse_space(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work) {
    assemble_coarse_matrix(coarse, cloth, mass, work);
    const Index size = 3 * coarse.count, stride = coarse.width + 1;
    for (Index row = 0; row < size; ++row) {
        if (coarse.band[row * stride] == 0.0) coarse.band[row * stride] = 1.0;  // (an aggregate of pinned particles)
    }
    coarse.factored = band_factor(coarse.band.data(), coarse.rows.data(), size, coarse.width) == 0;
}

void add_coarse_correction(CoarseSpace& coarse, const Cloth& cloth, const double* r, double* z) {
    if (!coarse.factored) return;
    // By runs of a grid row within one aggregate (contiguous particles): P^T r summed run by run, then
    // each run's particles take their aggregate's coarse solution.
    const Index n = cloth.n, grid_x = cloth.grid_x, side = coarse.side, columns = coarse.columns;
    const double* free = cloth.free;
    double* y = coarse.coarse.data();
    std::fill(coarse.coarse.begin(), coarse.coarse.end(), 0.0);
    for (Index first = 0; first < n; first += grid_x) {
        const Index aggregate_row = (first / grid_x) / side * columns;
        for (Index column = 0; column < columns; ++column) {
            const Index start = first + column * side, end = std::min(start + side, first + grid_x);
            double* target = y + 3 * (aggregate_row + column);
            for (Index c = 0; c < 3; ++c) {
                const double* rc = r + c * n;
                double sum = 0.0;
                for (Index i = start; i < end; ++i) sum += free[i] * rc[i];
                target[c] += sum;
            }
        }
    }
    band_solve_one(coarse.band.data(), coarse.rows.data(), y, 3 * coarse.count, coarse.width);
    for (Index first = 0; first < n; first += grid_x) {
        const Index aggregate_row = (first / grid_x) / side * columns;
        for (Index column = 0; column < columns; ++column) {
            const Index start = first + column * side, end = std::min(start + side, first + grid_x);
            const double* source = y + 3 * (aggregate_row + column);
            for (Index c = 0; c < 3; ++c) {
                double* zc = z + c * n;
                const double value = source[c];
                for (Index i = start; i < end; ++i) zc[i] += free[i] * value;
            }
        }
    }
}

}  // namespace wc
