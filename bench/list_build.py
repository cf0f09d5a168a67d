"""CPU time of one rebuild of the self-collision candidate list (broad_phase.cpp's build for the widest margin
whose list is empty), at states of a few scenes, and how many windows of the finest tier it left to the search
(flat_windows.hpp: the others are shown to hold no pair).

    .venv/bin/python bench/list_build.py [--repeat 3] [--builds 30]

Each scene runs to its state once; the list is then built --builds times in a row at those positions, best of
--repeat rounds.  To compare two trees, run this with each core in turn (the list, its margin and the run are
the same, pair for pair).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import wetcloth  # noqa: E402
from wetcloth import _core  # noqa: E402
import _paths  # noqa: E402,F401  (tests/ on sys.path)
from hanging_sheet import sheet  # noqa: E402
from test_self_collision import CURRENT_OVER_PIN  # noqa: E402

#: (label, scene, simulated seconds before the state).
CASES = [
    ("hanging sheet 81 x 81 at 1.0 s", lambda: sheet(81, "on"), 1.0),
    ("hanging sheet 81 x 81 at 1.5 s", lambda: sheet(81, "on"), 1.5),
    ("towel 41 x 57 landing, 1.0 s", lambda: wetcloth.load_scene(nx=41, ny=57, self_collision="on"), 1.0),
    ("flag preset, 1.0 s", lambda: wetcloth.load_scene("flag", self_collision="on"), 1.0),
    ("towel folded by a current, 2.0 s", lambda: wetcloth.load_scene(**CURRENT_OVER_PIN), 2.0),
    ("tablecloth preset (mesh), 1.0 s", lambda: wetcloth.load_scene("tablecloth", self_collision="on"), 1.0),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--builds", type=int, default=30)
    args = parser.parse_args()
    for label, make, duration in CASES:
        sim = wetcloth.Simulation(make())
        sim.advance(duration)
        contact, thickness = sim._contact, sim.scene.thickness
        x = sim.state.pos.copy()
        contact.reference[...] = x
        widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
        lists = _core.ContactState()
        best = float("inf")
        for _ in range(args.repeat):
            start = time.process_time()
            for _ in range(args.builds):
                _core.build_widest(contact, thickness, contact.least_margin, widest, lists=lists)
            best = min(best, (time.process_time() - start) / args.builds)
        unproven, windows, _, through = _core.unproven_windows(contact, x, thickness + 2.0 * widest, lists=lists)
        pairs = lists.point_triangle_count + lists.edge_edge_count
        print(f"{label:<34} {1e3 * best:7.3f} ms a build  pairs {pairs:5d}  margin {1e3 * float(contact.margin[0]):.2f} mm  "
              f"windows not shown {unproven}/{windows}  tiers shown through {through}", flush=True)


if __name__ == "__main__":
    main()
