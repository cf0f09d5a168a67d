"""A triangle mesh bent by hinges of rigidity ``bend_rigidity`` (docs/model.md section 2.4): a plate's bending
that converges with refinement, run by the core as linear springs of rest length 0 with the damping of a
Kelvin-Voigt fabric, and refused where it cannot apply."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.model import Model
from wetcloth.topology import HINGE, build_topology

RIGIDITY = 0.5  # N m: a 20 cm cantilever of the default fabric then sags about 2 mm (w / L ~ 1 %: linear)
LENGTH = 0.2  # m, the cantilever's free length
GRAVITY = 9.81  # m/s2
HEIGHT = 0.5  # m, the strip's height in its file


def strip_file(tmp_path, columns: int, width: float = LENGTH, clamp: int = 2):
    """A strip of equilateral triangles in a PLY file: ``columns`` + 1 columns of vertices over x in [0, LENGTH]
    (and ``clamp`` more at x < 0, to pin), alternate columns shifted half a spacing along y, about ``width`` wide."""
    sx = LENGTH / columns
    hy = 2.0 * sx / math.sqrt(3.0)
    rows = round(width / hy) + 1
    index = {}
    points = []
    for c in range(-clamp, columns + 1):
        for r in range(rows):
            index[c, r] = len(points)
            points.append([c * sx, r * hy + (0.5 * hy if c % 2 else 0.0) - 0.5 * width, HEIGHT])
    faces = []
    for c in range(-clamp, columns):
        for r in range(rows - 1):
            a, b, d, e = index[c, r], index[c, r + 1], index[c + 1, r], index[c + 1, r + 1]
            faces += [[a, d, b], [b, d, e]] if c % 2 == 0 else [[a, d, e], [a, e, b]]
    path = tmp_path / f"strip{columns}.ply"
    trimesh.Trimesh(np.array(points), faces, process=False).export(path)
    return path


def cantilever(tmp_path, columns: int, **settings) -> wetcloth.Scene:
    """The strip clamped along x <= 0 (its vertices there pinned), in air without drag, far above floor and water."""
    fields = dict(cloth_mesh=str(strip_file(tmp_path, columns)), bend_rigidity=RIGIDITY, air_density=0.0,
                  pinned_vertices="box:-1,-1,0,1e-9,1,1", water_level=-0.5, self_collision="off")
    return wetcloth.Scene(**(fields | settings))


def hinge_matrix(topo) -> coo_matrix:
    """The hinges' stiffness matrix (n, n) N/m from their springs of rest length 0 (one per coordinate)."""
    hinge = topo.pair_kind == HINGE
    (i, j), k = topo.pairs[:, hinge], topo.pair_stiffness[hinge]
    return coo_matrix((np.concatenate([k, k, -k, -k]), (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))),
                      shape=(topo.n, topo.n)).tocsr()


def static_sag(topo, load: np.ndarray) -> np.ndarray:
    """The hinges' linear static deflection (n,) m of the unpinned particles under a vertical ``load`` (n,) N."""
    free = ~topo.pinned
    sag = np.zeros(topo.n)
    sag[free] = spsolve(hinge_matrix(topo)[free][:, free].tocsc(), load[free])
    return sag


def test_a_cantilever_plate_sags_as_its_rigidity_says_ever_closer_with_refinement(tmp_path):
    """A plate of rigidity D clamped along one edge and loaded by its weight q per area sags at its tip by
    q L^4 / (8 D) (Euler-Bernoulli, per unit width; inextensible, so no anticlastic bend).  The hinges' linear
    static solution comes closer at each halving of the triangles, first order in their size (the free edges'
    half cells carry load but no hinge: 26 %, 15 %, 9 % at 10, 20, 40 columns), where bending springs would
    stiffen as h^-4 (docs/model.md section 2.4)."""
    analytic = wetcloth.Scene().areal_density * GRAVITY * LENGTH**4 / (8.0 * RIGIDITY)
    errors = []
    for columns in (10, 20, 40):
        topo = build_topology(cantilever(tmp_path, columns))
        sag = static_sag(topo, -wetcloth.Scene().areal_density * GRAVITY * topo.area)
        tip = np.isclose(topo.rest_pos[0], LENGTH)
        errors.append(abs(-sag[tip].mean() / analytic - 1.0))
    assert errors[1] < 0.7 * errors[0] and errors[2] < 0.7 * errors[1], errors
    assert errors[2] < 0.1, errors


