"""A random trial of in-range scenes: what a hostile or careless user may set, and what becomes of it.

    .venv/bin/python bench/random_trial.py [--seed 1] [--count 300] [--duration 1] [--budget 40]

Each scene is a preset (``models/*.toml``) with one to four parameters set to random values within their
allowed ranges (log-uniform, near the default, or uniform), on a grid of 5 to 21 particles a side, and in half
of them the artists' fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` 1/24, 1/30 or 1/60
s).  Each runs ``--duration`` s in a child process of its own, in 0.05 s advances, so that a crash or a hang
is an outcome, not the end of the trial:

* ``refused``: the scene was refused at load (a ConfigError naming the parameter): as it should be where the
  combination is invalid;
* ``ok``: it ran, every output finite;
* ``blow-up``: a BlowUpError, whose message names a likely cause (listed);
* ``slow``: it spent ``--budget`` s of CPU before the duration (listed: a scene's cost, not a failure);
* ``non-finite``, ``error``, ``died``, ``hung``: a non-finite output or position, another exception, a
  child killed by a signal, no answer within four budgets and 30 s of wall time (a step loop that keeps
  Python from its signals): defects (listed).

Each listed scene comes with the command that reproduces it. The trial draws the same scenes for the same
seed; what they do depends on the machine where they are chaotic.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import signal
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

from tqdm import tqdm  # noqa: E402

from wetcloth.scene import PARAMETERS, preset_dir  # noqa: E402

#: Parameters not drawn: files and free text (their own tests), and the grid's counts (drawn apart).
NOT_DRAWN = {"cloth_mesh", "pinned_vertices", "nx", "ny"}
#: Fixed frame steps, as the Blender extension's artists use them (s).
FRAMES = (1.0 / 24.0, 1.0 / 30.0, 1.0 / 60.0)
#: Outcomes that are defects, listed first.
DEFECTS = ("non-finite", "error", "died", "hung")
#: s of simulated time a child advances at once (its outputs checked after each).
ADVANCE = 0.05


def draw_value(name: str, rng: random.Random):
    """A random value within ``name``'s allowed range (None for free text)."""
    spec = PARAMETERS[name]
    meta, default = spec.metadata, spec.default
    if meta["choices"]:
        return rng.choice(meta["choices"])
    if meta["text"] or isinstance(default, (str, bool)):
        return None
    lo = -1e3 if meta["lo"] is None else meta["lo"]
    hi = 1e3 if meta["hi"] is None else meta["hi"]
    if isinstance(default, int):
        return rng.randint(int(lo), int(hi))
    way = rng.random()
    if way < 0.3 and lo >= 0.0 and hi > 0.0:  # log-uniform over six decades below the top
        return math.exp(rng.uniform(math.log(max(lo, hi * 1e-6, 1e-12)), math.log(hi)))
    if way < 0.6 and default:  # a fifth to five times the default
        return min(max(default * rng.uniform(0.2, 5.0), lo), hi)
    return rng.uniform(lo, hi)


def draw_scenes(seed: int, count: int, duration: float) -> list[dict]:
    """``count`` cases {preset, values, duration}, the same for the same seed."""
    rng = random.Random(seed)
    presets = sorted(p.stem for p in preset_dir().glob("*.toml"))
    names = sorted(n for n in PARAMETERS if n not in NOT_DRAWN)
    cases = []
    for _ in range(count):
        values = {}
        for _ in range(rng.randint(1, 4)):
            name = rng.choice(names)
            value = draw_value(name, rng)
            if value is not None:
                values[name] = value
        if rng.random() < 0.5:
            values |= dict(integrator="implicit_euler", tolerance=0.0, max_step=rng.choice(FRAMES))
        values |= dict(nx=rng.randint(5, 21), ny=rng.randint(5, 21))
        cases.append(dict(preset=rng.choice(presets), values=values, duration=duration))
    return cases


class OverBudget(Exception):
    """The child's CPU budget ran out (raised by its SIGPROF timer, within an advance too: the compiled step
    loop returns to Python often enough for signals)."""


def _over_budget(signum, frame):
    raise OverBudget


