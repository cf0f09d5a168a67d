"""What one ``Simulation.advance`` call, and one sampled output, cost in Python, apart from the steps.

    .venv/bin/python bench/call_overhead.py [--calls 3000] [--repeat 3]

Every front end calls ``advance`` once per output: 2700 times for the default towel at 30 Hz, once
per FMU communication step.  Timed here on the default towel with calls that take no step, so only
the calls are measured: the compiled core's own entry, ``sim._stepper.advance(t, n)`` (nanobind's
call, the GIL released and taken back), against ``Simulation.advance(0.0)`` (that call and the
Python around it: the argument's check, the loop over paused calls), alternately, best of
``--repeat``.  Then what reading the outputs costs per sample: ``advance(0.0)`` and ``outputs()``
per sample, as a Python loop over output times does, against ``Simulation.sample`` over as many
times in one call (what ``runner.run`` does between frames at which Python has work).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import wetcloth


def per_call(function, args, calls: int) -> float:
    """Mean wall time (us) of ``function(*args)``."""
    start = time.perf_counter()
    for _ in range(calls):
        function(*args)
    return (time.perf_counter() - start) / calls * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=3000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    sim = wetcloth.Simulation(wetcloth.load_scene())
    sim.advance(1.0 / 30.0)
    calls = {"_stepper.advance(t, n)": (sim._stepper.advance, (sim.time, sim._steps_per_call)),
             "Simulation.advance(0.0)": (sim.advance, (0.0,))}
    best = dict.fromkeys(calls, float("inf"))
    for _ in range(args.repeat):
        for name, (function, arguments) in calls.items():
            best[name] = min(best[name], per_call(function, arguments, args.calls))
    for name, micro in best.items():
        print(f"{name:24s} {micro:6.2f} us per call")

    def advance_and_read() -> None:
        sim.advance(0.0)
        sim.outputs()

    times = np.full(args.calls, sim.time)  # no step to take: only the sampling is timed
    loop, compiled = float("inf"), float("inf")
    for _ in range(args.repeat):
        loop = min(loop, per_call(advance_and_read, (), args.calls))
        compiled = min(compiled, per_call(sim.sample, (times,), 1) / args.calls)
    print(f"per sample: advance(0.0) + outputs() {loop:.2f} us, sample() of {args.calls} times {compiled:.3f} us "
          f"({loop / compiled:.0f}x less); best of {args.repeat} x {args.calls}")


if __name__ == "__main__":
    main()
