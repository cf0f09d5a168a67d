"""Banded Cholesky factorisation and solve (LAPACK dpbtrf, dpbtrs) callable from compiled code.

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
_dpbtrs = _lapack("dpbtrs", 9)

#: Slots of the int32 argument array ``info`` (a band matrix's size and LAPACK's scalar arguments).
UPLO, N, KD, LDAB, INFO, NRHS, LDB = range(7)


def band_arguments(n: int, kd: int) -> np.ndarray:
    """The int32 argument array for an n x n band matrix of half-bandwidth kd, one right-hand side."""
    return np.array([ord("L"), n, kd, kd + 1, 0, 1, n], dtype=np.int32)


@kernel
def band_factor(band, info):
    """Overwrite ``band`` by its Cholesky factor; return LAPACK's info (0: done, > 0: not positive definite)."""
    _dpbtrf(info[UPLO:].ctypes, info[N:].ctypes, info[KD:].ctypes, band.ctypes, info[LDAB:].ctypes,
            info[INFO:].ctypes)
    return info[INFO]


@kernel
def band_solve(band, b, info):
    """Solve A x = b in place (``b`` of length n) with the factor from ``band_factor``."""
    _dpbtrs(info[UPLO:].ctypes, info[N:].ctypes, info[KD:].ctypes, info[NRHS:].ctypes, band.ctypes,
            info[LDAB:].ctypes, b.ctypes, info[LDB:].ctypes, info[INFO:].ctypes)
    return info[INFO]
