"""A grid's springs as a mesh's listed springs: the same cloth through the core's mesh path (listed
springs, drag over the triangle list, the mesh preconditioner), to test that path against the grid's."""

from __future__ import annotations

import dataclasses

import numpy as np

from wetcloth.topology import BEND, SHEAR, STRETCH, Topology

_KIND = {"structural_x": STRETCH, "structural_y": STRETCH, "shear_up_right": SHEAR, "shear_up_left": SHEAR,
         "bend_x": BEND, "bend_y": BEND}


def listed_from_grid(topo: Topology) -> Topology:
    """``topo`` (a grid's) with every family's springs listed instead (tension-only first)."""
    columns = []
    for f, name in enumerate(topo.spring_family_names):
        first = np.flatnonzero(topo.spring_stiffness[f] != 0.0)
        columns.append((first, first + topo.spring_offset[f], np.full(len(first), topo.spring_rest[f]),
                        topo.spring_stiffness[f, first], topo.spring_damping[f, first], topo.spring_shape[f, first],
                        np.full(len(first), _KIND[name], dtype=np.int8), topo.spring_tension_only[f]))
    columns.sort(key=lambda c: not c[7])  # tension-only families first (a stable sort keeps their order)
    first, second, rest, k, c, shape, kind = (np.concatenate(parts) for parts in list(zip(*columns))[:7])
    families = dict(spring_offset=np.zeros(0, dtype=np.int64), spring_rest=np.zeros(0),
                    spring_tension_only=np.zeros(0, dtype=bool), spring_stiffness=np.zeros((0, topo.n)),
                    spring_damping=np.zeros((0, topo.n)), spring_shape=np.zeros((0, topo.n)), spring_family_names=())
    return dataclasses.replace(
        topo, **families, pairs=np.stack([first, second]).astype(np.int64), pair_rest=rest, pair_stiffness=k,
        pair_damping=c, pair_shape=shape, pair_kind=kind,
        pair_tension_count=int(sum(len(col[0]) for col in columns if col[7])))
