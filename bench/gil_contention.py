"""What another Python thread costs a run: the same run alone, and beside an asyncio loop that wakes
every millisecond (as a Dask worker's event loop sits beside its task).

    .venv/bin/python bench/gil_contention.py [--repeat 3]

The compiled core steps with the GIL released (``_core.Stepper.advance``, docs/core.md), so the loop
thread runs while it computes; code that held the GIL while stepping would lose it to the loop each
time the loop wakes (20 % of a run, measured when the numba kernels still held it).
"""

from __future__ import annotations

import argparse
import asyncio
import threading
import time

import wetcloth
from wetcloth.runner import run

SCENE = dict(nx=17, ny=17, absorption_rate=1.0)  # a batch-study run: thesis_fast, 30 s simulated
DURATION = 30.0


def one_run(scene) -> float:
    """Wall-clock seconds of one 30 s run sampled at 10 Hz."""
    start = time.perf_counter()
    run(scene, DURATION, 10.0, shapes=0, progress=False)
    return time.perf_counter() - start


def beside_a_loop(scene) -> float:
    """One run in a thread while an asyncio loop in another thread wakes every millisecond."""
    stop = threading.Event()

    async def tick():
        while not stop.is_set():
            await asyncio.sleep(0.001)

    loop_thread = threading.Thread(target=lambda: asyncio.run(tick()))
    loop_thread.start()
    try:
        seconds = []
        worker = threading.Thread(target=lambda: seconds.append(one_run(scene)))
        worker.start()
        worker.join()
    finally:
        stop.set()
        loop_thread.join()
    return seconds[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scene = wetcloth.load_scene("thesis_fast", **SCENE)
    run(scene, 1.0, 10.0, shapes=0, progress=False)  # one untimed run first
    alone, beside = [], []
    for _ in range(args.repeat):  # interleaved, so that drifts in the machine's speed hit both
        alone.append(one_run(scene))
        beside.append(beside_a_loop(scene))
    print(f"run alone: best {min(alone):.2f} s; beside a 1 ms asyncio loop: best {min(beside):.2f} s "
          f"({min(beside) / min(alone):.2f}x)")


if __name__ == "__main__":
    main()
