"""Progress of a simulation by wall-clock time, whatever its frame rate or simulated duration.

``time_bar`` is the progress bar of simulated seconds every front end shows (``wetcloth run``,
the FMU co-simulation); it appears only once the work has taken ``SHOW_AFTER`` s.  ``Watcher``
looks at a running :class:`~wetcloth.Simulation` from a thread every ``POLL`` s, so the bar moves
while a frame is being computed (a frame can take hours), and hands a timed sample of the run to
a callback once (for the cost estimate, ``wetcloth.advice.estimate_cost``).  It reads only
``sim.time`` and ``sim.steps``; the simulation runs on undisturbed in the caller's thread.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Callable

from tqdm.auto import tqdm

#: s of wall-clock time before a bar appears: quick work shows none.
SHOW_AFTER = 1.0
#: s between two looks at the running simulation.
POLL = 0.2
#: s of wall-clock time the run is timed for, from its first step, before the estimate.
SAMPLE = 1.0
#: s to wait for the first step; a run that has not taken one by then is estimated from that.
FIRST_STEP_PATIENCE = 5.0
BAR_FORMAT = "{l_bar}{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]"


def time_bar(duration: float, desc: str = "simulating", enabled: bool = True) -> tqdm:
    """A tqdm bar of ``duration`` simulated seconds; move it with ``bar.update(t - bar.n)``."""
    return tqdm(total=float(duration), unit="sim s", desc=desc, disable=not enabled, delay=SHOW_AFTER,
                bar_format=BAR_FORMAT, dynamic_ncols=True)


@dataclass(frozen=True)
class Sample:
    """A timed stretch of a run: ``elapsed`` s of wall-clock time in which it took ``steps`` internal
    steps over ``simulated`` s, ending at simulated time ``time`` (s)."""

    elapsed: float
    steps: int
    simulated: float
    time: float


class Watcher:
    """While in its ``with`` block: moves ``bar`` to ``sim.time`` every ``POLL`` s and calls
    ``on_sample(Sample)`` once, ``SAMPLE`` s after the first step (or, with ``steps = 0``,
    ``FIRST_STEP_PATIENCE`` s after the start if no step has ended by then)."""

    def __init__(self, sim, bar: tqdm | None = None, on_sample: Callable[[Sample], None] | None = None):
        self.sim = sim
        self.bar = bar
        self.on_sample = on_sample
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="wetcloth-progress", daemon=True)

    def __enter__(self) -> "Watcher":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()

    def _watch(self) -> None:
        start = time.monotonic()
        first = None  # (wall, time, steps) at the end of the first step
        pending = self.on_sample is not None
        while not self._stop.wait(POLL):
            now, t, steps = time.monotonic(), self.sim.time, self.sim.steps
            if self.bar is not None:
                self.bar.update(t - self.bar.n)
            if not pending:
                continue
            if first is None and steps > 0:
                first = (now, t, steps)
            if first is not None and now - first[0] >= SAMPLE:
                sample = Sample(now - first[0], steps - first[2], t - first[1], t)
            elif first is None and now - start >= FIRST_STEP_PATIENCE:
                sample = Sample(now - start, 0, 0.0, t)
            else:
                continue
            pending = False
            self.on_sample(sample)
