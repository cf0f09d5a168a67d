"""A try for issue 26 (bench/tablecloth_drape.py --hinge, bench/mesh_bending.py --hinge): a triangle mesh's
bending as a quadratic hinge energy (Bergou et al. 2006, "A quadratic bending model for inextensible
surfaces"; the discrete shells' hinge of Grinspun et al. 2003 linearised about the flat rest sheet) instead of
the springs across two triangles' opposite corners, whose energy grows as the fold angle^4 (bench/mesh_bending.py).

Per edge e shared by triangles (i, j, k) and (i, j, l), flat at rest: with w_m = n . (grad b_m(2) - grad b_m(1))
(b_m the corners' linear shape functions, n the edge's normal in the plane from k's side to l's: sum_m w_m f_m
is the jump in the gradient of a linear field f across the edge, the fold angle for f the height), the energy
D |e|^2 / (2 (A1 + A2)) |sum_m w_m x_m|^2 (J; D the rigidity, N m), zero for any flat or rigidly moved hinge;
a sheet bent to a curvature kappa stores D kappa^2 / 2 per area on equilateral triangles (whatever the bend's
direction), 1.12-1.16 times that on docs/make_meshes.py's jittered discs at every resolution
(bench/mesh_bending.py --hinge).  Quadratic in the positions, it is a sum over the hinge's six pairs of
both-ways springs of rest length 0 and stiffness -D |e|^2 / (A1 + A2) w_a w_b (N/m, some negative; the hinge's
sum is positive semidefinite), which the core's listed springs run as they are.  For meshes of triangles only
(every bending spring is replaced).

What it gave at D = 6e-5 N m (about the springs' bending at the preset's 2k vertices and fold radii of 5 to
10 cm), 2 s, on a shared 2-core EPYC (bench/tablecloth_drape.py --duration 2 --hinge 6e-5): hems at 2k, 4k,
8k vertices 0.4553, 0.4553, 0.4534 m (seed 26) and 0.4541, 0.4557, 0.4535 m (seed 27), 2k seed 28 0.4544 m
(the springs: 0.4570, 0.4555 m, 0.4518 m on a Xeon at 8k, seed 26; 0.4568, 0.4558 m seed 27); none into the
table, the centre at the top + e/2; 1.48x the CPU time at 2k (33.0 s against 22.3 s, run in turn), 1.35x
the steps, 1.5x the listed springs.  The 8k meshes still hang 2 mm below the 4k ones.
"""

from __future__ import annotations

import contextlib

import numpy as np

from wetcloth import topology


def hinges(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each interior edge's corners (m, 4: i, j, then k and l opposite), weights w (m, 4, 1/m) and
    |e|^2 / (2 (A1 + A2)) (m,) of a flat mesh (points (n, 3) m)."""
    rows = np.concatenate([triangles[:, [0, 1, 2]], triangles[:, [1, 2, 0]], triangles[:, [2, 0, 1]]])
    key = np.sort(rows[:, :2], axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, opposite = key[order], rows[order, 2]
    a = np.flatnonzero((key[1:] == key[:-1]).all(axis=1))  # rows a and a + 1: one edge's two triangles
    corners = np.column_stack([key[a], opposite[a], opposite[a + 1]])
    p = [points[corners[:, m]] for m in range(4)]
    edge = p[1] - p[0]
    length = np.linalg.norm(edge, axis=1)
    u = edge / length[:, None]
    to_l = p[3] - p[0]
    v = to_l - (to_l * u).sum(axis=1)[:, None] * u
    v /= np.linalg.norm(v, axis=1)[:, None]
    # the corners in the edge's frame (i at 0, j on the u axis, l at v > 0, k at v < 0)
    q = [np.column_stack([((x - p[0]) * u).sum(axis=1), ((x - p[0]) * v).sum(axis=1)]) for x in p]

    def normal_gradients(a_, b_, c_):
        """The v components of the gradients of a triangle's three shape functions (1/m) and its area (m2)."""
        twice = (b_[:, 0] - a_[:, 0]) * (c_[:, 1] - a_[:, 1]) - (b_[:, 1] - a_[:, 1]) * (c_[:, 0] - a_[:, 0])
        return [(y[:, 0] - x[:, 0]) / twice for x, y in ((b_, c_), (c_, a_), (a_, b_))], 0.5 * np.abs(twice)

    g1, area1 = normal_gradients(q[0], q[1], q[2])
    g2, area2 = normal_gradients(q[0], q[1], q[3])
    w = np.column_stack([g2[0] - g1[0], g2[1] - g1[1], -g1[2], g2[2]])
    return corners, w, length**2 / (2.0 * (area1 + area2))


def hinge_springs(points: np.ndarray, triangles: np.ndarray, rigidity: float) -> tuple[np.ndarray, np.ndarray]:
    """The hinges' springs of rest length 0: pairs (2, P) and stiffness (P,) N/m, a pair shared by hinges once."""
    corners, w, scale = hinges(points, triangles)
    pairs, stiffness = [], []
    for a in range(4):
        for b in range(a + 1, 4):
            pairs.append(np.sort(corners[:, [a, b]], axis=1))
            stiffness.append(-2.0 * rigidity * scale * w[:, a] * w[:, b])
    unique, inverse = np.unique(np.concatenate(pairs), axis=0, return_inverse=True)
    return unique.T.astype(np.int64), np.bincount(inverse.ravel(), np.concatenate(stiffness), minlength=len(unique))


@contextlib.contextmanager
def hinge_bending(rigidity: float):
    """Within it, a triangle mesh's cloth bends by hinge_springs of ``rigidity`` (N m) instead of its bending
    springs, undamped: damped along each spring (damping_model 'projected') with c / k = damping / bend_stiffness
    as the springs were, the pairs' dampers of mixed signs along differing directions sum to no positive form,
    and the tablecloth at 1/30 s frame steps gained 2.8e-5 J in a frame (bench/frame_steps.py tablecloth)."""
    listed = topology.listed_springs

    def with_hinges(mesh, scene):
        springs = listed(mesh, scene)
        keep = springs["pair_kind"] != topology.BEND
        pairs, k = hinge_springs(mesh.points, mesh.triangles, rigidity)
        added = dict(pairs=pairs, pair_rest=np.zeros(len(k)), pair_stiffness=k,
                     pair_damping=np.zeros(len(k)), pair_shape=k / scene.bend_stiffness,
                     pair_kind=np.full(len(k), topology.BEND, dtype=np.int8))
        for name, value in added.items():
            springs[name] = np.concatenate([springs[name][..., keep], value], axis=-1)
        return springs

    topology.listed_springs = with_hinges
    try:
        yield
    finally:
        topology.listed_springs = listed