def run_case(case: dict, budget: float) -> dict:
    """Child process: load and run one case within ``budget`` s of CPU; its outcome (as ``outcome_of``)."""
    import numpy as np

    import wetcloth
    from wetcloth.errors import BlowUpError, ConfigError

    start = time.process_time()
    try:
        scene = wetcloth.load_scene(case["preset"], **case["values"])
    except ConfigError as exc:
        return dict(outcome="refused", message=str(exc))
    signal.signal(signal.SIGPROF, _over_budget)
    signal.setitimer(signal.ITIMER_PROF, budget)
    sim = None
    try:
        sim = wetcloth.Simulation(scene)
        while sim.time < case["duration"] - 1e-9:
            sim.advance(ADVANCE)
            if not (all(math.isfinite(v) for v in sim.outputs().values()) and np.isfinite(sim.state.pos).all()):
                return dict(outcome="non-finite", message=f"at t = {sim.time:g} s")
    except OverBudget:
        reached = f"{sim.time:g} s of {case['duration']:g}" if sim is not None else "not started"
        counts = f" ({sim.steps} steps, {sim.rejected_steps} taken again)" if sim is not None else ""
        return dict(outcome="slow", message=f"{reached} in {budget:g} s of CPU{counts}")
    except BlowUpError as exc:
        return dict(outcome="blow-up", message=str(exc))
    except Exception as exc:  # noqa: BLE001 (what the trial looks for)
        return dict(outcome="error", message=f"{type(exc).__name__}: {exc}")
    return dict(outcome="ok", message=f"{time.process_time() - start:.2f} s of CPU, {sim.steps} steps")


def outcome_of(case: dict, budget: float) -> dict:
    """Run ``case`` in a child process: its outcome, or 'died' / 'hung'."""
    command = [sys.executable, __file__, "--one", json.dumps(case), "--budget", str(budget)]
    try:
        child = subprocess.run(command, capture_output=True, text=True, timeout=4 * budget + 30)
    except subprocess.TimeoutExpired:
        return dict(outcome="hung", message=f"no answer in {4 * budget + 30:g} s")
    lines = child.stdout.strip().splitlines()
    if child.returncode != 0 or not lines:
        return dict(outcome="died", message=f"exit status {child.returncode}: {child.stderr[-500:]}")
    return json.loads(lines[-1])


def command_of(case: dict) -> str:
    """The ``wetcloth run`` command that reproduces ``case``: every value in full (a chaotic run differs with the
    last digit), in frames of the trial's advances."""
    sets = " ".join(f"--set {k}={v}" if isinstance(v, str) else f"--set {k}={v!r}" for k, v in case["values"].items())
    return f"wetcloth run {case['preset']} --duration {case['duration']:g} --fps {1.0 / ADVANCE:g} {sets}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--count", type=int, default=300, help="scenes (default 300)")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated s a scene (default 1)")
    parser.add_argument("--budget", type=float, default=40.0, help="s of CPU a scene (default 40)")
    parser.add_argument("--workers", type=int, default=2, help="child processes at once (default 2)")
    parser.add_argument("--one", help=argparse.SUPPRESS)  # a child's case (JSON)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(run_case(json.loads(args.one), args.budget)))
        return
    cases = draw_scenes(args.seed, args.count, args.duration)
    started = time.perf_counter()
    with ThreadPoolExecutor(args.workers) as pool:
        outcomes = list(tqdm(pool.map(lambda case: outcome_of(case, args.budget), cases), total=len(cases),
                             desc="scenes", unit="scene"))
    counts = Counter(o["outcome"] for o in outcomes)
    print(f"\nrandom trial, seed {args.seed}: {len(cases)} scenes of {args.duration:g} s in "
          f"{time.perf_counter() - started:.0f} s: " + ", ".join(f"{counts[k]} {k}" for k in sorted(counts)))
    for kind in (*DEFECTS, "blow-up", "slow"):
        for case, outcome in zip(cases, outcomes):
            if outcome["outcome"] == kind:
                print(f"\n{kind}: {outcome['message'][:400]}\n  {command_of(case)}")


if __name__ == "__main__":
    main()
