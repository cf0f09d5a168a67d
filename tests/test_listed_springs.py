"""A mesh's listed springs, face drag over its triangle list, wicking over its listed links and its
preconditioner, checked against the grid's families on the same cloth (tests/support/listed.py lists
a grid's springs): the mesh path computes the same forces, Jacobians and motion.

Sums over a particle's springs come in another order on the two paths, so forces agree to round-off:
ROUND_OFF relative to the largest force (a few ulp of each of the ~16 terms summed per particle)."""

import dataclasses

import numpy as np
import pytest
from support.listed import listed_from_grid

from wetcloth import _core, load_scene
from wetcloth.model import Model
from wetcloth.simulation import Simulation
from wetcloth.topology import build_topology

ROUND_OFF = 1e-13


def hanging(**overrides):
    """A 21 x 17 sheet pinned along y_max, released horizontal in a vacuum (drag is tested on its own)."""
    values = dict(nx=21, ny=17, width=1.0, length=0.8, pinned_edge="y_max", initial_height=2.0, water_level=-10.0,
                  floor_level=-20.0, air_density=0.0)
    return load_scene(**{**values, **overrides})


def random_state(topo, seed=1):
    """Positions near the rest sheet (every spring stretched or compressed a little), random velocities."""
    rng = np.random.default_rng(seed)
    pos = np.stack([topo.rest_xy[0], topo.rest_xy[1], np.zeros(topo.n)]) + 0.01 * rng.standard_normal((3, topo.n))
    return pos, rng.standard_normal((3, topo.n)), 0.5 * rng.random(topo.n) * 1e-3


@pytest.mark.parametrize("damping_model", ["projected", "thesis"])
def test_listed_springs_give_the_families_forces_blocks_and_products(damping_model):
    scene = hanging(damping_model=damping_model, wet_stiffness_factor=0.5, absorption_capacity=2.0)
    grid = Model(scene)
    listed = Model(scene, topology=listed_from_grid(grid.topology))
    pos, vel, water = random_state(grid.topology)
    expected = grid.forces(pos, vel, water).copy()
    scale = np.abs(expected).max()
    np.testing.assert_allclose(listed.forces(pos, vel, water), expected, rtol=0, atol=ROUND_OFF * scale)

    h = 1e-2
    for model in (grid, listed):
        model.forces_and_blocks(pos, vel, water, h)
    for name in ("force", "diagonal_blocks", "blocks"):
        a, b = getattr(grid.work, name), getattr(listed.work, name)
        np.testing.assert_allclose(b, a, rtol=0, atol=ROUND_OFF * max(np.abs(a).max(), 1e-300), err_msg=name)
    p = np.random.default_rng(2).standard_normal((3, grid.topology.n))
    mass = grid.mass(water)
    products = []
    for model in (grid, listed):
        out = np.zeros((3, grid.topology.n))
        _core.system_matvec(model.cloth, model.work, mass, p, out)
        products.append(out)
    np.testing.assert_allclose(products[1], products[0], rtol=0, atol=ROUND_OFF * np.abs(products[0]).max())


def test_drag_over_a_triangle_list_is_the_grids():
    """Both paths give each triangle the same drag and share it among its corners by their Voronoi areas
    (the grid's 1/2, 1/4, 1/4 on its right triangles), so every particle gets the same drag, in water and in
    air with wind: to round-off of its largest force."""
    scene = hanging(water_level=0.0, initial_height=0.0, air_density=1.2, wind_x=3.0, current_x=0.2)
    grid = Model(scene)
    listed = Model(scene, topology=listed_from_grid(grid.topology))
    pos, vel, water = random_state(grid.topology, seed=3)
    expected = grid.forces(pos, vel, water).copy()
    assert 0.0 < grid.submerged.mean() < 1.0  # both fluids act
    np.testing.assert_allclose(listed.forces(pos, vel, water), expected, rtol=0, atol=ROUND_OFF * np.abs(expected).max())
    for model in (grid, listed):
        model.forces_and_blocks(pos, vel, water, 1e-2)
    np.testing.assert_allclose(listed.work.blocks, grid.work.blocks, rtol=0,
                               atol=ROUND_OFF * np.abs(grid.work.blocks).max())


