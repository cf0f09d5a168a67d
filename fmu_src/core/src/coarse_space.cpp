// Two-level coarse space of aggregate rigid motions (see coarse_space.hpp).
#include "wetcloth/coarse_space.hpp"

#include <algorithm>

#include "wetcloth/band.hpp"
#include "wetcloth/vec3.hpp"

namespace wc {

namespace {

constexpr Index U = COARSE_UNKNOWNS;

//: Slot (xx, yy, zz, xy, xz, yz) of a symmetric 3x3 block's entry (c, d).
constexpr int SLOT[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};

//: X(r) (3 x 3, row-major): column k is e_k x r, the motion a turn about axis k gives the arm r.
inline void turn_matrix(const double* r, double* x) {
    x[0] = 0.0, x[1] = r[2], x[2] = -r[1];
    x[3] = -r[2], x[4] = 0.0, x[5] = r[0];
    x[6] = r[1], x[7] = -r[0], x[8] = 0.0;
}

//: out (U x U, row-major) += s Phi_a^T S Phi_b, S = across I + (along - across) u u^T a spring's block,
//: Phi = [I, X(r)] at arms ra, rb: across Phi_a^T Phi_b + (along - across) g_a g_b^T with g = (u, r x u),
//: X(a)^T X(b) = (a . b) I - b a^T.
void add_spring_block(double s, double across, double along, const double* u, const double* ra, const double* rb,
                      double* out) {
    double ga[6] = {u[0], u[1], u[2]}, gb[6] = {u[0], u[1], u[2]};
    cross(ra, u, ga + 3);
    cross(rb, u, gb + 3);
    const double d = s * (along - across), a = s * across;
    for (Index c = 0; c < U; ++c)
        for (Index e = 0; e < U; ++e) out[c * U + e] += d * ga[c] * gb[e];
    double xa[9], xb[9];
    turn_matrix(ra, xa);
    turn_matrix(rb, xb);
    const double ab = ra[0] * rb[0] + ra[1] * rb[1] + ra[2] * rb[2];
    for (Index c = 0; c < 3; ++c) {
        out[c * U + c] += a;
        for (Index k = 0; k < 3; ++k) {
            out[c * U + 3 + k] += a * xb[c * 3 + k];
            out[(3 + k) * U + c] += a * xa[c * 3 + k];
            out[(3 + c) * U + 3 + k] += a * ((c == k ? ab : 0.0) - rb[c] * ra[k]);
        }
    }
}

//: out (U x U) += Phi^T D Phi for a particle's symmetric block D (six slots) at arm r.
void add_particle_block(const double* slots, const double* r, double* out) {
    double dm[9], x[9], dx[9];
    for (Index c = 0; c < 3; ++c)
        for (Index e = 0; e < 3; ++e) dm[c * 3 + e] = slots[SLOT[c][e]];
    turn_matrix(r, x);
    for (Index c = 0; c < 3; ++c)
        for (Index k = 0; k < 3; ++k) dx[c * 3 + k] = dm[c * 3] * x[k] + dm[c * 3 + 1] * x[3 + k] + dm[c * 3 + 2] * x[6 + k];
    for (Index c = 0; c < 3; ++c) {
        for (Index e = 0; e < 3; ++e) out[c * U + e] += dm[c * 3 + e];
        for (Index k = 0; k < 3; ++k) {
            out[c * U + 3 + k] += dx[c * 3 + k];
            out[(3 + k) * U + c] += dx[c * 3 + k];
        }
    }
    for (Index k = 0; k < 3; ++k)
        for (Index l = 0; l < 3; ++l) out[(3 + k) * U + 3 + l] += x[k] * dx[l] + x[3 + k] * dx[3 + l] + x[6 + k] * dx[6 + l];
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
    coarse.width = U * (columns + 1) + U - 1;
    coarse.aggregate.resize(cloth.n);
    coarse.turns.assign(coarse.count, 1.0);
    for (Index i = 0; i < cloth.n; ++i) {
        const Index row = i / cloth.grid_x, column = i % cloth.grid_x;
        coarse.aggregate[i] = (row / side) * columns + column / side;
    }
    for (Index I = 0; I < coarse.count; ++I) {  // a single row or column of particles does not turn
        const Index wide = std::min(side, cloth.grid_x - (I % columns) * side);
        const Index tall = std::min(side, cloth.grid_y - (I / columns) * side);
        if (wide < 2 || tall < 2) coarse.turns[I] = 0.0;
    }
    coarse.arm.assign(3 * cloth.n, 0.0);
    coarse.blocks.assign(coarse.count * COARSE_NEIGHBOURS * U * U, 0.0);
    coarse.edge.assign(6 * cloth.n, 0.0);
    coarse.band.assign(U * coarse.count * (coarse.width + 1), 0.0);
    coarse.rows.assign(coarse.band.size(), 0.0);
    coarse.coarse.assign(U * coarse.count, 0.0);
}

void set_arms(CoarseSpace& coarse, const Cloth& cloth, const double* pos) {
    const Index n = cloth.n;
    std::vector<double>& centre = coarse.coarse;  // (scratch: 3 per aggregate, then the counts)
    std::fill(centre.begin(), centre.end(), 0.0);
    for (Index i = 0; i < n; ++i) {
        double* ci = centre.data() + U * coarse.aggregate[i];
        for (Index c = 0; c < 3; ++c) ci[c] += pos[c * n + i];
        ci[3] += 1.0;
    }
    for (Index i = 0; i < n; ++i) {
        const Index I = coarse.aggregate[i];
        const double* ci = centre.data() + U * I;
        for (Index c = 0; c < 3; ++c) coarse.arm[c * n + i] = coarse.turns[I] * (pos[c * n + i] - ci[c] / ci[3]);
    }
}

void assemble_coarse_matrix(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work,
                            const double* pos) {
    const Index n = cloth.n, count = coarse.count, columns = coarse.columns;
    const double* free = cloth.free;
    set_arms(coarse, cloth, pos);
    const double* arm = coarse.arm.data();
    // Blocks (U x U) by aggregate I and neighbour J = I + NEIGHBOUR[k] (k = 0: I itself), P^T A P's block
    // (I, J); edge (6, n) each free particle's sum of the blocks of its springs that are not within its
    // aggregate between two free particles.
    const Index neighbour[COARSE_NEIGHBOURS] = {0, 1, columns - 1, columns, columns + 1};
    std::vector<double>& blocks = coarse.blocks;
    std::vector<double>& edge = coarse.edge;
    std::fill(blocks.begin(), blocks.end(), 0.0);
    std::fill(edge.begin(), edge.end(), 0.0);
    // A spring i-j with block S adds S to (i, i) and (j, j), -S to (i, j) and (j, i), each end weighted by
    // its free flag.  Within one aggregate, two free ends give (Phi_i - Phi_j)^T S (Phi_i - Phi_j): the
    // turns alone, about the arm r_i - r_j; otherwise Phi_i^T S Phi_i and Phi_j^T S Phi_j (through edge)
    // and -Phi_i^T S Phi_j between I and J.
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        const double* direction = work.direction + f * 3 * n;
        const double* along = work.along + f * n;
        const double* across = work.across + f * n;
        for (Index i = 0; i + off < n; ++i) {
            const Index j = i + off;
            const double fi = free[i], fj = free[j];
            if (fi == 0.0 && fj == 0.0) continue;
            const Index I = coarse.aggregate[i], J = coarse.aggregate[j];
            const double u[3] = {direction[i], direction[n + i], direction[2 * n + i]};
            const double ac = across[i], d = along[i] - across[i];
            if (I == J && fi * fj == 1.0) {
                const double r[3] = {arm[i] - arm[j], arm[n + i] - arm[n + j], arm[2 * n + i] - arm[2 * n + j]};
                double w[3];
                cross(r, u, w);
                const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                double* b = blocks.data() + I * COARSE_NEIGHBOURS * U * U;
                for (Index c = 0; c < 3; ++c)
                    for (Index e = 0; e < 3; ++e)
                        b[(3 + c) * U + 3 + e] += ac * ((c == e ? rr : 0.0) - r[c] * r[e]) + d * w[c] * w[e];
                continue;
            }
            const double slots[6] = {ac + d * u[0] * u[0], ac + d * u[1] * u[1], ac + d * u[2] * u[2],
                                     d * u[0] * u[1],      d * u[0] * u[2],      d * u[1] * u[2]};
            for (Index t = 0; t < 6; ++t) {
                edge[t * n + i] += fi * fi * slots[t];
                edge[t * n + j] += fj * fj * slots[t];
            }
            if (fi * fj == 0.0) continue;
            const double ri[3] = {arm[i], arm[n + i], arm[2 * n + i]};
            const double rj[3] = {arm[j], arm[n + j], arm[2 * n + j]};
            const Index low = std::min(I, J), high = std::max(I, J);
            Index k = 1;
            while (k < COARSE_NEIGHBOURS && neighbour[k] != high - low) ++k;
            if (k == COARSE_NEIGHBOURS) continue;  // (a grid's spring across a row's end: coefficients 0)
            double* b = blocks.data() + (low * COARSE_NEIGHBOURS + k) * U * U;
            if (I < J) add_spring_block(-fi * fj, ac, along[i], u, ri, rj, b);  // Phi_i^T S Phi_j into (I, J)
            else add_spring_block(-fi * fj, ac, along[i], u, rj, ri, b);
        }
    }
    for (Index i = 0; i < n; ++i) {  // M + the per-particle blocks + the edge springs' blocks
        if (free[i] == 0.0) continue;
        double slots[6];
        for (Index t = 0; t < 6; ++t) slots[t] = free[i] * (work.blocks[t * n + i] + (t < 3 ? mass[i] : 0.0) + edge[t * n + i]);
        const double r[3] = {arm[i], arm[n + i], arm[2 * n + i]};
        add_particle_block(slots, r, blocks.data() + coarse.aggregate[i] * COARSE_NEIGHBOURS * U * U);
    }
    // into the lower band: (I, I)'s lower triangle, (J, I) = (I, J)^T
    std::fill(coarse.band.begin(), coarse.band.end(), 0.0);
    const Index stride = coarse.width + 1;
    for (Index I = 0; I < count; ++I) {
        for (Index k = 0; k < COARSE_NEIGHBOURS; ++k) {
            const Index J = I + neighbour[k];
            if (J >= count) continue;
            const double* b = blocks.data() + (I * COARSE_NEIGHBOURS + k) * U * U;
            for (Index c = 0; c < U; ++c) {  // b's row c: row U I + c, column U J + e of P^T A P
                for (Index e = 0; e < U; ++e) {
                    const Index row = U * J + e, col = U * I + c;  // its transpose's entry, in the lower band
                    if (col <= row) coarse.band[col * stride + row - col] += b[c * U + e];
                }
            }
        }
    }
}

void build_coarse_space(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work,
                        const double* pos) {
    assemble_coarse_matrix(coarse, cloth, mass, work, pos);
    const Index size = U * coarse.count, stride = coarse.width + 1;
    for (Index row = 0; row < size; ++row) {
        // (an aggregate of pinned particles, or one that does not turn: unknowns nothing couples)
        if (coarse.band[row * stride] == 0.0) coarse.band[row * stride] = 1.0;
    }
    coarse.factored = band_factor(coarse.band.data(), coarse.rows.data(), size, coarse.width) == 0;
}

void add_coarse_correction(CoarseSpace& coarse, const Cloth& cloth, const double* r, double* z) {
    if (!coarse.factored) return;
    // By runs of a grid row within one aggregate (contiguous particles): P^T r (forces, then torques
    // about the aggregate's centre) summed run by run, then each run's particles take their
    // aggregate's motion, translation plus turn.
    const Index n = cloth.n, grid_x = cloth.grid_x, side = coarse.side, columns = coarse.columns;
    const double* free = cloth.free;
    const double* arm = coarse.arm.data();
    double* y = coarse.coarse.data();
    std::fill(coarse.coarse.begin(), coarse.coarse.end(), 0.0);
    for (Index first = 0; first < n; first += grid_x) {
        const Index aggregate_row = (first / grid_x) / side * columns;
        for (Index column = 0; column < columns; ++column) {
            const Index start = first + column * side, end = std::min(start + side, first + grid_x);
            double* target = y + U * (aggregate_row + column);
            double sum[U] = {};
            for (Index i = start; i < end; ++i) {
                const double fx = free[i] * r[i], fy = free[i] * r[n + i], fz = free[i] * r[2 * n + i];
                const double ax = arm[i], ay = arm[n + i], az = arm[2 * n + i];
                sum[0] += fx, sum[1] += fy, sum[2] += fz;
                sum[3] += ay * fz - az * fy, sum[4] += az * fx - ax * fz, sum[5] += ax * fy - ay * fx;
            }
            for (Index k = 0; k < U; ++k) target[k] += sum[k];
        }
    }
    band_solve_one(coarse.band.data(), coarse.rows.data(), y, U * coarse.count, coarse.width);
    for (Index first = 0; first < n; first += grid_x) {
        const Index aggregate_row = (first / grid_x) / side * columns;
        for (Index column = 0; column < columns; ++column) {
            const Index start = first + column * side, end = std::min(start + side, first + grid_x);
            const double* m = y + U * (aggregate_row + column);  // translation, then turn (omega)
            for (Index i = start; i < end; ++i) {
                const double ax = arm[i], ay = arm[n + i], az = arm[2 * n + i];
                z[i] += free[i] * (m[0] + m[4] * az - m[5] * ay);
                z[n + i] += free[i] * (m[1] + m[5] * ax - m[3] * az);
                z[2 * n + i] += free[i] * (m[2] + m[3] * ay - m[4] * ax);
            }
        }
    }
}

}  // namespace wc
