"""Run a scene for a duration, sampling outputs at a frame rate: the loop every front end shares."""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from tqdm.auto import tqdm

from wetcloth.errors import BlowUpError
from wetcloth.scene import Scene
from wetcloth.simulation import OUTPUT_NAMES, Simulation

#: Runs whose simulated duration exceeds this many seconds get a progress bar by default.
PROGRESS_AFTER = 2.0


@dataclass
class Snapshot:
    """The cloth at one time: positions (n, 3) m and wetness (n,) 0..1."""

    time: float
    positions: np.ndarray
    wetness: np.ndarray


@dataclass
class RunResult:
    """Outputs at every frame (``rows``: time then ``OUTPUT_NAMES``) and a few snapshots."""

    scene: Scene
    fps: float
    rows: list[dict[str, float]] = field(default_factory=list)
    snapshots: list[Snapshot] = field(default_factory=list)
    triangles: np.ndarray | None = None

    def column(self, name: str) -> np.ndarray:
        return np.array([row[name] for row in self.rows])

    def write_csv(self, path: str | Path) -> Path:
        """Write the outputs as CSV (header: time and the output names, SI units)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=["time", *OUTPUT_NAMES])
            writer.writeheader()
            writer.writerows(self.rows)
        return path


FrameCallback = Callable[[int, Simulation], None]


def frame_times(duration: float, fps: float) -> np.ndarray:
    """Frame times 0, 1/fps, ... up to ``duration`` (s); the last frame lands on ``duration``."""
    if not (fps > 0 and math.isfinite(fps)):
        raise ValueError(f"fps must be a finite number > 0, got {fps!r}")
    if not (duration >= 0 and math.isfinite(duration)):
        raise ValueError(f"duration must be a finite number >= 0 s, got {duration!r}")
    count = int(math.floor(duration * fps + 1e-9))
    times = np.arange(count + 1) / fps
    if duration - times[-1] > 1e-9:
        times = np.append(times, duration)
    return times


def run(
    scene: Scene,
    duration: float,
    fps: float = 30.0,
    on_frame: FrameCallback | None = None,
    snapshots: int = 4,
    progress: bool | None = None,
) -> RunResult:
    """Simulate ``scene`` for ``duration`` s; record outputs at ``fps`` and ``snapshots`` cloth shapes.

    ``on_frame(index, sim)`` is called at every frame (index 0 at t = 0), for exporters.
    A blow-up raises ``BlowUpError`` with the frames recorded so far as its ``partial_result``.
    A progress bar (tqdm, simulated seconds) shows when ``progress`` is True, or by default for
    runs longer than ``PROGRESS_AFTER`` seconds.
    """
    sim = Simulation(scene)
    times = frame_times(duration, fps)
    snapshot_frames = set(np.linspace(0, len(times) - 1, snapshots).round().astype(int).tolist()) if snapshots else set()
    result = RunResult(scene=scene, fps=fps, triangles=sim.triangles)
    show = duration > PROGRESS_AFTER if progress is None else progress
    with tqdm(total=float(duration), unit="sim s", disable=not show, desc="simulating",
              bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]") as bar:
        for index, t in enumerate(times):
            try:
                sim.advance(t - sim.time)
            except BlowUpError as exc:
                exc.partial_result = result  # every frame up to the last good one
                raise
            result.rows.append({"time": float(t), **sim.outputs()})
            if index in snapshot_frames:
                result.snapshots.append(Snapshot(float(t), sim.positions, sim.wetness))
            if on_frame is not None:
                on_frame(index, sim)
            bar.update(float(t) - bar.n)
    return result