def test_stokes_drag_and_smooth_buoyancy_on_a_triangle_list_are_the_grids():
    """The per-particle water forces (Stokes drag, smooth buoyancy and its position Jacobian) come after a
    mesh's sums of springs and face drag: with them, in water and air, every particle's force and blocks
    are the grid's to round-off."""
    scene = hanging(water_level=0.0, initial_height=0.0, air_density=1.2, wind_x=3.0, current_x=0.2,
                    drag_model="stokes", buoyancy_model="smooth")
    grid = Model(scene)
    listed = Model(scene, topology=listed_from_grid(grid.topology))
    pos, vel, water = random_state(grid.topology, seed=4)
    expected = grid.forces(pos, vel, water).copy()
    assert 0.0 < grid.submerged.mean() < 1.0
    np.testing.assert_allclose(listed.forces(pos, vel, water), expected, rtol=0, atol=ROUND_OFF * np.abs(expected).max())
    for model in (grid, listed):
        model.forces_and_blocks(pos, vel, water, 1e-2)
    for name in ("force", "diagonal_blocks", "blocks"):
        a, b = getattr(grid.work, name), getattr(listed.work, name)
        np.testing.assert_allclose(b, a, rtol=0, atol=ROUND_OFF * np.abs(a).max(), err_msg=name)


def test_a_meshs_triangle_order_changes_its_forces_by_round_off_only():
    """The core takes a mesh's triangles in its own order (topology.cloth_order): the same triangles listed
    in another order give the same forces and drag blocks to round-off, and the topology (what exports
    see) keeps the order it was given."""
    scene = hanging(water_level=0.0, initial_height=0.0, air_density=1.2, wind_x=3.0)
    topo = listed_from_grid(build_topology(scene))
    shuffled = dataclasses.replace(topo, triangles=topo.triangles[np.random.default_rng(5).permutation(len(topo.triangles))])
    models = [Model(scene, topology=t) for t in (topo, shuffled)]
    assert not np.array_equal(shuffled.triangles, topo.triangles)
    np.testing.assert_array_equal(models[1].topology.triangles, shuffled.triangles)  # what exports see
    pos, vel, water = random_state(topo, seed=6)
    for model in models:
        model.forces_and_blocks(pos, vel, water, 1e-2)
    for name in ("force", "blocks"):
        a, b = getattr(models[0].work, name), getattr(models[1].work, name)
        np.testing.assert_allclose(b, a, rtol=0, atol=ROUND_OFF * np.abs(a).max(), err_msg=name)


def test_wicking_over_listed_links_moves_the_same_water():
    scene = hanging(wicking_rate=1e-4, absorption_capacity=2.0)
    grid = Model(scene)
    listed = Model(scene, topology=listed_from_grid(grid.topology))
    rng = np.random.default_rng(4)
    start = grid.capacity * rng.random(grid.topology.n)
    velocity = rng.standard_normal((3, grid.topology.n))
    results = []
    for model in (grid, listed):
        water, vel = start.copy(), velocity.copy()
        _core.wick(model.cloth, 4, 0.1, water, vel, np.zeros((6, grid.topology.n)))
        results.append((water, vel))
    np.testing.assert_allclose(results[1][0], results[0][0], rtol=0, atol=ROUND_OFF * start.max())
    np.testing.assert_allclose(results[1][1], results[0][1], rtol=0, atol=ROUND_OFF * np.abs(velocity).max())
    assert abs(results[1][0].sum() - start.sum()) <= ROUND_OFF * start.sum()


def test_an_explicit_run_on_listed_springs_follows_the_grids():
    """No solver between them: symplectic Euler's run differs only by round-off (measured 1e-14 m after 1 s)."""
    scene = hanging(integrator="symplectic_euler")
    runs = [Simulation(scene, topology=t) for t in (None, listed_from_grid(build_topology(scene)))]
    for sim in runs:
        sim.advance(1.0)
    assert np.abs(runs[1].positions - runs[0].positions).max() < 1e-11


def test_implicit_runs_on_listed_springs_converge_to_the_grids():
    """BDF2 on the mesh path (its own preconditioner, so other CG iterates and other steps) and on the grid
    solve the same equations: their difference is the controllers' error and falls with the tolerance
    (measured 5.1e-5, 3.4e-6, 5.9e-7 m at 1e-6, 1e-7, 1e-8), with the mesh path's solves converging."""
    listed = listed_from_grid(build_topology(hanging()))
    differences = []
    for tolerance in (1e-6, 1e-8):
        scene = hanging(tolerance=tolerance)
        runs = [Simulation(scene, topology=t) for t in (None, listed)]
        for sim in runs:
            sim.advance(1.0)
        differences.append(np.abs(runs[1].positions - runs[0].positions).max())
    assert differences[1] < 2e-6
    assert differences[1] < differences[0] / 20
