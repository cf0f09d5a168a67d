"""The cloth's fixed structure: particle areas and masses, springs and triangles, built once per scene.

Particles sit on an ``nx`` x ``ny`` grid, index ``i = row * nx + col`` (col along x, row along y).
Springs are grouped in *families* that share one index offset: spring ``i`` of a family joins
particle ``i`` to particle ``i + offset``.  A missing spring (across the grid's edge) has zero
stiffness.  This layout lets every kernel loop over flat arrays with no index lists.

A cloth from a mesh has no families: its springs are *listed*, each with its two particles
(``pairs``) and its own rest length, the tension-only ones first.  A grid lists none.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wetcloth.scene import Scene


#: Kinds of listed springs (Topology.pair_kind): along a face's edge, across a quad, bending.
STRETCH, SHEAR, BEND = 0, 1, 2


@dataclass(frozen=True)
class Topology:
    """Grid connectivity and per-particle constants (SI units)."""

    nx: int
    ny: int
    dx: float  # m, rest spacing along x
    dy: float  # m, rest spacing along y
    rest_xy: np.ndarray  # (2, n) m, particle coordinates in the flat rest sheet, centred on 0
    area: np.ndarray  # (n,) m2, each particle's share of the sheet
    spring_offset: np.ndarray  # (F,) int64, index offset of each family
    spring_rest: np.ndarray  # (F,) m, rest length of each family
    spring_tension_only: np.ndarray  # (F,) bool: True for structural and shear springs
    spring_stiffness: np.ndarray  # (F, n) N/m, zero where a family has no spring
    spring_damping: np.ndarray  # (F, n) N s/m
    spring_shape: np.ndarray  # (F, n) strip area / rest length^2 (-): stiffness = modulus * shape
    spring_family_names: tuple[str, ...]
    triangles: np.ndarray  # (m, 3) int64, counter-clockwise seen from +z in the rest sheet
    pinned: np.ndarray  # (n,) bool
    # Listed springs (a mesh's; none on a grid): spring k joins pairs[0, k] and pairs[1, k].
    pairs: np.ndarray = field(default_factory=lambda: np.zeros((2, 0), dtype=np.int64))  # (2, S)
    pair_rest: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (S,) m
    pair_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (S,) N/m
    pair_damping: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (S,) N s/m
    pair_shape: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (S,) strip area / rest length^2
    pair_kind: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int8))  # (S,) 0 stretch, 1 shear, 2 bend
    pair_tension_count: int = 0  # the first pair_tension_count listed springs are tension-only
    mesh: object = None  # a mesh cloth's faces and UVs for export; None for a grid

    @property
    def n(self) -> int:
        return self.area.shape[0]

    @property
    def is_grid(self) -> bool:
        """Whether the springs are a grid's families (not listed), whatever file the cloth came from."""
        return self.pairs.shape[1] == 0

    def per_particle_pair_sum(self, values: np.ndarray, kinds=None) -> np.ndarray:
        """Sum (n) onto both ends of each listed spring of a per-listed-spring quantity (S,), only the
        springs whose kind is in ``kinds`` if given."""
        keep = np.ones(len(values), dtype=bool) if kinds is None else np.isin(self.pair_kind, kinds)
        return (np.bincount(self.pairs[0, keep], values[keep], minlength=self.n)
                + np.bincount(self.pairs[1, keep], values[keep], minlength=self.n))

    def per_particle_sum(self, per_spring: np.ndarray, offsets: np.ndarray | None = None) -> np.ndarray:
        """Sum (n) over the springs touching each particle of a per-spring quantity (F, n), whose
        families have ``offsets`` (default: all families, ``spring_offset``)."""
        offsets = self.spring_offset if offsets is None else offsets
        n = self.n
        total = np.zeros(n)
        for values, off in zip(per_spring, offsets):
            total[: n - off] += values[: n - off]
            total[off:] += values[: n - off]
        return total

    @property
    def spring_count(self) -> int:
        """Number of actual springs (families' zero-stiffness slots not counted)."""
        return int(np.count_nonzero(self.spring_stiffness)) + int(np.count_nonzero(self.pair_stiffness))


