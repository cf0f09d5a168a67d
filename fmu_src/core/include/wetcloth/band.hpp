// Banded Cholesky factorisation and the two-system band solve of the plane preconditioner (port of
// bf41571:fmu_src/wetcloth/kernels/lapack.py, with a factorisation of our own in place of LAPACK's dpbtrf).
//
// A band matrix is stored in LAPACK's lower band form: in a C array `band` (n, kd + 1),
// band[j, i - j] = A[i, j] for j <= i <= j + kd, so that row j of the array is column j of A from
// its diagonal down (contiguous).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Overwrite `band` (n, kd + 1) by its Cholesky factor L (A = L L^T), as LAPACK's dpbtrf (its
//: unblocked dpbtf2, column by column: the column scaled by 1 / L[j, j], then the trailing
//: triangle's rank-one update, each over contiguous memory).  Returns 0, or k > 0 if the leading
//: minor of order k is not positive definite (the factorisation stops there).
Index band_cholesky(double* band, Index n, Index kd);

//: `band_cholesky`, then fill `rows` (n, kd + 1) with L by rows for `band_solve_two`:
//: rows[j, t] = L[j, j - kd + t] for t < kd (row j left of the diagonal, in column order, zero
//: before the first column) and rows[j, kd] = 1 / L[j, j].  Returns band_cholesky's info.
Index band_factor(double* band, double* rows, Index n, Index kd);

//: Solve the two band systems A_c x_c = b_c in place (`bands`, `rows` (2, n, kd + 1) from
//: `band_factor`, b (2, n)): L y = b, then L^T x = y, column by column, the two systems side by
//: side (each fills the other's waits on the column before).
void band_solve_two(const double* bands, const double* rows, double* b, Index n, Index kd);

//: The same for one system: band and rows (n, kd + 1), b (n).
void band_solve_one(const double* band, const double* rows, double* b, Index n, Index kd);

}  // namespace wc
