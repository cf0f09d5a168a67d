"""``wetcloth run``: simulate a scene, write its outputs as CSV and a plot, optionally export meshes.

Whatever stops a run early (a blow-up, Ctrl-C, a full disk) the outputs of the frames computed
so far are written, and an export's ``frames.json`` counts the frames on disk.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tqdm.auto import tqdm

from wetcloth import run_settings
from wetcloth.commands.common import FAILED, INTERRUPTED, csv_path, path_argument, scene_with_overrides
from wetcloth.errors import BlowUpError
from wetcloth.runner import interrupts_held, run
from wetcloth.scene import read_scene_file, spelled_number


def parse_assignment(text: str) -> tuple[str, str]:
    """'name=value' from ``--set``."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"--set expects NAME=VALUE, got {text!r}")
    return name.strip(), value.strip()


def number_argument(kind):
    """An argument type: the ``kind`` (int or float) a command-line number spells, refusing what Python
    reads but a person would not mean (``1_0`` is 10 to ``float``)."""
    def number(text: str):
        value = spelled_number(text, (kind,))
        if value is None:
            raise argparse.ArgumentTypeError(f"expected {'a whole number' if kind is int else 'a number'}, got {text!r}")
        return value
    return number


#: Options that only shape an export, and their defaults (the parser's are None: what was given is known).
EXPORT_OPTIONS = {"format": "ply", "writer": None, "faces": "quads", "first_frame": 1, "overwrite": False}


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="simulate a scene and write its outputs",
                       description="Simulate a scene (default: the towel) and write CSV outputs and a plot. "
                                   "'wetcloth params' lists the parameters.")
    p.add_argument("scene", nargs="?", default=None, help="scene TOML file or preset name (default: towel)")
    p.add_argument("--duration", type=number_argument(float),
                   help=f"simulated time, s (default: the scene file's [run] duration, else {run_settings.DEFAULTS['duration']:g})")
    p.add_argument("--fps", type=number_argument(float),
                   help=f"output frames per second (default: the scene file's [run] fps, else {run_settings.DEFAULTS['fps']:g})")
    p.add_argument("--set", dest="overrides", action="append", default=[], type=parse_assignment,
                   metavar="NAME=VALUE", help="override a scene parameter (repeatable)")
    p.add_argument("--export", type=path_argument, metavar="DIR", help="write one mesh per frame into DIR")
    p.add_argument("--format", choices=["ply", "obj", "usd"], help="mesh format (default ply)")
    p.add_argument("--writer", choices=["trimesh", "meshio"],
                   help="mesh writer of ply and obj frames (default trimesh; usd is written by usd-core)")
    p.add_argument("--faces", choices=["quads", "triangles"],
                   help="mesh faces of a rectangle: one quad per grid cell or two triangles (default quads); a cloth "
                        "from a mesh file keeps its file's faces with quads, else its triangles")
    p.add_argument("--first-frame", type=number_argument(int), metavar="N",
                   help="number of the first frame: file <prefix>_N, USD time code N, Blender frame N (default 1)")
    p.add_argument("--overwrite", action="store_const", const=True,
                   help="replace an earlier export in DIR (one described by its own frames.json)")
    p.add_argument("--csv", type=csv_path, default=Path("out/run/outputs.csv"),
                   help="outputs CSV (default out/run/outputs.csv)")
    p.add_argument("--plot", type=path_argument, default=Path("out/run/plot.png"),
                   help="plot PNG (default out/run/plot.png)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


def scene_and_settings(args):
    """The scene (file, then ``--set``) and the run settings (options, then the file's [run]);
    every mistake of the command line reported at once."""
    scene = scene_with_overrides(args.scene, args.overrides)
    settings = run_settings.resolve(read_scene_file(args.scene).get("run"), duration=args.duration, fps=args.fps)
    return scene, settings


def check_options(args) -> None:
    """Refuse what the command line asks for but the run would not do: export options without ``--export``,
    a ``--set`` of a run setting (ValueError naming the option; a parameter set twice: scene_with_overrides)."""
    if args.export is None:
        given = [name for name in EXPORT_OPTIONS if getattr(args, name) is not None]
        if given:
            option = "--" + given[0].replace("_", "-")
            raise ValueError(f"{option} applies to an export only: add --export DIR (or leave out {option})")
    for name, _ in args.overrides:
        if name in run_settings.SETTINGS:
            raise ValueError(f"--set {name}: {name} is a run setting, not a scene parameter: use --{name}")


def main(args) -> int:
    check_options(args)
    for name, default in EXPORT_OPTIONS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)
    if args.writer is not None and args.format == "usd":
        raise ValueError(f"--writer {args.writer} does not apply to --format usd: usd-core writes USD files; "
                         "leave out --writer (it chooses the library of ply and obj frames)")
    args.writer = args.writer or "trimesh"
    scene, settings = scene_and_settings(args)
    # Every output is checked before any simulating: a run is not thrown away at its end.
    _check_writable(args.csv, "--csv")
    _check_writable(args.plot, "--plot")
    _check_image_format(args.plot)
    sequence = None
    if args.export is not None:
        from wetcloth.exporter import ExportError, open_sequence  # only needed when exporting
        from wetcloth.exporter.sequence import OVERWRITE

        try:
            sequence = open_sequence(args.export, fmt=args.format, writer=args.writer, fps=settings.fps, scene=scene,
                                     faces=args.faces, first_frame=args.first_frame, overwrite=args.overwrite,
                                     frame_count=run_settings.whole_frames(settings.duration, settings.fps))
        except ExportError as exc:  # the exporter's names of its arguments made the command line's
            message = str(exc).replace(OVERWRITE, "--overwrite")
            if message.startswith("first_frame "):
                message = message.replace("first_frame ", "--first-frame ").replace("a first_frame", "a --first-frame")
            raise ExportError(message) from None
    stop = None
    try:
        result = run(scene, settings.duration, settings.fps, on_frame=sequence.on_frame if sequence else None,
                     progress=not args.no_progress, warn=_warn)
    except (Exception, KeyboardInterrupt) as exc:  # a blow-up, Ctrl-C, a full disk: keep what was good
        result, stop = getattr(exc, "partial_result", None), exc
    problems: list[str] = []  # what could not be written; reported after why the run stopped
    try:  # a Ctrl-C while the outputs are written stops the command once they are
        with interrupts_held():
            kept = _keep(result, sequence, args, f"{args.scene or 'towel'}: {settings.duration:g} s", stop is None,
                         problems)
    except KeyboardInterrupt as exc:
        stop = stop or exc
    trouble = "".join(f"; {p}" for p in problems)
    if stop is None:
        last = result.rows[-1]
        worst = max(result.rows, key=lambda row: row["step_error"])
        print(f"simulated {settings.duration:g} s: centroid {_below_water(last['depth'])}, "
              f"wet mass {last['wet_mass'] * 1000:.1f} g; the steps' own error estimate at most "
              f"{worst['step_error'] * 1000:.3g} mm in a frame (t = {worst['time']:g} s; column step_error)")
        if problems:
            print(f"wetcloth run: error: {trouble[2:]}; written: {kept or 'nothing'}", file=sys.stderr)
            return FAILED
        print(f"wrote {kept}")
        return 0
    so_far = f"outputs up to t = {result.rows[-1]['time']:g} s are in {kept}" if kept else "nothing was written"
    if isinstance(stop, KeyboardInterrupt):
        print(f"wetcloth run: interrupted; {so_far}{trouble}", file=sys.stderr)
        return INTERRUPTED
    if not isinstance(stop, (BlowUpError, OSError, ValueError)):
        raise stop  # not a user's problem: a bug, with its traceback (the outputs are saved)
    print(f"wetcloth run: error: {stop}\nthe run stopped early; {so_far}{trouble}", file=sys.stderr)
    return FAILED


