"""Numba kernels over flat (3, n) arrays, one module per force family.

Fast-math flags leave out ``nnan`` and ``ninf`` so that non-finite values still propagate
and the blow-up guard sees them.
"""

FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}
