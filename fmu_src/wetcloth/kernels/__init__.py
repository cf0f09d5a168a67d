"""Numba kernels over flat (3, n) arrays, one module per force family.

Fast-math flags leave out ``nnan`` and ``ninf`` so that non-finite values still propagate
and the blow-up guard sees them.  Every kernel is compiled with ``nogil=True``: a process that
runs other Python threads beside the simulation (a Dask worker's event loop, a GUI) would
otherwise take the GIL back and forth with it; in a Dask worker that cost 20 % of a run
(docs/benchmarks.md, Batch studies).
"""

FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}
