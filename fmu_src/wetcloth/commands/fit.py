"""``wetcloth fit``: fit scene parameters to measured curves or sink times (docs/fit.md)."""

from __future__ import annotations

import sys
from pathlib import Path

from wetcloth import run_settings
from wetcloth.commands.common import (check_writable_folder, path_argument, scene_with_overrides, scheduler_argument,
                                      seed_argument)
from wetcloth.commands.run import parse_assignment
from wetcloth.errors import Mistakes
from wetcloth.scene import read_scene_file

#: Where the report goes without --out: out/fit/<data file name without suffix>/.
DEFAULT_OUT_DIR = Path("out/fit")


def add_parser(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit scene parameters to measurements",
        description=(
            "Fit number parameters of a scene to measurements: curves (a CSV with 'time' in s and any of depth, "
            "wet_mass, water_mass, centroid_x/y/z, each with an optional sigma_NAME column of its noise) by "
            "nonlinear least squares, or sink times (a CSV with 'time_to_sink' in s alone, one row per timed drop) "
            "by a root search for one parameter. Prints the estimates with standard errors, 95 % intervals and "
            "correlations, and writes fit.json, fitted_scene.toml and fit.png. See docs/fit.md."),
    )
    p.add_argument("scene", help="scene TOML file or preset name: the cloth measured; the fitted parameters "
                                 "start from its values")
    p.add_argument("--data", type=path_argument, required=True, metavar="MEASURED.csv", help="the measurements (CSV)")
    p.add_argument("--params", required=True, metavar="NAME[,NAME...]",
                   help="the parameters to fit, comma-separated: number parameters of the scene, or number fields of "
                        "its [[collider]], [[grip_key]] and [[collider_key]] tables (collider1_z, grip_key2_z)")
    p.add_argument("--bounds", nargs="+", action="extend", default=[], metavar="NAME=LO:HI",
                   help="keep a parameter within LO..HI (default: its allowed range; --global needs them)")
    p.add_argument("--set", dest="overrides", action="append", default=[], type=parse_assignment,
                   metavar="NAME=VALUE", help="override a scene parameter: a fixed one, or a fitted one's start (repeatable)")
    p.add_argument("--global", dest="global_search", action="store_true",
                   help="start with a global search (differential evolution within --bounds) on Dask")
    p.add_argument("--scheduler", type=scheduler_argument, metavar="ADDRESS",
                   help="with --global: the Dask scheduler to run on (default: a local cluster)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="with --global: local cluster's worker processes (default one per core); with --scheduler: "
                        "wait for N workers")
    p.add_argument("--seed", type=seed_argument, default=0, help="seed of the global search, 0..2**32 - 1 (default 0)")
    p.add_argument("--sink-depth", type=float, default=0.05, metavar="M",
                   help="sink times: m below the surface at which the cloth counts as sunk (default 0.05, "
                        "as in studies)")
    p.add_argument("--out", type=path_argument, metavar="DIR",
                   help="where the report goes (default: out/fit/<data file name>/)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


def main(args) -> int:
    from wetcloth.calibration import fit, parse_bounds, read_measurements, summary, write_report
    from wetcloth.calibration.parameters import BoundsError

    scene = scene_with_overrides(args.scene, args.overrides)
    names = [n.strip() for n in args.params.split(",") if n.strip()]
    bounds = {}
    mistakes = Mistakes()
    for text in args.bounds:
        with mistakes.collect():
            name, lo, hi = parse_bounds(text)
            if name in bounds:
                raise BoundsError(name, "given twice")
            bounds[name] = (lo, hi)
    mistakes.raise_if_any()
    if not args.global_search and (args.scheduler or args.workers is not None):
        raise ValueError("--scheduler and --workers are for the global search: add --global")
    data = read_measurements(args.data)
    out = args.out if args.out is not None else DEFAULT_OUT_DIR / args.data.stem
    check_writable_folder(out, "--out")
    result = fit(scene, data, names, bounds, global_search=args.global_search, scheduler=args.scheduler,
                 workers=args.workers, seed=args.seed, sink_depth=args.sink_depth, progress=not args.no_progress,
                 announce=lambda line: print(line, file=sys.stderr, flush=True))
    print(summary(result, str(args.data), warnings=False))
    for warning in result.warnings:
        print(f"wetcloth fit: warning: {warning}", file=sys.stderr)
    fps = run_settings.resolve(read_scene_file(args.scene).get("run")).fps
    written = write_report(result, out, data_path=str(args.data), scene=args.scene, fps=fps)
    print("wrote " + ", ".join(str(p) for p in written))
    return 0