def _edge_weights(count: int) -> np.ndarray:
    """1 inside, 1/2 on the edges: a particle's share of the cells along one axis."""
    w = np.ones(count)
    w[0] = w[-1] = 0.5
    return w


def build_topology(scene: Scene) -> Topology:
    """Build the grid topology and per-spring constants of ``scene``."""
    nx, ny = scene.nx, scene.ny
    n = nx * ny
    dx = scene.width / (nx - 1)
    dy = scene.length / (ny - 1)
    col = np.tile(np.arange(nx), ny)
    row = np.repeat(np.arange(ny), nx)
    rest_xy = np.stack([col * dx - 0.5 * scene.width, row * dy - 0.5 * scene.length])
    wc = _edge_weights(nx)[col]
    wr = _edge_weights(ny)[row]
    area = dx * dy * wc * wr

    # Each spring stands for a strip of the sheet of area a_s; with rest length l its constant
    # is k = stiffness * a_s / l**2 (= stiffness * width / length), likewise for damping.
    diag = np.hypot(dx, dy)
    families = [
        # name, offset, rest length, strip area per spring, exists, tension only, bending
        ("structural_x", 1, dx, dx * dy * wr, col < nx - 1, True, False),
        ("structural_y", nx, dy, dy * dx * wc, row < ny - 1, True, False),
        ("shear_up_right", nx + 1, diag, np.full(n, 0.5 * dx * dy), (col < nx - 1) & (row < ny - 1), True, False),
        ("shear_up_left", nx - 1, diag, np.full(n, 0.5 * dx * dy), (col > 0) & (row < ny - 1), True, False),
        ("bend_x", 2, 2 * dx, 2 * dx * dy * wr, col < nx - 2, False, True),
        ("bend_y", 2 * nx, 2 * dy, 2 * dy * dx * wc, row < ny - 2, False, True),
    ]
    names, offsets, rests, tension, ks, cs, shapes = [], [], [], [], [], [], []
    for name, offset, rest, strip_area, exists, tension_only, bending in families:
        modulus = scene.bend_stiffness if bending else scene.stretch_stiffness
        if modulus == 0.0 or not exists.any():
            continue
        names.append(name)
        offsets.append(offset)
        rests.append(rest)
        tension.append(tension_only)
        ks.append(np.where(exists, modulus * strip_area / rest**2, 0.0))
        cs.append(np.where(exists, scene.damping * strip_area / rest**2, 0.0))
        shapes.append(np.where(exists, strip_area / rest**2, 0.0))

    quads = (col < nx - 1) & (row < ny - 1)
    a = np.flatnonzero(quads)
    triangles = np.concatenate(
        [np.stack([a, a + 1, a + nx + 1], axis=1), np.stack([a, a + nx + 1, a + nx], axis=1)]
    )
    return Topology(
        nx=nx,
        ny=ny,
        dx=dx,
        dy=dy,
        rest_xy=rest_xy,
        area=area,
        spring_offset=np.array(offsets, dtype=np.int64),
        spring_rest=np.array(rests, dtype=np.float64),
        spring_tension_only=np.array(tension, dtype=np.bool_),
        spring_stiffness=np.array(ks, dtype=np.float64).reshape(len(ks), n),
        spring_damping=np.array(cs, dtype=np.float64).reshape(len(cs), n),
        spring_shape=np.array(shapes, dtype=np.float64).reshape(len(shapes), n),
        spring_family_names=tuple(names),
        triangles=triangles.astype(np.int64),
        pinned=_pinned_mask(scene.pinned_edge, col, row, nx, ny),
    )


def _pinned_mask(edge: str, col: np.ndarray, row: np.ndarray, nx: int, ny: int) -> np.ndarray:
    return {
        "none": np.zeros(col.shape, dtype=bool),
        "x_min": col == 0,
        "x_max": col == nx - 1,
        "y_min": row == 0,
        "y_max": row == ny - 1,
    }[edge]
