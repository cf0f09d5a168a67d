"""``wetcloth demo``: co-simulate the default towel through WetCloth.fmu (fmpy); frames, CSV and plot."""

from __future__ import annotations

from pathlib import Path

from wetcloth.commands.common import path_argument


def add_parser(sub) -> None:
    from wetcloth.fmu import default_fmu_path

    p = sub.add_parser("demo", help="co-simulate the default towel through WetCloth.fmu",
                       description="Build the unit (models/WetCloth.fmu) if missing or older than the sources, co-simulate "
                                   "the default towel through fmpy for the preset's duration, and write PLY "
                                   "frames, outputs.csv and plot.png.")
    p.add_argument("--out", type=path_argument, default=Path("out/demo"), help="output folder (default out/demo)")
    p.add_argument("--fmu", type=path_argument, default=default_fmu_path(),
                   help=f"the unit to use, built there if needed (default {default_fmu_path()})")
    p.add_argument("--duration", type=float, help="simulated time, s (default: the towel preset's [run] duration)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=main)


def main(args) -> int:
    from wetcloth.fmu.cosim import demo

    paths = demo(args.out, fmu=args.fmu, duration=args.duration, progress=not args.no_progress)
    print(f"co-simulated the towel through {paths['fmu']}: frames in {paths['frames']}, "
          f"outputs in {paths['csv']}, plot in {paths['plot']}")
    return 0
