// Geometric multigrid V-cycle (port of bf41571:fmu_src/wetcloth/kernels/multigrid.py).
#include "wetcloth/multigrid.hpp"

namespace wc {

namespace {

//: Zero the padding of `level` in v (the line before its first row and column, the two after its last):
//: the neighbours a sweep from zero and its residual read beyond the grid.  The sweep itself writes every
//: point of the level before anything reads it.
void zero_padding(Hierarchy& h, Index level, float* v, Index components) {
    const Index nx = level_value(h.levels, level, NX), ny = level_value(h.levels, level, NY);
    const Index pad = level_value(h.levels, level, PAD_X);
    const Index start = level_value(h.levels, level, START);
    for (Index c = 0; c < components; ++c) {
        float* vc = v + c * h.size + start;
        for (Index p = 0; p < pad; ++p) vc[p] = 0.0f;  // the line before the first row
        for (Index row = 1; row <= ny; ++row) {
            vc[row * pad] = 0.0f;
            vc[row * pad + nx + 1] = 0.0f;
            vc[row * pad + nx + 2] = 0.0f;
        }
        for (Index p = (ny + 1) * pad; p < (ny + 3) * pad; ++p) vc[p] = 0.0f;  // the two after the last
    }
}

//: The padded points of `level`: its first index and how many.
Index level_begin(const Hierarchy& h, Index level) { return level_value(h.levels, level, START); }
Index level_length(const Hierarchy& h, Index level) {
    return level_value(h.levels, level, PAD_X) * (level_value(h.levels, level, NY) + 3);
}

//: to[p] = from[p] rounded to single precision, for p from `begin` to `end` (exclusive).
void round_range(const double* from, float* to, Index begin, Index end) {
    for (Index p = begin; p < end; ++p) to[p] = static_cast<float>(from[p]);
}

//: to = from, rounded to single precision, over `level`'s padded points of the first `components` components.
void to_single(const Hierarchy& h, Index level, const double* from, float* to, Index components) {
    const Index begin = level_begin(h, level), end = begin + level_length(h, level);
    for (Index c = 0; c < components; ++c) round_range(from + c * h.size, to + c * h.size, begin, end);
}

//: to = from over `level`'s padded points of the first `components` components.
void to_double(const Hierarchy& h, Index level, const float* from, double* to, Index components) {
    const Index begin = level_begin(h, level), end = begin + level_length(h, level);
    for (Index c = 0; c < components; ++c)
        for (Index p = c * h.size + begin; p < c * h.size + end; ++p) to[p] = from[p];
}

}  // namespace

namespace {

//: One fine entry's part of a coarse entry: the fine point 2 Q + (px, py) of coarse point Q, its stencil
//: slot k, and the weight its entry a takes (the product of the interpolation weights of both ends).
struct Contribution {
    Index px, py, k;
    double weight;
};

//: The fine entries (a of point p, slot k: p and its neighbour j) that coarse slot `slot` of every
//: coarse point takes, in the order of the fine points (row after row), then of k: P^T A P adds
//: w_p w_j a (w the bilinear weights: 1 at even, 1/2 at odd indices) for each p among Q's fine
//: points and j among those of the neighbour Q + (dx, dy).  Returns their number (at most 49).
Index contributions(Index slot, Contribution* out) {
    const Index dx = slot % 3 - 1, dy = slot / 3 - 1;
    Index count = 0;
    for (Index py = -1; py <= 1; ++py) {
        for (Index px = -1; px <= 1; ++px) {
            for (Index k = 0; k < 9; ++k) {
                const Index jx = px + k % 3 - 1 - 2 * dx, jy = py + k / 3 - 1 - 2 * dy;  // j from 2 (Q + d)
                if (jx < -1 || jx > 1 || jy < -1 || jy > 1) continue;
                const Index weights = (py == 0 ? 2 : 1) * (px == 0 ? 2 : 1) * (jy == 0 ? 2 : 1) * (jx == 0 ? 2 : 1);
                out[count++] = {px, py, k, 0.0625 * static_cast<double>(weights)};
            }
        }
    }
    return count;
}

//: target[q] += weight a[2 q] for the m points q of a coarse row (a: the fine entries from the row's
//: first fine point, every other one).
void add_weighted(double* __restrict target, const double* __restrict a, double weight, Index m) {
    for (Index q = 0; q < m; ++q) target[q] += weight * a[2 * q];
}

}  // namespace

void galerkin(Hierarchy& h, Index level, Index first, Index end) {
    // Each coarse entry gathers its fine entries times their weights (the product of the interpolation
    // weights of both ends), coarse points side by side (vectorised).  A fine point or neighbour outside
    // the grid has zero entries (the padding): adding them changes no sum.
    const Index* levels = h.levels;
    const Index size = h.size;
    const Index nx = level_value(levels, level, NX), ny = level_value(levels, level, NY);
    const Index coarse_nx = level_value(levels, level + 1, NX), coarse_ny = level_value(levels, level + 1, NY);
    const Index coarse_start = level_value(levels, level + 1, START);
    const Index coarse_pad = level_value(levels, level + 1, PAD_X);
    const Index coarse_end = coarse_start + coarse_pad * (coarse_ny + 3);
    Contribution list[9][49];
    Index listed[9];
    for (Index slot = 0; slot < 9; ++slot) listed[slot] = contributions(slot, list[slot]);
    for (Index c = first; c < end; ++c) {
        double* coef = h.coef + c * 9 * size;  // coef[k * size + p]
        double* inverse = h.inverse_diagonal + c * size;
        for (Index iy = 0; iy < ny; ++iy) {
            const Index row = padded_index(levels, level, 0, iy);
            const double* __restrict centre = coef + CENTRE * size + row;
            double* __restrict inv = inverse + row;
            for (Index ix = 0; ix < nx; ++ix) inv[ix] = 1.0 / centre[ix];
        }
        for (Index k = 0; k < 9; ++k)
            for (Index q = coarse_start; q < coarse_end; ++q) coef[k * size + q] = 0.0;
        for (Index slot = 0; slot < 9; ++slot) {
            for (Index qy = 0; qy < coarse_ny; ++qy) {
                double* target = coef + slot * size + padded_index(levels, level + 1, 0, qy);
                for (Index e = 0; e < listed[slot]; ++e) {
                    const Contribution& t = list[slot][e];
                    // fine point (2 qx + px, 2 qy + py) for qx = 0: its padded index
                    const double* a = coef + t.k * size + padded_index(levels, level, t.px, 2 * qy + t.py);
                    add_weighted(target, a, t.weight, coarse_nx);
                }
            }
        }
        // the level's stencils and inverse diagonals as the V-cycle reads them
        const Index level_first = level_begin(h, level), level_end = level_first + level_length(h, level);
        float* single = h.single_coef + c * 9 * size;
        for (Index k = 0; k < 9; ++k) round_range(coef + k * size, single + k * size, level_first, level_end);
        round_range(inverse, h.single_inverse_diagonal + c * size, level_first, level_end);
    }
}

namespace {

//: Points of a row whose Gauss-Seidel values are computed together: what is known of them is kept
//: on the stack (for both components) before the recurrence along the row.
constexpr Index BLOCK = 64;

//: known = b - (the row below's three neighbours) for m points from s (a forward sweep from x = 0).
//: coef (9, size) from the row's first point; below a view from one point before the row.
void known_from_zero(float* __restrict known, const float* __restrict b, const float* __restrict coef,
                     Index size, const float* __restrict below, Index s, Index m) {
    const float* a0 = coef + 0 * size + s;
    const float* a1 = coef + 1 * size + s;
    const float* a2 = coef + 2 * size + s;
    b += s;
    below += s;
    for (Index i = 0; i < m; ++i) known[i] = b[i] - a0[i] * below[i] - a1[i] * below[i + 1] - a2[i] * below[i + 2];
}

//: known = b - every neighbour but the one the recurrence updates: the left one (slot 3) going forward,
//: the right one (slot 5) going backward.  The row's other neighbour (`side`) takes the same place in the
//: sum both ways.
template <bool FORWARD>
void known_beside(float* __restrict known, const float* __restrict b, const float* __restrict coef, Index size,
                  const float* __restrict below, const float* __restrict here, const float* __restrict above,
                  Index s, Index m) {
    const float* a0 = coef + 0 * size + s;
    const float* a1 = coef + 1 * size + s;
    const float* a2 = coef + 2 * size + s;
    const float* side = coef + (FORWARD ? 5 : 3) * size + s;  // the neighbour not yet updated
    const float* a6 = coef + 6 * size + s;
    const float* a7 = coef + 7 * size + s;
    const float* a8 = coef + 8 * size + s;
    b += s;
    below += s;
    here += s + (FORWARD ? 2 : 0);
    above += s;
    for (Index i = 0; i < m; ++i)
        known[i] = b[i] - a0[i] * below[i] - a1[i] * below[i + 1] - a2[i] * below[i + 2] - side[i] * here[i] -
                   a6[i] * above[i] - a7[i] * above[i + 1] - a8[i] * above[i + 2];
}

}  // namespace

template <Index C>
void sweep_components(Hierarchy& h, Index level, bool forward, bool from_zero) {
    // Each row in two passes: what is known before the row's own recurrence (vectorised), then the
    // recurrence along the row.  The components' recurrences run side by side (each fills the
    // others' waits; they never meet, so the values are those of one component after the other),
    // a block of points at a time.  A block's known values read only the row's old values beyond
    // the block (forward: its right neighbours; backward: its left ones), which the recurrence has
    // not reached yet.
    const Index* levels = h.levels;
    const Index size = h.size;
    const Index nx = level_value(levels, level, NX), ny = level_value(levels, level, NY);
    const Index pad = level_value(levels, level, PAD_X);
    float known[C][BLOCK];
    for (Index t = 0; t < ny; ++t) {
        const Index iy = forward ? t : ny - 1 - t;
        const Index base = padded_index(levels, level, 0, iy);
        const Index below = base - pad - 1, here = base - 1, above = base + pad - 1;
        float last[C] = {};  // the row's neighbour just updated (none before the first)
        for (Index done = 0; done < nx; done += BLOCK) {
            const Index m = nx - done < BLOCK ? nx - done : BLOCK;
            const Index s = forward ? done : nx - done - m;  // the block's first point
            for (Index c = 0; c < C; ++c) {
                const float* coef = h.single_coef + c * 9 * size + base;
                const float* b = h.single_b + c * size + base;
                const float* x = h.single_x + c * size;
                if (forward && from_zero) {
                    known_from_zero(known[c], b, coef, size, x + below, s, m);
                } else if (forward) {
                    known_beside<true>(known[c], b, coef, size, x + below, x + here, x + above, s, m);
                } else {
                    known_beside<false>(known[c], b, coef, size, x + below, x + here, x + above, s, m);
                }
            }
            float* xc[C];
            const float* ic[C];
            const float* neighbour[C];  // the slot the recurrence updates: left (3) or right (5)
            for (Index c = 0; c < C; ++c) {
                xc[c] = h.single_x + c * size + base + s;
                ic[c] = h.single_inverse_diagonal + c * size + base + s;
                neighbour[c] = h.single_coef + (c * 9 + (forward ? 3 : 5)) * size + base + s;
            }
            if (forward) {
                for (Index i = 0; i < m; ++i) {
                    for (Index c = 0; c < C; ++c) {
                        last[c] = (known[c][i] - neighbour[c][i] * last[c]) * ic[c][i];
                        xc[c][i] = last[c];
                    }
                }
            } else {
                for (Index i = m - 1; i >= 0; --i) {
                    for (Index c = 0; c < C; ++c) {
                        last[c] = (known[c][i] - neighbour[c][i] * last[c]) * ic[c][i];
                        xc[c][i] = last[c];
                    }
                }
            }
        }
    }
}

void sweep(Hierarchy& h, Index level, bool forward, bool from_zero, Index components) {
    if (components == 3) {
        sweep_components<3>(h, level, forward, from_zero);
    } else {
        sweep_components<2>(h, level, forward, from_zero);
    }
}

namespace {

//: r = b - A x over m points of a row after one forward sweep from x = 0, which solved each point's
//: equation with the values then known: what is left is -U x, the neighbours it had not reached (right,
//: and the row above; coef (9, size) from the row's first point; here, above views of x from one point
//: before the row).
void swept_residual_row(float* __restrict r, const float* __restrict coef, Index size,
                        const float* __restrict here, const float* __restrict above, Index m) {
    const float* a5 = coef + 5 * size;
    const float* a6 = coef + 6 * size;
    const float* a7 = coef + 7 * size;
    const float* a8 = coef + 8 * size;
    for (Index s = 0; s < m; ++s)
        r[s] = -(a5[s] * here[s + 2]) - a6[s] * above[s] - a7[s] * above[s + 1] - a8[s] * above[s + 2];
}

//: b of a coarse row from the fine residual rows around its fine row (views from one point before it).
void restrict_row(float* __restrict b, const float* __restrict below, const float* __restrict here,
                  const float* __restrict above, Index coarse_nx) {
    for (Index s = 0; s < coarse_nx; ++s) {
        const Index t = 2 * s;
        b[s] = here[t + 1] + 0.5f * (here[t] + here[t + 2] + below[t + 1] + above[t + 1]) +
               0.25f * (below[t] + below[t + 2] + above[t] + above[t + 2]);
    }
}

}  // namespace

void restrict_swept_residual(Hierarchy& h, Index level, Index components) {
    static_assert(SWEEPS == 1, "the residual is -U x after one sweep from zero");
    const Index* levels = h.levels;
    const Index size = h.size;
    const Index nx = level_value(levels, level, NX), ny = level_value(levels, level, NY);
    const Index pad = level_value(levels, level, PAD_X);
    const Index coarse_nx = level_value(levels, level + 1, NX), coarse_ny = level_value(levels, level + 1, NY);
    for (Index c = 0; c < components; ++c) {
        const float* coef = h.single_coef + c * 9 * size;
        const float* x = h.single_x + c * size;
        float* b = h.single_b + c * size;
        float* r = h.single_r + c * size;
        for (Index iy = 0; iy < ny; ++iy) {
            const Index base = padded_index(levels, level, 0, iy);
            swept_residual_row(r + base, coef + base, size, x + base - 1, x + base + pad - 1, nx);
        }
        // each coarse point gathers its fine point with weight 1, those beside it with 1/2 and
        // those diagonal to it with 1/4
        for (Index iy = 0; iy < coarse_ny; ++iy) {
            const Index coarse = padded_index(levels, level + 1, 0, iy);
            const Index fine = padded_index(levels, level, 0, 2 * iy);
            restrict_row(b + coarse, r + fine - pad - 1, r + fine - 1, r + fine + pad - 1, coarse_nx);
        }
    }
}

namespace {

//: A fine row += its coarse rows' interpolation (lc, hc the coarse rows iy // 2 and (iy + 1) // 2):
//: fine point ix takes its parents ix // 2 and (ix + 1) // 2, the even and odd points in pairs.
void interpolate_row(float* __restrict xc, const float* __restrict lc, const float* __restrict hc, Index nx) {
    const Index pairs = nx / 2;
    for (Index s = 0; s < pairs; ++s) {
        xc[2 * s] += 0.25f * (lc[s] + lc[s] + hc[s] + hc[s]);
        xc[2 * s + 1] += 0.25f * (lc[s] + lc[s + 1] + hc[s] + hc[s + 1]);
    }
    if (nx % 2 != 0) xc[nx - 1] += 0.25f * (lc[pairs] + lc[pairs] + hc[pairs] + hc[pairs]);
}

}  // namespace

void interpolate(Hierarchy& h, Index level, Index components) {
    const Index* levels = h.levels;
    const Index nx = level_value(levels, level, NX), ny = level_value(levels, level, NY);
    for (Index c = 0; c < components; ++c) {
        float* x = h.single_x + c * h.size;
        for (Index iy = 0; iy < ny; ++iy) {
            const Index low = padded_index(levels, level + 1, 0, iy / 2);
            const Index high = padded_index(levels, level + 1, 0, (iy + 1) / 2);
            interpolate_row(x + padded_index(levels, level, 0, iy), x + low, x + high, nx);
        }
    }
}

void v_cycle_down(Hierarchy& h, Index components) {
    const Index coarsest = h.level_count - 1;
    if (coarsest < 1) return;
    to_single(h, 0, h.b, h.single_b, components);
    for (Index level = 0; level < coarsest; ++level) {
        zero_padding(h, level, h.single_x, components);
        for (Index s = 0; s < SWEEPS; ++s) sweep(h, level, true, s == 0, components);
        restrict_swept_residual(h, level, components);
    }
    to_double(h, coarsest, h.single_b, h.b, components);
}

void v_cycle_up(Hierarchy& h, Index components) {
    const Index coarsest = h.level_count - 1;
    if (coarsest < 1) return;
    to_single(h, coarsest, h.x, h.single_x, components);
    for (Index level = coarsest - 1; level >= 0; --level) {
        interpolate(h, level, components);
        for (Index s = 0; s < SWEEPS; ++s) sweep(h, level, false, false, components);
    }
    to_double(h, 0, h.single_x, h.x, components);
}

}  // namespace wc