def test_hinges_hold_a_flat_or_rigidly_moved_sheet_with_no_force_and_damp_bending_by_their_matrix(tmp_path):
    """The core's forces on the flat strip, turned and moved as a whole, are its weight alone (the hinges store
    nothing there); a velocity across the flat sheet adds the damping -(damping / stretch_stiffness) K v of a
    Kelvin-Voigt fabric, K the hinges' (positive semidefinite) matrix, so bending motion only loses energy;
    round-off bounds, scaled by the hinges' stiffest term."""
    scene = cantilever(tmp_path, 10, pinned_vertices="")
    topo = build_topology(scene)
    model = Model(scene)
    turn = np.array([[math.cos(0.3), -math.sin(0.3), 0.0], [math.sin(0.3), math.cos(0.3), 0.0], [0.0, 0.0, 1.0]])
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(0.7), -math.sin(0.7)], [0.0, math.sin(0.7), math.cos(0.7)]])
    pos = tilt @ turn @ topo.rest_pos + np.array([[0.1], [-0.2], [0.3]])
    water = np.zeros(topo.n)
    still = model.forces(pos, np.zeros_like(pos), water).copy()
    weight = model.cloth.dry_mass * GRAVITY
    scale = np.abs(topo.pair_stiffness[topo.pair_kind == HINGE]).max() * LENGTH
    assert np.abs(still[:2]).max() < 1e-12 * scale and np.abs(still[2] + weight).max() < 1e-12 * scale
    vel = np.zeros_like(pos)
    vel[2] = np.random.default_rng(3).normal(size=topo.n)
    flat = model.forces(topo.rest_pos, np.zeros_like(pos), water).copy()
    damped = model.forces(topo.rest_pos, vel, water).copy() - flat
    expected = -(scene.damping / scene.stretch_stiffness) * (hinge_matrix(topo) @ vel[2])
    assert np.abs(damped[2] - expected).max() < 1e-12 * scale * np.abs(vel).max()
    assert vel[2] @ damped[2] < 0.0


def test_the_core_rests_the_cantilever_on_its_hinges_static_solution(tmp_path):
    """Run to rest (implicit Euler at 1 ms, the fabric's bending damped with a 10 ms time constant), the
    core's strip hangs where the hinges' linear statics put it, within the geometric nonlinearity ((w / L)^2
    ~ 1e-4 of the sag) and the membrane's stretch (q L / stretch_stiffness ~ 1e-4 m: nearly inextensible)."""
    scene = cantilever(tmp_path, 10, damping=20.0, integrator="implicit_euler", tolerance=0.0, max_step=1e-3)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.5)
    topo = sim.model.topology
    sag = static_sag(topo, -sim.model.cloth.dry_mass * GRAVITY)
    assert np.abs(sim.positions[:, 2] - HEIGHT - sag).max() < 2e-3 * np.abs(sag).max()


def test_bend_rigidity_is_refused_where_no_hinge_can_carry_it(tmp_path):
    """The grid (built in, or a file of quads that forms it) bends by its springs, and a mesh of quads has no
    edge between two triangles: bend_rigidity > 0 there is a ParameterError naming it and what is allowed."""
    with pytest.raises(ParameterError, match="bend_rigidity.*allowed: 0 N m on the grid"):
        wetcloth.Scene(bend_rigidity=1e-4)
    quads = tmp_path / "quads.obj"
    quads.write_text("v 0 0 1\nv 0.1 0 1\nv 0.2 0 1\nv 0 0.13 1\nv 0.1 0.1 1\nv 0.2 0.1 1\nf 1 2 5 4\nf 2 3 6 5\n")
    with pytest.raises(ParameterError, match="bend_rigidity.*has none; allowed: 0 N m"):
        build_topology(wetcloth.Scene(cloth_mesh=str(quads), bend_rigidity=1e-4))
