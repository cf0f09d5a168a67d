"""Banded Cholesky factorisation (LAPACK dpbtrf) callable from compiled code, and its solve.

SciPy ships LAPACK with Cython bindings; ``scipy.linalg.cython_lapack`` exports each routine's
address.  It is registered with LLVM under a name of ours, and the kernels call that name as an
external function: unlike a ctypes pointer (an address baked into the code), a name lets numba
cache the compiled kernels, and each process binds it anew when this module is imported.  A band matrix is stored as LAPACK's
lower band form: in a C array ``band`` of shape (n, kd + 1), ``band[j, i - j] = A[i, j]`` for
``j <= i <= j + kd`` (the Fortran (kd + 1, n) array with leading dimension kd + 1).
"""

from __future__ import annotations

import llvmlite.binding
import numpy as np
from numba import types
from numba.extending import get_cython_function_address

from wetcloth.kernels import kernel


def _lapack(name: str, arguments: int):
    symbol = f"wetcloth_lapack_{name}"
    llvmlite.binding.add_symbol(symbol, get_cython_function_address("scipy.linalg.cython_lapack", name))
    return types.ExternalFunction(symbol, types.void(*[types.voidptr] * arguments))


_dpbtrf = _lapack("dpbtrf", 6)

#: Slots of the int32 argument array ``info`` (a band matrix's size and LAPACK's scalar arguments).
UPLO, N, KD, LDAB, INFO = range(5)


def band_arguments(n: int, kd: int) -> np.ndarray:
    """The int32 argument array of dpbtrf for an n x n band matrix of half-bandwidth kd."""
    return np.array([ord("L"), n, kd, kd + 1, 0], dtype=np.int32)


@kernel
def band_factor(band, rows, info):
    """Overwrite ``band`` by its Cholesky factor L (LAPACK's dpbtrf) and fill ``rows`` (same shape)
    with L by rows for ``band_solve_two``: ``rows[j, t] = L[j, j - kd + t]`` for t < kd (row j left
    of the diagonal, in column order) and ``rows[j, kd] = 1 / L[j, j]``.  Returns LAPACK's info
    (0: done, > 0: not positive definite)."""
    _dpbtrf(info[UPLO:].ctypes, info[N:].ctypes, info[KD:].ctypes, band.ctypes, info[LDAB:].ctypes,
            info[INFO:].ctypes)
    if info[INFO] != 0:
        return info[INFO]
    n, width = band.shape
    kd = width - 1
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
