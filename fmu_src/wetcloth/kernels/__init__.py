"""Numba kernels over flat (3, n) arrays, one module per force family, and the compiled step loop.

Every kernel is compiled by ``kernel``, on its own (its callers call it, they do not copy it: see
``compilation``), with one set of options, stated here once:

* ``cache=True``: compiled code is kept beside the sources, so a new process starts in a second;
  it is used only while every kernel source is as it was compiled (``compilation.KernelCache``).
* ``nogil=True``: a process that runs other Python threads beside the simulation (a Dask worker's
  event loop, a GUI) would otherwise take the GIL back and forth with it; in a Dask worker that
  cost 20 % of a run (docs/benchmarks.md, Batch studies).
* ``fastmath`` limited to ``nsz`` (signed zeros may be ignored), nothing that changes values:
  with reassociation (``reassoc``) or fused multiply-add (``contract``) LLVM's choices depend on
  what it inlines, and a kernel compiled in this process then gave other results (by 1e-7 of
  the state after 15 s of the thesis towel) than the same kernel loaded from the cache in the next
  process: Dask workers and the process that started them disagreed.  Element-wise loops
  vectorise without them; on the towel the step loop measured no slower without them.
* ``error_model="numpy"``: a division by zero gives inf or nan, as in NumPy, instead of raising;
  without it every division carries a zero check that keeps its loop from vectorising.
"""

from wetcloth.kernels.compilation import compile_kernel

FASTMATH = {"nsz"}
OPTIONS = dict(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy")


def kernel(function=None, **extra):
    """``@kernel`` or ``@kernel(inline="always")``: a numba-compiled function with the options above."""
    if function is None:
        return lambda f: compile_kernel(f, dict(OPTIONS, **extra))
    return compile_kernel(function, OPTIONS)
