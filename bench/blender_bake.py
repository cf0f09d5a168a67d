"""The Wet Cloth extension's bake against ``wetcloth run`` on the same scene: the bake's overhead.

    .venv/bin/python bench/blender_bake.py [--cuts 23] [--frames 120] [--repeats 3] [--zip wetcloth-0.1.0.zip]
                                           [--cloth round --segments 48 --rings 16]

1. Builds the extension (``wetcloth blender-extension``, unless --zip is given) and, in bpy
   (.venv-blender, its own user folder), bakes a towel over a ball in a pool: a 0.8 m plane
   subdivided by --cuts (25 x 25 particles by default), a UV sphere of 0.3 m, water at 0.1 m,
   --frames frames at 24 fps, timing ``bpy.ops.wetcloth.bake()`` alone.  With ``--cloth round`` the
   cloth is a mesh instead: a disc of 0.4 m, --rings rings of --segments quads around an n-gon.
2. Runs the same scene (the one the bake recorded in frames.json; a round cloth from the arrays
   Blender held, as the extension reads them) here, as ``wetcloth run --export DIR --format usd``
   does it: ``runner.run`` writing a USD sequence.
Both --repeats times, interleaved (a bake, a run, a bake, ...); then, for the plane, times the
``wetcloth run`` command itself once (a fresh process: imports, the CSV and plot too).  Prints the best times and
the ratio bake / run, best against best and the median of the pairs (the target is at most 1.1).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.cli import main as cli_main
from wetcloth.exporter import open_sequence
from wetcloth.runner import run
from wetcloth.exporter.blender_extension.geometry import cloth_of
from wetcloth.scene import COLLIDER_FIELDS, from_dict

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"
FPS = 24


def scene_toml(values: dict, duration: float) -> str:
    """A scene file of a flattened scene dict (colliders as [[collider]] tables) with its [run] table."""
    lines, colliders = [], {}
    for name, value in values.items():
        if name.startswith("collider") and "_" in name and name.split("_", 1)[1] in COLLIDER_FIELDS:
            number, field = name[len("collider"):].split("_", 1)
            colliders.setdefault(int(number), {})[field] = value
        else:
            lines.append(f"{name} = {json.dumps(value)}")
    for k in sorted(colliders):
        lines += ["", "[[collider]]"] + [f"{field} = {json.dumps(value)}" for field, value in colliders[k].items()]
    return "\n".join(lines + ["", "[run]", f"duration = {duration!r}", f"fps = {float(FPS)!r}", ""])


def bake(zip_path: Path, work: Path, args) -> dict:
    """One bake in a fresh bpy process (installing the extension into a scratch user folder)."""
    work.mkdir()
    spec = {"zip": str(zip_path), "work": str(work), "frames": args.frames, "fps": FPS, "cuts": args.cuts,
            "size": 0.8, "height": 0.311, "radius": 0.3, "water": 0.1, "repeats": 1}
    if args.cloth == "round":
        spec["round"] = {"segments": args.segments, "radius": 0.4, "z": 0.311, "insets": args.rings,
                         "inset": 0.36 / args.rings}
    (work / "user").mkdir()
    (work / "spec.json").write_text(json.dumps(spec))
    done = subprocess.run([str(BLENDER_PYTHON), str(ROOT / "bench" / "_blender_bake_probe.py"), str(work / "spec.json"),
                           str(work / "result.json")], capture_output=True, text=True, cwd=work,
                          env=os.environ | {"BLENDER_USER_RESOURCES": str(work / "user")})
    if done.returncode != 0 or not (work / "result.json").exists():
        sys.exit(f"the bake failed:\n{done.stderr[-3000:]}")
    return json.loads((work / "result.json").read_text())


def run_seconds(scene, manifest: dict, directory: Path) -> float:
    """``runner.run`` writing a USD sequence of ``scene``, as ``wetcloth run --export --format usd`` does."""
    duration = (manifest["frame_count"] - 1) / manifest["fps"]
    started = time.perf_counter()
    with open_sequence(directory, fmt="usd", fps=manifest["fps"], scene=scene) as frames:
        run(scene, duration, manifest["fps"], on_frame=frames.on_frame, progress=False, warn=None)
    return time.perf_counter() - started


def scene_of(baked: dict, manifest: dict):
    """The scene the bake recorded; a round cloth's mesh from the arrays Blender held (world space)."""
    values = manifest["scene"]
    held = baked["cloth"]
    if held is not None:
        matrix = np.array(held["matrix"])
        positions = np.array(held["co"]) @ matrix[:3, :3].T + matrix[:3, 3]
        cloth, pins = cloth_of(positions, np.array(held["edges"]), (held["sizes"], held["loops"]),
                               (held["triangles"], held["triangle_faces"]), [], "Towel")
        values = values | cloth.scene_values() | {"pinned_edge": pins}
    return from_dict(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cuts", type=int, default=23)
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--zip", type=Path)
    parser.add_argument("--cloth", choices=("plane", "round"), default="plane")
    parser.add_argument("--segments", type=int, default=48, help="round cloth: vertices around")
    parser.add_argument("--rings", type=int, default=16, help="round cloth: rings of quads")
    args = parser.parse_args()
    if not BLENDER_PYTHON.exists():
        sys.exit(f"{BLENDER_PYTHON} is missing: make .venv-blender/.installed")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        zip_path = args.zip
        if zip_path is None:
            cli_main(["blender-extension", "--out", str(work)])
            zip_path = next(work.glob("wetcloth-*.zip"))
        bakes, runs = [], []
        for k in range(args.repeats):  # interleaved, so that a busy machine slows both alike
            baked = bake(zip_path.resolve(), work / f"bake{k}", args)
            bakes.append(baked["seconds"][0])
            manifest = json.loads(Path(baked["manifest"]).read_text())
            runs.append(run_seconds(scene_of(baked, manifest), manifest, work / f"run{k}"))
        duration = (manifest["frame_count"] - 1) / manifest["fps"]
        command = None
        if args.cloth == "plane":  # (a round cloth has no file for the command to read)
            (work / "scene.toml").write_text(scene_toml(manifest["scene"], duration))
            started = time.perf_counter()
            subprocess.run([str(Path(sys.executable).with_name("wetcloth")), "run", str(work / "scene.toml"), "--export",
                            str(work / "cli"), "--format", "usd", "--no-progress", "--csv", str(work / "out.csv"),
                            "--plot", str(work / "plot.png")], check=True, capture_output=True)
            command = time.perf_counter() - started
    n = manifest["vertex_count"]
    print(f"wetcloth {wetcloth.__version__}, Blender {baked['blender']}: {n} particles, {manifest['frame_count']} frames "
          f"at {manifest['fps']:g} fps ({duration:g} s simulated), best of {args.repeats}")
    print(f"| | s |\n|---|---|\n| bpy.ops.wetcloth.bake() | {min(bakes):.3f} |\n"
          f"| runner.run + USD export (what wetcloth run does) | {min(runs):.3f} |\n"
          + (f"| wetcloth run --export --format usd (a fresh process) | {command:.3f} |" if command else ""))
    print("pairs (bake, run) s: " + ", ".join(f"({b:.2f}, {r:.2f})" for b, r in zip(bakes, runs)))
    ratios = sorted(b / r for b, r in zip(bakes, runs))
    print(f"bake / run: {min(bakes) / min(runs):.3f} best against best, {ratios[len(ratios) // 2]:.3f} the median "
          f"of the {len(ratios)} interleaved pairs (target <= 1.1)")


if __name__ == "__main__":
    main()
