"""CPU time of one self-collision candidate-list build (broad_phase.cpp's build_lists, with the coarser tiers'
nearest far pairs) on bench/mesh_cost.py's shapes hanging in air (the irregular 10k-vertex disc, the 100 x 100
grid), after --settle s: per build, best of --repeat, and per vertex against the grid's; and a digest of the
lists, margin and allowances built, to check that a faster build builds the same lists (run builds in turn).

    .venv/bin/python bench/mesh_lists.py [--repeat 10] [--settle 0.3]

Each build starts from the cloth's positions at --settle s, as rebuild_for_step does after an empty list, at two
margins: the least (Contact.least_margin) and the widest that keeps the rest sheet's neighbours out.  The
simulation's own list is left alone (the build works on a copy of its reference, margin and counters).  The builds
at a margin share one ContactState, as a run's rebuilds do: the first cuts the rest sheet's tiers (kept for the
others; its time is printed apart, as "first").
"""

from __future__ import annotations

import argparse
import hashlib
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth import _core  # noqa: E402
from mesh_cost import CASES, PIN, shapes_of  # noqa: E402


def build_times(sim: wetcloth.Simulation, repeat: int) -> tuple[dict, str]:
    """The best CPU time (ms) of a list build from ``sim``'s positions at each margin (m), and a digest of
    what the builds made."""
    contact, thickness = sim._contact, sim.model.scene.thickness
    copy = contact._replace(reference=sim._buffers.pos.copy(), margin=np.zeros(1), counters=contact.counters.copy())
    widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
    times, digest = {}, hashlib.sha1()
    for margin in (contact.least_margin, widest):
        lists, spent = _core.ContactState(), []
        for _ in range(repeat + 1):
            start = time.process_time()
            _core.build_widest(copy, thickness, contact.least_margin, margin, lists)
            spent.append(time.process_time() - start)
        times[margin] = 1e3 * min(spent[1:]), 1e3 * spent[0], lists.point_triangle_count + lists.edge_edge_count
        for part in (lists.point_triangle, lists.edge_edge, np.asarray(lists.allowances),
                     np.asarray(lists.particle_allowances), copy.margin):
            digest.update(np.ascontiguousarray(part).tobytes())
    return times, digest.hexdigest()[:12]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=10)
    parser.add_argument("--settle", type=float, default=0.3, help="simulated seconds of hanging before (default 0.3)")
    args = parser.parse_args()
    shapes = shapes_of(10000, shuffle=False, square_meshes=False)
    per_vertex = {}
    print(f"hanging after {args.settle} s: CPU ms per list build, best of {args.repeat}")
    for kind in ("grid", "mesh"):
        sim = wetcloth.Simulation(wetcloth.load_scene(**CASES["hanging in air"], **shapes[kind], pinned_vertices=PIN))
        sim.advance(args.settle)
        times, digest = build_times(sim, args.repeat)
        n = sim.model.topology.n
        per_vertex[kind] = min(ms for ms, _, _ in times.values()) / n
        builds = "  ".join(f"margin {1e3 * m:.3f} mm: {ms:6.1f} ms, first {first:6.1f} ({pairs} pairs)"
                           for m, (ms, first, pairs) in times.items())
        print(f"  {kind}: {n} vertices  {builds}  digest {digest}", flush=True)
    print(f"  per vertex: mesh / grid {per_vertex['mesh'] / per_vertex['grid']:.2f}x")


if __name__ == "__main__":
    main()
