// Banded Cholesky factorisation and band solves (port of bf41571:fmu_src/wetcloth/kernels/lapack.py).
#include "wetcloth/band.hpp"

#include <algorithm>
#include <cmath>

namespace wc {

namespace {

//: target -= x * value over m entries.
inline void axpy_down(double* __restrict target, const double* __restrict x, double value, Index m) {
    for (Index t = 0; t < m; ++t) target[t] -= x[t] * value;
}

//: target = (target - x * value) - y * other over m entries: two columns' updates, in column order.
inline void axpy_down_two(double* __restrict target, const double* __restrict x, double value,
                          const double* __restrict y, double other, Index m) {
    for (Index t = 0; t < m; ++t) target[t] = (target[t] - x[t] * value) - y[t] * other;
}

}  // namespace

Index band_cholesky(double* band, Index n, Index kd) {
    // LAPACK's dpbtf2 (lower), right-looking: column j is scaled by 1 / L[j, j], then the trailing
    // triangle takes the rank-one update A[i, k] -= L[i, j] L[k, j] (row j + k of the array is
    // column j + k of A from its diagonal: contiguous).  Two columns at a time: column j + 1 takes
    // column j's update and is factored, then each later entry takes both updates in one pass, in
    // column order as dpbtf2 does (the same values; half the passes over memory).  dpbtrf's blocked
    // variant (kd > 32) computes the same quantities with another summation order.
    const Index width = kd + 1;
    for (Index j = 0; j < n;) {
        double* column = band + j * width;
        double ajj = column[0];
        if (ajj <= 0.0) return j + 1;  // not positive definite (a NaN goes on, as in LAPACK)
        ajj = std::sqrt(ajj);
        column[0] = ajj;
        const Index kn = std::min(kd, n - 1 - j);
        if (kn == 0) {  // the last column, or a diagonal matrix (kd = 0): nothing below it
            ++j;
            continue;
        }
        const double scale = 1.0 / ajj;
        for (Index t = 1; t <= kn; ++t) column[t] *= scale;
        // column j + 1: column j's update, then its own factorisation
        double* next = band + (j + 1) * width;
        axpy_down(next, column + 1, column[1], kn);
        double anext = next[0];
        if (anext <= 0.0) {  // (column j's update of the later columns first, as dpbtf2 left them)
            for (Index k = 2; k <= kn; ++k) axpy_down(band + (j + k) * width, column + k, column[k], kn - k + 1);
            return j + 2;
        }
        anext = std::sqrt(anext);
        next[0] = anext;
        const Index kn1 = std::min(kd, n - 2 - j);  // column j + 1's length below its diagonal
        const double scale1 = 1.0 / anext;
        for (Index t = 1; t <= kn1; ++t) next[t] *= scale1;
        // columns j + k, k >= 2: both updates (column j reaches j + kn, column j + 1 one further
        // when kn = kd)
        for (Index k = 2; k <= kn1 + 1; ++k) {
            double* target = band + (j + k) * width;
            const Index both = kn - k + 1;  // entries of column j + k that column j reaches
            if (k <= kn) {
                axpy_down_two(target, column + k, column[k], next + k - 1, next[k - 1], both);
                axpy_down(target + both, next + k - 1 + both, next[k - 1], kn1 - k + 2 - both);
            } else {
                axpy_down(target, next + k - 1, next[k - 1], kn1 - k + 2);
            }
        }
        j += 2;
    }
    return 0;
}

Index band_factor(double* band, double* rows, Index n, Index kd) {
    const Index info = band_cholesky(band, n, kd);
    if (info != 0) return info;
    const Index width = kd + 1;
    for (Index j = 0; j < n; ++j) {
        double* row = rows + j * width;
        row[kd] = 1.0 / band[j * width];
        for (Index t = 0; t < kd; ++t) {
            const Index d = kd - t;
            row[t] = j >= d ? band[(j - d) * width + d] : 0.0;
        }
    }
    return 0;
}

namespace {

//: target_c -= column_c * value_c for both systems, element by element.
inline void column_update(double* __restrict target0, const double* __restrict column0, double value0,
                          double* __restrict target1, const double* __restrict column1, double value1, Index m) {
    for (Index k = 0; k < m; ++k) {
        target0[k] -= column0[k] * value0;
        target1[k] -= column1[k] * value1;
    }
}

//: target_c = (target_c - column_c * value_c) - next_c * other_c for both systems: two columns'
//: updates in column order.
inline void column_update_two(double* __restrict target0, const double* __restrict column0, double value0,
                              const double* __restrict next0, double other0, double* __restrict target1,
                              const double* __restrict column1, double value1, const double* __restrict next1,
                              double other1, Index m) {
    for (Index k = 0; k < m; ++k) {
        target0[k] = (target0[k] - column0[k] * value0) - next0[k] * other0;
        target1[k] = (target1[k] - column1[k] * value1) - next1[k] * other1;
    }
}

}  // namespace

void band_solve_two(const double* bands, const double* rows, double* b, Index n, Index kd) {
    // L y = b, then L^T x = y, each column by column: an update of the kd entries next to it, over
    // contiguous memory, which vectorises.  Each column waits for the one before it, so the two
    // systems are solved side by side, each filling the other's waits.  Written here rather than
    // LAPACK's dpbtrs, whose transposed solve sums each row serially (44 % of the towel's run).
    // Two columns at a time: the second takes the first's update of its own entry, then the entries
    // both reach take both updates in one pass, in column order (the same values as one column at a
    // time; half the passes over b).
    const Index width = kd + 1;
    const double* band0 = bands;
    const double* band1 = bands + n * width;
    const double* rows0 = rows;
    const double* rows1 = rows + n * width;
    double* b0 = b;
    double* b1 = b + n;
    if (kd == 0) {  // diagonal: y = b / L[j, j], then x = y / L[j, j]
        for (Index j = 0; j < n; ++j) {
            b0[j] = b0[j] * rows0[j];
            b1[j] = b1[j] * rows1[j];
        }
        for (Index j = n - 1; j >= 0; --j) {
            b0[j] = b0[j] * rows0[j];
            b1[j] = b1[j] * rows1[j];
        }
        return;
    }
    // L y = b: column j reaches j + 1 .. j + m (band[j, 1 .. m])
    Index j = 0;
    for (; j + 1 < n; j += 2) {
        const double y0 = b0[j] * rows0[j * width + kd];
        const double y1 = b1[j] * rows1[j * width + kd];
        b0[j] = y0;
        b1[j] = y1;
        const Index m = std::min(kd, n - 1 - j);       // >= 1
        const Index m_next = std::min(kd, n - 2 - j);  // column j + 1's reach; j + 1 + m_next >= j + m
        const double* c0 = band0 + j * width;
        const double* c1 = band1 + j * width;
        const double* d0 = band0 + (j + 1) * width;
        const double* d1 = band1 + (j + 1) * width;
        const double z0 = (b0[j + 1] - c0[1] * y0) * rows0[(j + 1) * width + kd];
        const double z1 = (b1[j + 1] - c1[1] * y1) * rows1[(j + 1) * width + kd];
        b0[j + 1] = z0;
        b1[j + 1] = z1;
        // entries j + 2 .. j + m: both columns; j + m + 1 .. j + 1 + m_next: column j + 1 only
        column_update_two(b0 + j + 2, c0 + 2, y0, d0 + 1, z0, b1 + j + 2, c1 + 2, y1, d1 + 1, z1, m - 1);
        const Index rest = m_next + 1 - m;  // 0 or 1
        column_update(b0 + j + 1 + m, d0 + m, z0, b1 + j + 1 + m, d1 + m, z1, rest);
    }
    if (j < n) {  // the last column (n odd)
        b0[j] = b0[j] * rows0[j * width + kd];
        b1[j] = b1[j] * rows1[j * width + kd];
    }
    // L^T x = y: column j reaches j - m .. j - 1 (rows[j, kd - m .. kd - 1])
    j = n - 1;
    for (; j >= 1; j -= 2) {
        const double x0 = b0[j] * rows0[j * width + kd];
        const double x1 = b1[j] * rows1[j * width + kd];
        b0[j] = x0;
        b1[j] = x1;
        const Index m = std::min(kd, j);            // >= 1
        const Index m_next = std::min(kd, j - 1);   // column j - 1's reach; j - 1 - m_next >= j - m - 1
        const double* c0 = rows0 + j * width + kd;  // c[-d] = L[j, j - d]
        const double* c1 = rows1 + j * width + kd;
        const double* d0 = rows0 + (j - 1) * width + kd;
        const double* d1 = rows1 + (j - 1) * width + kd;
        const double w0 = (b0[j - 1] - c0[-1] * x0) * d0[0];
        const double w1 = (b1[j - 1] - c1[-1] * x1) * d1[0];
        b0[j - 1] = w0;
        b1[j - 1] = w1;
        // entries j - m .. j - 2: both columns; j - 1 - m_next .. j - m - 1: column j - 1 only
        column_update_two(b0 + j - m, c0 - m, x0, d0 - m + 1, w0, b1 + j - m, c1 - m, x1, d1 - m + 1, w1, m - 1);
        const Index rest = m_next + 1 - m;  // 0 or 1
        column_update(b0 + j - 1 - m_next, d0 - m_next, w0, b1 + j - 1 - m_next, d1 - m_next, w1, rest);
    }
    if (j == 0) {  // the first column (n odd)
        b0[0] = b0[0] * rows0[kd];
        b1[0] = b1[0] * rows1[kd];
    }
}

void band_solve_one(const double* band, const double* rows, double* b, Index n, Index kd) {
    const Index width = kd + 1;
    for (Index j = 0; j < n; ++j) {  // L y = b: column j reaches j + 1 .. j + m
        const double y = b[j] * rows[j * width + kd];
        b[j] = y;
        const Index m = std::min(kd, n - 1 - j);
        axpy_down(b + j + 1, band + j * width + 1, y, m);
    }
    for (Index j = n - 1; j >= 0; --j) {  // L^T x = y: column j reaches j - m .. j - 1
        const double x = b[j] * rows[j * width + kd];
        b[j] = x;
        const Index m = std::min(kd, j);
        axpy_down(b + j - m, rows + j * width + kd - m, x, m);
    }
}

}  // namespace wc
