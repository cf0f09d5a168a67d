"""Run a scene for a duration, sampling outputs at a frame rate: the loop every front end shares."""

from __future__ import annotations

import contextlib
import csv
import math
import signal
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from wetcloth.files import whole_file
from wetcloth.progress import Watcher, time_bar
from wetcloth.run_settings import MAX_FRAMES, whole_frames
from wetcloth.scene import Scene
from wetcloth.simulation import OUTPUT_NAMES, Simulation


@dataclass
class ClothShape:
    """The cloth at one time, as plotted: positions (n, 3) m and wetness (n,) 0..1.  (Not a
    ``Simulation.snapshot``, which holds everything needed to resume a run.)"""

    time: float
    positions: np.ndarray
    wetness: np.ndarray


@dataclass
class RunResult:
    """Outputs at every frame (``rows``: time, ``OUTPUT_NAMES``, then ``step_error``: the largest local
    position error, m, any step since the frame before estimated for itself) and a few cloth shapes."""

    scene: Scene
    fps: float
    rows: list[dict[str, float]] = field(default_factory=list)
    shapes: list[ClothShape] = field(default_factory=list)
    triangles: np.ndarray | None = None

    def column(self, name: str) -> np.ndarray:
        return np.array([row[name] for row in self.rows])

    def write_csv(self, path: str | Path) -> Path:
        """Write the outputs as CSV (header: the rows' keys, SI units), whole or not at all."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with whole_file(path) as tmp, open(tmp, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(self.rows[0]) if self.rows else ["time", *OUTPUT_NAMES])
            writer.writeheader()
            writer.writerows(self.rows)
        return path


FrameCallback = Callable[[int, Simulation], None]


class CostWarning(UserWarning):
    """A run is estimated to take long; the message names cheaper settings."""


def warn_cost(message: str) -> None:
    """The default ``warn`` of :func:`run`: a :class:`CostWarning`."""
    warnings.warn(message, CostWarning, stacklevel=2)


def frame_times(duration: float, fps: float) -> np.ndarray:
    """Frame times 0, 1/fps, ... up to ``duration`` (s); the last sample lands on ``duration`` (a sample
    short of a whole frame after the last whole frame when ``duration`` is not a whole number of frames)."""
    if not (fps > 0 and math.isfinite(fps)):
        raise ValueError(f"fps must be a finite number > 0, got {fps!r}")
    if not (duration >= 0 and math.isfinite(duration)):
        raise ValueError(f"duration must be a finite number >= 0 s, got {duration!r}")
    frames = whole_frames(duration, fps)
    if frames > MAX_FRAMES:  # named as run()'s arguments, not a scene file's [run]
        raise ValueError(f"duration {duration:g} s at fps {fps:g} is {frames:.3g} frames; at "
                         f"most {MAX_FRAMES} per run: a duration up to {(MAX_FRAMES - 1) / fps:g} s at this fps")
    times = np.arange(frames) / fps
    if duration - times[-1] > 1e-9:
        times = np.append(times, duration)
    return times


def shape_frames(frames: int, shapes: int) -> list[int]:
    """Indices of ``shapes`` frames evenly spread over ``frames`` (first and last included), ascending."""
    if frames <= 0 or shapes <= 0:
        return []
    return sorted(set(np.linspace(0, frames - 1, shapes).round().astype(int).tolist()))


def run(
    scene: Scene,
    duration: float,
    fps: float = 30.0,
    on_frame: FrameCallback | None = None,
    shapes: int = 4,
    progress: bool = True,
    warn: Callable[[str], None] | None = warn_cost,
) -> RunResult:
    """Simulate ``scene`` for ``duration`` s; record outputs at ``fps`` and ``shapes`` cloth shapes
    (evenly spread frames, ``shape_frames``).

    ``on_frame(index, sim)`` is called at every whole frame (index 0 at t = 0), for exporters; a frame's
    row of outputs is recorded once ``on_frame`` has returned, so the rows are the frames written.  A last
    sample short of a whole frame (``duration`` not a whole number of frames) gets its row but no frame: a
    frame sequence plays frame k at k / fps.
    Whatever stops the run early (a ``BlowUpError``, Ctrl-C's ``KeyboardInterrupt``, a failed
    ``on_frame``) is raised with the frames recorded so far as its ``partial_result``.
    ``progress``: a bar of simulated seconds, moving by wall-clock time, once the run has taken
    a second.  ``warn(message)`` is called once, a few seconds in, if the run is estimated to take
    more than ``wetcloth.advice.WARN_AFTER`` (None: no estimate).
    """
    times = frame_times(duration, fps)
    frames = whole_frames(duration, fps)
    sim = Simulation(scene)
    plotted = shape_frames(len(times), shapes)
    result = RunResult(scene=scene, fps=fps, triangles=sim.triangles)
    with time_bar(duration, enabled=progress) as bar, _deferrable_interrupts() as deferred:
        watching = progress or warn is not None
        with Watcher(sim, bar, _cost_check(sim, duration, warn)) if watching else contextlib.nullcontext():
            # Python steps in only at the frames it has work at; the frames between are sampled in
            # compiled code (``Simulation.sample``).
            stops = range(len(times)) if on_frame is not None else sorted({*plotted, len(times) - 1})
            start = 0
            try:
                for index in stops:
                    try:
                        outputs = sim.sample(times[start:index + 1])
                    except BaseException as exc:
                        if on_frame is None:  # with frames, a row counts once its frame is written
                            _add_rows(result, times[start:], getattr(exc, "partial_outputs", ()), sim.sample_errors)
                        raise
                    if on_frame is None:
                        _add_rows(result, times[start:index + 1], outputs, sim.sample_errors)
                    if index in plotted:
                        result.shapes.append(ClothShape(float(times[index]), sim.positions, sim.wetness))
                    if on_frame is not None:
                        with deferred():  # the frame, then its row: the outputs never count a frame not on disk
                            if index < frames:
                                on_frame(index, sim)
                            _add_rows(result, times[start:index + 1], outputs, sim.sample_errors)
                    start = index + 1
            except BaseException as exc:
                exc.partial_result = result  # every frame up to the last good one
                raise
        bar.update(float(duration) - bar.n)
    return result


def _add_rows(result: RunResult, times: np.ndarray, outputs, errors: np.ndarray) -> None:
    """Append a row (time, OUTPUT_NAMES, step_error) for each row of ``outputs`` (its times the first of
    ``times``, its steps' largest errors the first of ``errors``)."""
    for t, values, error in zip(times.tolist(), np.asarray(outputs).tolist(), errors.tolist()):
        result.rows.append({"time": t, **dict(zip(OUTPUT_NAMES, values)), "step_error": error})


@contextlib.contextmanager
def interrupts_held():
    """A block inside which Ctrl-C is held back and raised as KeyboardInterrupt when it ends (in the main
    thread, under Python's own handler; elsewhere it changes nothing): for writing outputs whole."""
    with _deferrable_interrupts() as deferred, deferred():
        yield


@contextlib.contextmanager
def _deferrable_interrupts():
    """Yields ``deferred``: a context manager inside which Ctrl-C is held back, and raised as
    KeyboardInterrupt when the block ends; elsewhere it is raised at once, as usual.  The frame
    callback runs deferred: the exporter's libraries catch BaseException in places (trimesh's
    vertex normals do, and log a traceback), which swallowed the interrupt, and a frame's files are
    written whole either way.  Only where Python's own handler is in place, in the main thread
    (elsewhere ``deferred`` changes nothing)."""
    if threading.current_thread() is not threading.main_thread() or (
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield contextlib.nullcontext
        return
    deferring, held_back = False, False

    def handler(signum, frame):
        nonlocal held_back
        if not deferring:
            raise KeyboardInterrupt
        held_back = True

    @contextlib.contextmanager
    def deferred():
        nonlocal deferring, held_back
        deferring, held_back = True, False
        try:
            yield
        finally:
            deferring = False
        if held_back:
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield deferred
    finally:
        signal.signal(signal.SIGINT, previous)


def _cost_check(sim: Simulation, duration: float, warn: Callable[[str], None] | None):
    """The Watcher callback that warns when the rest of the run is estimated to take long (None: none)."""
    if warn is None:
        return None
    from wetcloth.advice import cost_warning

    def check(sample) -> None:
        message = cost_warning(sim.scene, duration, sample, sim.integrator.stable_step(0.0))
        if message is not None:
            warn(message)

    return check
