"""Banded Cholesky factorisation and its solves, for the plane preconditioner's in-plane systems.

A band matrix is stored as LAPACK's lower band form: in a C array ``band`` of shape (n, kd + 1),
``band[j, i - j] = A[i, j]`` for ``j <= i <= j + kd`` (the Fortran (kd + 1, n) array with leading
dimension kd + 1).  Both are written here rather than called from LAPACK (``dpbtrf``, ``dpbtrs``):
on the preconditioner's bands (kd up to 41) ``dpbtrf`` runs its unblocked ``dpbtf2``, two BLAS calls
per column, and the calls cost more than the arithmetic; ``dpbtrs``'s transposed solve sums each
row serially.  Measured against LAPACK through SciPy in the same process (``tests/test_kernels.py``
checks the factors against ``scipy.linalg.cholesky_banded``): the factorisation 2.8x faster on
9 x 9 (3.4 against 9.7 us), 2.2x on 21 x 29 (64 against 153 us), 2x on 32 x 32; ``sink_map``'s 16
runs, which refactor at most steps once the cloth sinks, took 4-5 % less CPU time.
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel


@kernel
def band_factor(band, rows):
    """Overwrite ``band`` by its Cholesky factor L (column by column, as LAPACK's dpbtf2: scale the
    column below the diagonal, then subtract its outer product from the block it reaches) and fill
    ``rows`` (same shape) with L by rows for ``band_solve_two``: ``rows[j, t] = L[j, j - kd + t]`` for
    t < kd (row j left of the diagonal, in column order) and ``rows[j, kd] = 1 / L[j, j]``.
    Returns 0, or j + 1 if the leading minor of order j + 1 is not positive definite (LAPACK's info)."""
    n, width = band.shape
    kd = width - 1
    for j in range(n):
        pivot = band[j, 0]
        if not pivot > 0.0:
            return j + 1
        pivot = math.sqrt(pivot)
        band[j, 0] = pivot
        reach = min(kd, n - 1 - j)
        column = band[j, 1:1 + reach]
        for a in range(reach):
            column[a] /= pivot
        for a in range(reach):  # row j + 1 + a of the trailing block, from its diagonal on
            target = band[j + 1 + a, 0:reach - a]
            source = column[a:reach]
            factor = column[a]
            for b in range(reach - a):
                target[b] -= factor * source[b]
    for j in range(n):
        rows[j, kd] = 1.0 / band[j, 0]
        for t in range(kd):
            d = kd - t
            rows[j, t] = band[j - d, d] if j >= d else 0.0
    return 0


@kernel
def band_solve_two(bands, rows, b):
    """Solve two band systems A_c x_c = b_c in place (``bands``, ``rows`` (2, n, kd + 1) from
    ``band_factor``, ``b`` (2, n)): L y = b, then L^T x = y, each column by column (an update of the
    kd entries next to it, over contiguous views, which vectorises).  Each column waits for the one
    before it, so the two systems are solved side by side, each filling the other's waits.  Written
    here rather than called (LAPACK's dpbtrs, whose transposed solve sums each row serially and
    took 44 % of the towel's run, perf): the pair costs 28 us on the towel's bands (609 x 23),
    the plane preconditioner 53, 326 and 5078 us at 32, 64, 128 squared against 73, 379 and 5179
    with dpbtrs."""
    n = b.shape[1]
    kd = bands.shape[2] - 1
    b0, b1 = b[0], b[1]
    for j in range(n):
        y0 = b0[j] * rows[0, j, kd]
        y1 = b1[j] * rows[1, j, kd]
        b0[j] = y0
        b1[j] = y1
        m = min(kd, n - 1 - j)
        _column_update(b0[j + 1:j + 1 + m], bands[0, j, 1:1 + m], y0, b1[j + 1:j + 1 + m], bands[1, j, 1:1 + m], y1)
    for j in range(n - 1, -1, -1):
        x0 = b0[j] * rows[0, j, kd]
        x1 = b1[j] * rows[1, j, kd]
        b0[j] = x0
        b1[j] = x1
        m = min(kd, j)
        _column_update(b0[j - m:j], rows[0, j, kd - m:kd], x0, b1[j - m:j], rows[1, j, kd - m:kd], x1)


@kernel(inline="always")
def _column_update(target0, column0, value0, target1, column1, value1):
    """target_c -= column_c * value_c for both systems, element by element."""
    for k in range(target0.shape[0]):
        target0[k] -= column0[k] * value0
        target1[k] -= column1[k] * value1
