"""CPU time of the self-collision stage's per-step check that its candidate list still holds
(broad_phase.cpp's covers: the tiers' windows against rigid motions), on the hanging sheet of
bench/hanging_sheet.py (81 x 81, released horizontal: its list stays empty), replayed from its recorded
motion: per step, best of --repeat, and the steps whose list held (an exact count, to compare trees).

    .venv/bin/python bench/list_check.py [--repeat 5] [--duration 3] [--substeps 12]

The sheet is run once, its positions recorded every 1/(30 substeps) s (its steps are at most that long);
then each replay checks the motions from one recorded state to the next in order, with a list built as
bench/mesh_lists.py builds it (the widest margin whose list is empty, from the midpoint of the first motion
it does not hold for), so that the check sees the same sequence of motions as in the run.  Only the checks
are timed.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import wetcloth  # noqa: E402
from wetcloth import _core  # noqa: E402
from hanging_sheet import FRAME, sheet  # noqa: E402


def record(duration: float, substeps: int) -> tuple[wetcloth.Simulation, list[np.ndarray]]:
    """The hanging sheet's positions (3, n) m every FRAME / substeps s, from the start."""
    sim = wetcloth.Simulation(sheet(81, "on", max_step=FRAME / substeps))
    states = [sim._buffers.pos.copy()]
    for _ in range(round(duration / FRAME) * substeps):
        sim.advance(FRAME / substeps)
        states.append(sim._buffers.pos.copy())
    return sim, states


def replay(sim: wetcloth.Simulation, states: list[np.ndarray]) -> tuple[float, int, int]:
    """CPU seconds of the checks over the recorded motions, how many held, and how many lists were built."""
    contact, thickness = sim._contact, sim.model.scene.thickness
    widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
    copy = contact._replace(reference=states[0].copy(), margin=np.zeros(1), counters=contact.counters.copy())
    lists = _core.ContactState()
    spent, held, built = 0.0, 0, 0
    for x0, x1 in zip(states, states[1:]):
        start = time.process_time()
        holds = built > 0 and _core.covers(copy, x0, x1, lists=lists)
        spent += time.process_time() - start
        if holds:
            held += 1
        else:
            copy.reference[...] = 0.5 * (x0 + x1)
            _core.build_widest(copy, thickness, contact.least_margin, widest, lists)
            built += 1
    return spent, held, built


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds (default 3)")
    parser.add_argument("--substeps", type=int, default=12, help="recorded states per frame (default 12)")
    args = parser.parse_args()
    sim, states = record(args.duration, args.substeps)
    steps = len(states) - 1
    times = []
    for _ in range(args.repeat):
        spent, held, built = replay(sim, states)
        times.append(spent)
    print(f"hanging sheet, {args.duration:g} s, {steps} motions of {1e3 * FRAME / args.substeps:.2f} ms: check "
          f"{1e3 * min(times) / steps:.3f} ms per step (best of {args.repeat}; median "
          f"{1e3 * float(np.median(times)) / steps:.3f}); held {held}, lists built {built}", flush=True)


if __name__ == "__main__":
    main()