def _keep(result, sequence, args, title: str, complete: bool, problems: list[str]) -> str:
    """Close the frame sequence (frames.json counts the frames on disk) and write the outputs CSV
    and plot of ``result``, each whole or not at all; what was kept, as text ('' for nothing).
    What could not be written is added to ``problems``."""
    from wetcloth.plotting import plot_run

    frames = ""
    if sequence is not None:  # first: the manifest must come true, the rest is written if there is room
        try:
            sequence.close(complete=complete)
        except (OSError, ValueError) as exc:
            problems.append(str(exc))
        frames = f"{sequence.frame_count} frames in {sequence.directory}" if sequence.frame_count else ""
    kept = []
    if result is not None and result.rows:
        if not complete:
            title += f" (stopped at {result.rows[-1]['time']:g} s)"
        for path, write in ((args.csv, result.write_csv), (args.plot, lambda p: plot_run(result, p, title=title))):
            try:
                kept.append(str(write(path)))
            except OSError as exc:
                problems.append(f"cannot write {path}: {exc.strerror or exc}")
    return "; ".join(filter(None, [" and ".join(kept), frames]))


def _warn(message: str) -> None:
    tqdm.write(f"wetcloth run: warning: {message}", file=sys.stderr)


def _below_water(depth: float) -> str:
    """Where a centroid ``depth`` m under the water surface is, in words (cm; metres when far)."""
    side = "below" if depth >= 0.0 else "above"
    size = abs(depth)
    return f"{size * 100:.2f} cm {side} the water" if size < 1.0 else f"{size:.2f} m {side} the water"


def _check_image_format(path: Path) -> None:
    """Refuse a ``--plot`` file of a format matplotlib does not write (ValueError naming the option)."""
    from wetcloth.plotting import image_format

    try:
        image_format(path)
    except ValueError as exc:
        raise ValueError(f"--plot {exc}") from None


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
