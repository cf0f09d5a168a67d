"""Exporter speed: frames written per second for a 64 x 64 cloth, each format, writer and kind of face.

    .venv/bin/python bench/export_speed.py [--grid 64] [--frames 60] [--repeats 3] [--blender]

1. Simulates the default towel on a grid x grid mesh for a short while at 30 fps and times the
   simulation per frame (the yardstick: the exporter must not dominate a ``wetcloth run``).
2. Writes those frames (positions, wetness and velocities, cycled up to --frames) through every
   format and writer: with quads and velocities (what ``wetcloth run`` writes now; only USD stores
   the velocities) and with triangles and no velocities (the exporter before both), and USD also
   with triangles and velocities; streaming into a fresh directory, best of --repeats runs, the
   cases interleaved so that a busy machine slows them alike.  Reports frames/s, ms/frame,
   MB/frame, the share of a run's time (simulation + export) that the export takes, and each
   case's time against triangles without velocities.
3. With --blender (needs .venv-blender), times ``load_in_blender.py`` (its default, render-ready
   options) on the PLY and USD sequences with quads.

Prints a Markdown table and writes bench/results/export_speed.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.exporter import open_sequence
from wetcloth.runner import run

ROOT = Path(__file__).resolve().parents[1]
#: (format, writer, faces, velocities given to write_frame, as wetcloth run gives them; only USD
#: stores them): quads with velocities is the exporter now, triangles without them the exporter
#: before quads and velocities (the baseline); for USD also triangles with velocities.
CASES = [(fmt, writer, faces, velocities)
         for fmt, writer in [("ply", "trimesh"), ("ply", "meshio"), ("obj", "trimesh"), ("obj", "meshio"),
                             ("usd", "usd-core")]
         for faces, velocities in (("quads", True), ("triangles", False))] + [("usd", "usd-core", "triangles", True)]
FPS = 30.0


def simulate(grid: int, duration: float):
    """Frames (positions, wetness, velocities) of the towel on a grid x grid mesh, and the simulation's s/frame."""
    scene = wetcloth.load_scene(nx=grid, ny=grid)
    run(scene, 1.0 / FPS, FPS, progress=False)  # one untimed run first: lazy imports, memory first touched
    frames = []
    started = time.perf_counter()
    run(scene, duration, FPS, progress=False,
        on_frame=lambda i, sim: frames.append((sim.positions, sim.wetness, sim.velocities)))
    elapsed = time.perf_counter() - started
    return scene, frames, elapsed / len(frames)


def write_frames(scene, frames, case, count, directory):
    """Seconds to write ``count`` frames (cycling ``frames``) and close; bytes written."""
    fmt, writer, faces, with_velocities = case
    shutil.rmtree(directory, ignore_errors=True)
    started = time.perf_counter()
    sequence = open_sequence(directory, fmt=fmt, writer="trimesh" if writer == "usd-core" else writer,
                             fps=FPS, scene=scene, faces=faces)
    for k in range(count):
        positions, wetness, velocities = frames[k % len(frames)]
        sequence.write_frame(positions, wetness, velocities=velocities if with_velocities else None)
    sequence.close()
    elapsed = time.perf_counter() - started
    size = sum(p.stat().st_size for p in Path(directory).iterdir() if p.suffix in (".ply", ".obj", ".usd"))
    return elapsed, size


def blender_load_seconds(directory: Path) -> float | None:
    python = ROOT / ".venv-blender" / "bin" / "python"
    if not python.exists():
        return None
    code = ("import bpy, runpy, time, sys; bpy.ops.wm.read_factory_settings(use_empty=True); t = time.time(); "
            f"runpy.run_path({str(directory / 'load_in_blender.py')!r}, run_name='__main__'); "
            "bpy.context.scene.frame_set(2); print('SECONDS', time.time() - t)")
    done = subprocess.run([str(python), "-c", code], capture_output=True, text=True, timeout=1800)
    for line in done.stdout.splitlines():
        if line.startswith("SECONDS"):
            return float(line.split()[1])
    raise RuntimeError(done.stderr[-2000:])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=64, help="particles along each side (default 64)")
    parser.add_argument("--frames", type=int, default=60, help="frames written per measurement (default 60)")
    parser.add_argument("--repeats", type=int, default=3, help="best of this many measurements (default 3)")
    parser.add_argument("--sim-duration", type=float, default=0.5, help="simulated seconds for the yardstick")
    parser.add_argument("--blender", action="store_true", help="also time load_in_blender.py (PLY, USD)")
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "export_speed.json")
    args = parser.parse_args(argv)

    scene, frames, sim_seconds = simulate(args.grid, args.sim_duration)
    n = args.grid * args.grid
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        directories = {case: Path(tmp) / "_".join(map(str, case)) for case in CASES}
        times = {case: [] for case in CASES}
        for _ in range(args.repeats):  # interleaved: a busy machine slows every case alike
            for case in CASES:
                times[case].append(write_frames(scene, frames, case, args.frames, directories[case]))
        for case in CASES:
            fmt, writer, faces, with_velocities = case
            best, size = min(times[case])
            baseline = min(times[(fmt, writer, "triangles", False)])[0]
            per_frame = best / args.frames
            row = {"format": fmt, "writer": writer, "faces": faces, "velocities": with_velocities,
                   "frames_per_s": 1.0 / per_frame, "ms_per_frame": 1e3 * per_frame,
                   "mb_per_frame": size / args.frames / 1e6, "share_of_run": per_frame / (per_frame + sim_seconds),
                   "against_triangles": best / baseline}
            if args.blender and faces == "quads" and (fmt, writer) in (("ply", "trimesh"), ("usd", "usd-core")):
                row["blender_load_s"] = blender_load_seconds(directories[case])
            rows.append(row)

    result = {
        "grid": f"{args.grid}x{args.grid}", "vertices": n, "frames": args.frames, "repeats": args.repeats,
        "simulation_ms_per_frame": 1e3 * sim_seconds, "fps": FPS, "rows": rows,
        "machine": {"python": platform.python_version(), "cpu_count": os.cpu_count(), "platform": platform.platform()},
        "command": "python bench/export_speed.py " + " ".join(sys.argv[1:] if argv is None else argv),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")

    print(f"{args.grid}x{args.grid} cloth ({n} vertices), {args.frames} frames, best of {args.repeats}; "
          f"simulation {1e3 * sim_seconds:.1f} ms per frame at {FPS:g} fps")
    print("| format | writer | faces | velocities | frames/s | ms/frame | MB/frame | share of a run | "
          "time against triangles |" + (" Blender load (s) |" if args.blender else ""))
    print("|---|---|---|---|---:|---:|---:|---:|---:|" + ("---:|" if args.blender else ""))
    for r in rows:
        line = (f"| {r['format']} | {r['writer']} | {r['faces']} | {'yes' if r['velocities'] else '-'} | "
                f"{r['frames_per_s']:.0f} | {r['ms_per_frame']:.1f} | {r['mb_per_frame']:.2f} | "
                f"{100 * r['share_of_run']:.0f} % | {r['against_triangles']:.2f}x |")
        if args.blender:
            load = r.get("blender_load_s")
            line += f" {load:.1f} |" if load is not None else " |"
        print(line)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
