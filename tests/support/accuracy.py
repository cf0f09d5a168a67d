"""Reference scenes for accuracy: run a case at 30 Hz and measure its error against a reference.

Shared by ``bench/work_precision.py`` and the accuracy tests, which both compute the references in
their own process (``reference``): BDF2 with fixed steps of REFERENCE_STEP.  Halving that step
moves the centroids by 6-27 um and the wet mass by up to 1.8e-4 (docs/benchmarks.md), well below
the 1 mm and 1e-3 asked of the defaults (``tests/test_accuracy.py`` checks the sinking scene's).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from wetcloth.scene import Scene, load_scene
from wetcloth.simulation import Simulation

SAMPLE_RATE = 30.0  # Hz: how often outputs and inputs are exchanged, as an FMU master would
GRID = dict(nx=15, ny=21)
REFERENCE_STEP = 2.5e-4  # s, BDF2 with fixed steps


@dataclass
class Case:
    name: str
    scene: Scene
    duration: float  # s
    water_level: Callable[[float], float] | None = None  # t (s) -> m, or None for a constant level


def hanging_sheet() -> Scene:
    """A 41 x 41 sheet, 1 m square, pinned along its y_max edge and released horizontal in air (water
    and floor far below): it falls, swings and hangs, most of its springs slack as it swings."""
    return load_scene(nx=41, ny=41, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0,
                      initial_height=2.0, water_level=-10.0, floor_level=-20.0)


def cases() -> list[Case]:
    """A tilted towel landing; a towel soaking up water almost at once and sinking; a floating towel
    carried up by water rising 3 cm in 1 s; a sheet swinging down from one edge (1 s)."""
    towel = load_scene(**GRID)
    return [
        Case("landing", towel, 3.0),
        Case("sinking", towel.replace(absorption_rate=20.0, initial_height=0.05), 4.0),
        Case("rising_water", towel.replace(absorption_capacity=0.0, absorption_rate=0.0, initial_height=0.02,
                                           initial_tilt=0.0), 3.0,
             water_level=lambda t: 0.03 * min(max(t - 1.0, 0.0), 1.0)),
        Case("hanging_sheet", hanging_sheet(), 1.0),
    ]


@dataclass
class Trajectory:
    centroid: np.ndarray  # (T, 3) m
    positions: np.ndarray  # (T, n, 3) m
    wet_mass: np.ndarray  # (T,) kg
    seconds: float  # wall time
    steps: int


def simulate(case: Case, skip_idle_work: bool = True, **settings) -> Trajectory:
    """Run a case with integrator settings, exchanging inputs and outputs at SAMPLE_RATE.
    References pass ``skip_idle_work=False``: they compute every step, asleep or not."""
    sim = Simulation(case.scene.replace(**settings), skip_idle_work=skip_idle_work)
    frames = int(round(case.duration * SAMPLE_RATE))
    centroid, positions, wet_mass = [], [], []
    start = time.perf_counter()
    for _ in range(frames):
        if case.water_level is not None:
            sim.set_inputs(water_level=case.water_level(sim.time))
        sim.advance(1.0 / SAMPLE_RATE)
        out = sim.outputs()
        centroid.append([out["centroid_x"], out["centroid_y"], out["centroid_z"]])
        positions.append(sim.positions)
        wet_mass.append(out["wet_mass"])
    seconds = time.perf_counter() - start
    return Trajectory(np.array(centroid), np.array(positions), np.array(wet_mass), seconds, sim.steps)


def errors(run: Trajectory, ref: Trajectory) -> dict[str, float]:
    """Centroid error (max over samples, m), vertex RMS error (m), wet-mass error (max relative)."""
    return {
        "centroid_error": float(np.abs(run.centroid - ref.centroid).max()),
        "vertex_rms_error": float(np.sqrt(((run.positions - ref.positions) ** 2).sum(axis=2).mean())),
        "wet_mass_error": float(np.abs(run.wet_mass / ref.wet_mass - 1).max()),
    }


def reference(case: Case, step: float = REFERENCE_STEP) -> Trajectory:
    """The converged reference of a case: BDF2 with fixed steps, every step computed (no sleep)."""
    return simulate(case, skip_idle_work=False, integrator="bdf2", tolerance=0.0, max_step=step)
