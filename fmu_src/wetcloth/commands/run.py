"""``wetcloth run``: simulate a scene, write its outputs as CSV and a plot, optionally export meshes."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wetcloth.errors import BlowUpError
from wetcloth.runner import run
from wetcloth.scene import load_scene, read_scene_file

DEFAULT_DURATION = 10.0  # s, when neither the command line nor the scene file's [run] table says
DEFAULT_FPS = 30.0


def parse_assignment(text: str) -> tuple[str, str]:
    """'name=value' from ``--set``."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"--set expects NAME=VALUE, got {text!r}")
    return name.strip(), value.strip()


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="simulate a scene and write its outputs",
                       description="Simulate a scene (default: the towel) and write CSV outputs and a plot.")
    p.add_argument("scene", nargs="?", default=None, help="scene TOML file or preset name (default: towel)")
    p.add_argument("--duration", type=float, help="simulated time, s (default: the scene file's [run] duration)")
    p.add_argument("--fps", type=float, help="output frames per second (default: the scene file's, or 30)")
    p.add_argument("--set", dest="overrides", action="append", default=[], type=parse_assignment,
                   metavar="NAME=VALUE", help="override a scene parameter (repeatable)")
    p.add_argument("--export", type=Path, metavar="DIR", help="write one mesh per frame into DIR")
    p.add_argument("--format", default="ply", choices=["ply", "obj", "usd"], help="mesh format (default ply)")
    p.add_argument("--writer", default="trimesh", choices=["trimesh", "meshio"], help="mesh writer (default trimesh)")
    p.add_argument("--faces", default="quads", choices=["quads", "triangles"],
                   help="mesh faces: one quad per grid cell or two triangles (default quads)")
    p.add_argument("--first-frame", type=int, default=1, metavar="N",
                   help="number of the first frame: file <prefix>_N, USD time code N, Blender frame N (default 1)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an earlier export in DIR (one described by its own frames.json)")
    p.add_argument("--csv", type=Path, default=Path("out/run/outputs.csv"), help="outputs CSV (default out/run/outputs.csv)")
    p.add_argument("--plot", type=Path, default=Path("out/run/plot.png"), help="plot PNG (default out/run/plot.png)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


def main(args) -> int:
    run_table = read_scene_file(args.scene).get("run", {})
    scene = load_scene(args.scene, **dict(args.overrides))
    duration = args.duration if args.duration is not None else float(run_table.get("duration", DEFAULT_DURATION))
    fps = args.fps if args.fps is not None else float(run_table.get("fps", DEFAULT_FPS))
    title = f"{args.scene or 'towel'}: {duration:g} s"
    # Every output is checked before any simulating: a run is not thrown away at its end.
    _check_writable(args.csv, "--csv")
    _check_writable(args.plot, "--plot")
    sequence = None
    if args.export is not None:
        from wetcloth.exporter import open_sequence  # only needed when exporting

        sequence = open_sequence(args.export, fmt=args.format, writer=args.writer, fps=fps, scene=scene,
                                 faces=args.faces, first_frame=args.first_frame, overwrite=args.overwrite)
    try:
        result = run(scene, duration, fps, on_frame=sequence.on_frame if sequence else None,
                     progress=False if args.no_progress else None)
    except BaseException as exc:  # a blow-up, Ctrl-C, a full disk: keep what was good
        if sequence is not None:
            sequence.close(complete=False)  # frames.json counts the frames on disk; USD saved
        partial = exc.partial_result if isinstance(exc, BlowUpError) else None
        if partial is not None and partial.rows:
            written = _write_outputs(partial, args, title + f" (stopped at {partial.rows[-1]['time']:g} s)")
            print(f"the run stopped early; outputs up to t = {partial.rows[-1]['time']:g} s are in {written}",
                  file=sys.stderr)
        raise
    if sequence is not None:
        sequence.close()
    last = result.rows[-1]
    print(f"simulated {duration:g} s: depth {last['depth'] * 100:.2f} cm, wet mass {last['wet_mass'] * 1000:.1f} g")
    written = _write_outputs(result, args, title)
    print(f"wrote {written}" + (f"; meshes in {args.export}" if args.export else ""))
    return 0


def _write_outputs(result, args, title: str) -> str:
    """Write the outputs CSV and the plot of ``result``; return their paths as text."""
    from wetcloth.plotting import plot_run

    csv_path = result.write_csv(args.csv)
    plot_path = plot_run(result, args.plot, title=title)
    return f"{csv_path} and {plot_path}"


def _check_writable(path: Path, option: str) -> None:
    """Refuse an output file that cannot be written (ValueError naming the option), leaving no trace."""
    existed = path.exists()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "a"):
            pass
    except OSError as exc:
        raise ValueError(f"{option} {path}: cannot write there ({exc.strerror or exc})") from None
    if not existed:
        path.unlink()
