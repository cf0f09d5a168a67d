"""What a study would do, without doing it (``wetcloth batch --dry-run``): its runs, each marked done,
failed or to run by the results table, and an estimate of their time.

The estimate times some of the runs still to do in this process, each for up to ``PROBE_BUDGET`` s
of wall-clock time from its start (after one untimed frame that loads the kernels), and extrapolates
each to its duration at the pace it had (``wetcloth.advice.estimate_cost``).  It starts no cluster.
``PROBES`` runs spread over the study are timed, then more, in a fixed shuffled order, until
``TOTAL_PROBE_BUDGET`` s are spent: the runs of a study can differ in cost by 50x (the sensitivity
example's: 0.08 to 4 s), and three of them put its 512 runs at 20 s on 2 workers where they took 74 s.
The pace of a run's first seconds is not always that of the rest (a towel that sinks moves more),
so it is an estimate, not a promise.

A local cluster adds its own time: starting its worker processes, their first imports, and stopping
it.  That is estimated from the time a fresh Python process takes to import what a worker runs
(``startup_time``, timed in a child process): left out, the sink_map example was estimated at 0.6 s
where it took 3.4 s.
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from wetcloth.batch.engines import OK
from wetcloth.batch.execution import runs_to_do
from wetcloth.batch.results import KEY
from wetcloth.batch.spec import Run, Study

#: s of wall-clock time each probe run is timed for, at most.
PROBE_BUDGET = 1.0
#: Runs timed for the estimate at least (spread over the runs to do), if there are as many.
PROBES = 3
#: s of wall-clock time after which no further run is timed (the first ``PROBES`` always are).
TOTAL_PROBE_BUDGET = 5.0
#: A local cluster's start, its workers' first imports and its stop take about STARTUP_BASE times a
#: fresh process's imports, plus STARTUP_PER_ROUND times for each round of workers started (one per
#: core at a time).  Measured (2-core AMD EPYC, 2 workers, sink_map): imports 0.7 s; the study took
#: 3.4 s for 1.2 s of computing, the cluster's start 1.9 s and its stop 0.3 s of it.
STARTUP_BASE, STARTUP_PER_ROUND = 1.5, 2.5
#: What a worker imports before its first run.
WORKER_IMPORTS = "import distributed, wetcloth.batch.engines, wetcloth.simulation"
#: Rows of the run listing shown whole; a longer listing shows its head and tail.
SHOWN_ROWS = 30


def run_listing(study: Study, existing: pd.DataFrame, retry_errors: bool = False,
                curves: set[str] | None = None) -> pd.DataFrame:
    """One row per run of ``study``, in run order: ``run`` (1, 2, ...), the axis values, and ``state``:
    'done' (in ``existing`` and ok, with its curves among ``curves`` if the study keeps them: the
    run keys its series store holds), 'failed' (recorded as an error: kept, unless ``retry_errors``)
    or 'to run'."""
    runs = study.runs()
    status = dict(zip(existing[KEY], existing["status"])) if len(existing) else {}
    todo = {r.key for r in runs_to_do(runs, existing, retry_errors, curves)}
    rows = []
    for i, r in enumerate(runs, 1):
        state = "to run" if r.key in todo else "done" if status[r.key] == OK else "failed"
        rows.append({"run": i, **r.point, "state": state})
    return pd.DataFrame(rows, columns=["run", *study.axis_names, "state"])


@dataclass(frozen=True)
class Probe:
    """One timed run: ``seconds`` of wall-clock time estimated for the whole run, from ``simulated``
    s of it timed over ``elapsed`` s (``error``: why it could not be timed)."""

    run: Run
    seconds: float = float("nan")
    simulated: float = 0.0
    elapsed: float = 0.0
    error: str | None = None


def probe(run: Run, study: Study, budget: float = PROBE_BUDGET) -> Probe:
    """Time ``run`` in this process for up to ``budget`` s from its start, and extrapolate to its duration."""
    from wetcloth.advice import estimate_cost
    from wetcloth.progress import Sample
    from wetcloth.scene import from_dict
    from wetcloth.simulation import Simulation

    chunk = min(1.0 / study.sample_rate, 0.05, study.duration)  # s simulated between two looks at the clock
    try:
        scene = from_dict(run.params)
        Simulation(scene).advance(chunk)  # loads (or compiles) the kernels this scene needs: not timed
        sim = Simulation(scene)
        start = time.perf_counter()
        while True:  # at least one chunk, then until the run ends or the budget is spent
            sim.advance(min(chunk, study.duration - sim.time))
            if sim.time >= study.duration * (1 - 1e-12) or time.perf_counter() - start >= budget:
                break
        elapsed = time.perf_counter() - start
    except Exception as exc:  # a run that cannot be timed is left out of the estimate, and said so
        return Probe(run, error=f"{type(exc).__name__}: {exc}")
    # time = 0: the cost of the whole run at the pace of the timed part
    cost = estimate_cost(scene, study.duration, Sample(elapsed, sim.steps, sim.time, 0.0), sim.integrator.stable_step(0.0))
    return Probe(run, cost.seconds, sim.time, elapsed)


@dataclass(frozen=True)
class TimeEstimate:
    """The estimated time of ``runs`` runs from ``probes``: ``per_run`` s (the probes' mean; NaN if
    no probe could be timed) and ``compute`` s in all (per_run x runs).  ``refused``: runs left out,
    since a value out of range refuses them before they reach a worker (they cost nothing)."""

    runs: int
    probes: tuple[Probe, ...]
    refused: int = 0

    @property
    def timed(self) -> list[Probe]:
        return [p for p in self.probes if p.error is None]

    @property
    def per_run(self) -> float:
        return float(np.mean([p.seconds for p in self.timed])) if self.timed else float("nan")

    @property
    def compute(self) -> float:
        return self.per_run * self.runs

    def wall(self, workers: int) -> float:
        """s of wall-clock time on ``workers`` single-threaded workers (runs spread evenly)."""
        return self.per_run * int(np.ceil(self.runs / workers))


def probe_order(count: int, spread: int) -> list[int]:
    """The order in which ``count`` runs are timed: ``spread`` of them evenly spread over the list,
    then the others in a shuffled order (fixed: the same study gets the same estimate)."""
    first = sorted(set(np.linspace(0, count - 1, min(spread, count)).round().astype(int).tolist())) if count else []
    chosen = set(first)
    return first + [int(i) for i in np.random.default_rng(0).permutation(count) if i not in chosen]


def estimate_time(study: Study, runs: list[Run], probes: int = PROBES, budget: float = PROBE_BUDGET,
                  total: float = TOTAL_PROBE_BUDGET) -> TimeEstimate:
    """Time ``probes`` of ``runs`` (spread evenly over them), then more until ``total`` s are spent,
    each for ``budget`` s at most: see :class:`TimeEstimate`."""
    from wetcloth.scene import from_dict

    def valid(run: Run) -> bool:
        try:
            from_dict(run.params)
        except ValueError:
            return False
        return True

    costly = [r for r in runs if valid(r)]
    if not costly:
        return TimeEstimate(0, (), refused=len(runs))
    timed = []
    start = time.perf_counter()
    for i in probe_order(len(costly), probes):
        if len(timed) >= probes and time.perf_counter() - start >= total:
            break
        timed.append(probe(costly[i], study, budget))
    return TimeEstimate(len(costly), tuple(timed), len(runs) - len(costly))


def startup_time(workers: int, cores: int, timeout: float = 120.0) -> float:
    """s a local cluster of ``workers`` processes on ``cores`` cores adds to a study (start, first
    imports, stop), from the time a fresh Python process here takes to import what a worker runs
    (timed now, in a child process: what the disk cache and this machine make of it); NaN if the
    child process fails."""
    start = time.perf_counter()
    try:
        subprocess.run([sys.executable, "-c", WORKER_IMPORTS], check=True, capture_output=True, timeout=timeout)
    except (OSError, subprocess.SubprocessError):
        return float("nan")
    fresh = time.perf_counter() - start
    return fresh * (STARTUP_BASE + STARTUP_PER_ROUND * math.ceil(workers / max(1, cores)))


def format_listing(listing: pd.DataFrame, shown: int = SHOWN_ROWS) -> str:
    """The run listing as text: whole up to ``shown`` rows, else its head and tail."""
    if len(listing) <= shown:
        return listing.to_string(index=False)
    head, tail = shown * 2 // 3, shown // 3
    lines = listing.to_string(index=False).splitlines()
    return "\n".join([*lines[:head + 1], f"  ... {len(listing) - head - tail} more runs ...", *lines[-tail:]])


def format_estimate(estimate: TimeEstimate, workers: int | None, budget: float = PROBE_BUDGET,
                    startup: float | None = None) -> str:
    """'estimated time: about 1.4 s per run x 512 runs = 12 min of computing; about 6 min on 2 workers (...)';
    with ``startup`` (s, ``startup_time``: a local cluster) the wall time includes it and says so."""
    from wetcloth.advice import about, format_duration

    refused = (f"{estimate.refused} run{'s' if estimate.refused > 1 else ''} with a value out of range will be "
               "refused at once" if estimate.refused else "")
    if estimate.runs == 0:
        return "estimated time: nothing to run" + (f" ({refused})" if refused else "")
    failed = [p for p in estimate.probes if p.error is not None]
    notes = "; ".join([*(f"run {p.run.key} could not be timed ({p.error.splitlines()[0]})" for p in failed),
                       *([refused] if refused else [])])
    if not estimate.timed:
        return f"estimated time: none: {notes}"
    spread = [p.seconds for p in estimate.timed]
    timed = (f"{len(spread)} of the runs timed in this process for up to {budget:g} s each"
             + (f", {format_duration(min(spread))} to {format_duration(max(spread))} per run" if len(spread) > 1 else ""))
    text = (f"estimated time: {about(estimate.per_run)} per run x {estimate.runs} runs = "
            f"{format_duration(estimate.compute)} of computing")
    if workers:
        plural = "s" if workers > 1 else ""
        if startup is not None and math.isfinite(startup):
            text += (f"; {about(estimate.wall(workers) + startup)} on {workers} worker{plural} of a "
                     f"local cluster, {format_duration(startup)} of it to start the cluster, warm up its "
                     f"worker{plural} and stop it")
        else:
            text += f"; {about(estimate.wall(workers))} on {workers} worker{plural}"
    else:
        text += "; divide by the number of workers of the cluster"
    return text + f" ({timed}{'; ' + notes if notes else ''})"
