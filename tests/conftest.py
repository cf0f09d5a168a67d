"""Shared helpers for the tests."""

import numpy as np
import pytest
from hypothesis import settings

import wetcloth
from wetcloth.integrators import SMALLEST_STEP

# Property tests draw the same examples on every run (derived from each test's source), so that the
# suite's verdict never depends on the luck of a draw on a CI machine; to search further, draw new
# ones: `pytest --hypothesis-profile=explore` (and raise a test's max_examples).
settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("repeatable")

G = 9.81


@pytest.fixture(scope="session")
def native_objects(tmp_path_factory):
    """The folder every native build of the session compiles into (``build_native_fmu``'s ``build_dir``),
    beside pytest's temporary folders of the session and so shared by its xdist workers: objects are named
    by the digest of compiler, flags, source and headers, and locked while compiled, so the core and the
    unit's fixed sources compile once a session."""
    return tmp_path_factory.getbasetemp().parent / "wetcloth-native-objects"

INTEGRATORS = ["explicit_euler", "symplectic_euler", "implicit_euler", "bdf2"]


def mean_velocity(sim: wetcloth.Simulation) -> np.ndarray:
    """Mass-weighted mean velocity (m/s) of the cloth."""
    mass = sim.model.mass(sim.state.water)
    return sim.state.vel @ mass / mass.sum()


def totals(sim: wetcloth.Simulation):
    """(dry mass kg, envelope volume m3) of the whole cloth."""
    return float(sim.model.dry_mass.sum()), float(sim.model.volume.sum())


def heavy_submerged_scene(**overrides) -> wetcloth.Scene:
    """A flat, dense cloth (0.5 kg/m2, 0.4 mm: 1.25x the water it displaces) starting 0.5 m under
    water in a deep tank, not absorbing: it sinks broadside."""
    base = dict(
        areal_density=0.5, thickness=0.0004, initial_tilt=0.0, initial_height=-0.5, floor_level=-1000.0,
        absorption_capacity=0.0, absorption_rate=0.0,
    )
    return wetcloth.load_scene(**(base | overrides))


def explicit_near_the_smallest_step(margin: float) -> wetcloth.Scene:
    """The towel under explicit Euler with its damping set so that the scheme's stability bound at rest is
    (1 + margin) times the smallest step: the bound is 0.9 * 2 / (damping rate + drag rate) there, the damping
    rate proportional to ``damping`` (read off a run at 1e4 N s/m, bound 3.6e-9 s)."""
    scene = wetcloth.load_scene(integrator="explicit_euler", damping=1e4)
    control = wetcloth.Simulation(scene).integrator.control()
    rate = 1.8 / (SMALLEST_STEP * (1.0 + margin)) - control.drag_rate_offset
    return scene.replace(damping=1e4 * rate / control.damping_rate)
