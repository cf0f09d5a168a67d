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
* ``_nrt=False``: numba's reference counting off.  A kernel allocates nothing and keeps no array
  beyond its call (its caller, ultimately Python, owns every array), yet with counting on each
  call took and released a reference to every array of the bundles it was passed, each an atomic
  instruction: on a floating 9 x 9 cloth these took 15 % of the step loop's compiled time (perf),
  and without them a step costs 9-10 % less (docs/benchmarks.md, Large steps).  Kernels that
  allocate arrays, or take self-collision's typed lists (which need the counting even to be
  passed on), are ``counted_kernel``s instead: self-collision's and the step loop's entry points.
"""

from wetcloth.kernels.compilation import compile_kernel

FASTMATH = {"nsz"}
OPTIONS = dict(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy", _nrt=False)


def kernel(function=None, **extra):
    """``@kernel`` or ``@kernel(inline="always")``: a numba-compiled function with the options above."""
    if function is None:
        return lambda f: compile_kernel(f, dict(OPTIONS, **extra))
    return compile_kernel(function, OPTIONS)


def counted_kernel(function=None, **extra):
    """``kernel`` with numba's reference counting on (``_nrt=True``): for kernels that allocate
    arrays or take typed lists."""
    decorate = kernel(_nrt=True, **extra)
    return decorate if function is None else decorate(function)
