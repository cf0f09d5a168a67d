"""What keeping frames.json true after every frame costs the exporter.

    .venv/bin/python bench/manifest_cost.py [--grid 64] [--frames 60] [--repeats 9]

Writes the same PLY frames (trimesh writer, the default) of a grid x grid towel into a fresh
directory twice per repeat, interleaved: as ``wetcloth run --export`` does (``frames.json``
rewritten, whole, after each frame file) and with the manifest written only when the sequence
closes (the exporter before).  Prints ms per frame of each, best of --repeats, and their ratio.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

import wetcloth
from wetcloth.exporter import open_sequence
from wetcloth.exporter.sequence import FrameSequence


def write(directory: Path, scene, frames, per_frame_manifest: bool) -> float:
    """Seconds per frame to write ``frames`` (positions, wetness) into ``directory``."""
    sequence = open_sequence(directory, scene=scene)
    if not per_frame_manifest:
        sequence.write_manifest = lambda complete, _write=sequence.write_manifest: (
            _write(complete) if sequence.closed else None)
    start = time.perf_counter()
    for positions, wetness in frames:
        sequence.write_frame(positions, wetness)
    elapsed = time.perf_counter() - start
    sequence.close()
    return elapsed / len(frames)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=64, help="particles along each side (default 64)")
    parser.add_argument("--frames", type=int, default=60, help="frames written per measurement (default 60)")
    parser.add_argument("--repeats", type=int, default=9, help="best of this many measurements (default 9)")
    args = parser.parse_args()
    scene = wetcloth.load_scene(nx=args.grid, ny=args.grid)
    sim = wetcloth.Simulation(scene)
    frames = []
    for _ in range(args.frames):
        sim.advance(1 / 30)
        frames.append((sim.positions, sim.wetness))
    best = {True: float("inf"), False: float("inf")}
    root = Path(tempfile.mkdtemp(prefix="wetcloth_manifest_"))
    try:
        for k in range(args.repeats):
            for per_frame in (True, False):
                best[per_frame] = min(best[per_frame], write(root / f"{k}_{per_frame}", scene, frames, per_frame))
    finally:
        shutil.rmtree(root)
    print(f"# {args.grid} x {args.grid} towel, {args.frames} PLY frames (trimesh), best of {args.repeats}; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"frames.json after every frame: {best[True] * 1e3:.2f} ms/frame")
    print(f"frames.json only at close:     {best[False] * 1e3:.2f} ms/frame")
    print(f"ratio: {best[True] / best[False]:.2f}x (+{(best[True] - best[False]) * 1e3:.2f} ms/frame)")


if __name__ == "__main__":
    main()
