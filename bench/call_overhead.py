"""What one ``Simulation.advance`` call, and one sampled output, cost in Python, apart from the steps.

    .venv/bin/python bench/call_overhead.py [--calls 3000] [--repeat 3]

Every front end calls ``advance`` once per output: 2700 times for the default towel at 30 Hz, once
per FMU communication step.  Timed here on the default towel with calls that take no step
(``advance(0.0)``), so only the Python side is measured: numba's dispatcher (which types every
argument, some sixty arrays in nested tuples, at each call) against the compiled code looked up
once for those objects (``wetcloth.kernels.compilation.TypedCall``, what ``Simulation`` uses), in
the same process, alternately; best of ``--repeat``.  Then what reading the outputs costs per
sample: ``advance(0.0)`` and ``outputs()`` per sample, as a Python loop over output times does,
against ``Simulation.sample`` over as many times in one call (what ``runner.run`` does between
frames at which Python has work).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import wetcloth
from wetcloth.kernels.stepping import advance


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
    m = sim.model
    loop_args = (m.cloth, m.physics, sim._control, m.work, sim._solver, sim._plane, sim._contact, sim._buffers,
                 sim._clock, sim.time, 1)
    best = {"numba dispatcher": float("inf"), "Simulation.advance(0.0)": float("inf")}
    for _ in range(args.repeat):
        best["numba dispatcher"] = min(best["numba dispatcher"], per_call(advance, loop_args, args.calls))
        best["Simulation.advance(0.0)"] = min(best["Simulation.advance(0.0)"], per_call(sim.advance, (0.0,), args.calls))
    for name, micro in best.items():
        print(f"{name:26s} {micro:8.1f} us per call")
    ratio = best["numba dispatcher"] / best["Simulation.advance(0.0)"]
    print(f"Simulation.advance's call costs {ratio:.1f}x less than the dispatcher's typing alone "
          f"(best of {args.repeat} x {args.calls} calls)")

    def advance_and_read() -> None:
        sim.advance(0.0)
        sim.outputs()

    times = np.full(args.calls, sim.time)  # no step to take: only the sampling is timed
    loop, compiled = float("inf"), float("inf")
    for _ in range(args.repeat):
        loop = min(loop, per_call(advance_and_read, (), args.calls))
        compiled = min(compiled, per_call(sim.sample, (times,), 1) / args.calls)
    print(f"per sample: advance(0.0) + outputs() {loop:.1f} us, sample() of {args.calls} times {compiled:.2f} us "
          f"({loop / compiled:.0f}x less)")


if __name__ == "__main__":
    main()
