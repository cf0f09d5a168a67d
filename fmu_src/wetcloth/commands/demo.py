"""``wetcloth demo``: co-simulate the default towel through WetCloth.fmu and WetClothNative.fmu (fmpy); frames,
CSV and a plot of both."""

from __future__ import annotations

from pathlib import Path

from wetcloth.commands.common import check_out_suffix, check_writable_folder, path_argument


def add_parser(sub) -> None:
    from wetcloth.fmu import default_fmu_path

    p = sub.add_parser("demo", help="co-simulate the default towel through WetCloth.fmu and WetClothNative.fmu",
                       description="Build the unit (models/WetCloth.fmu) if missing or older than the sources, co-simulate "
                                   "the default towel through fmpy for the preset's duration, and write PLY "
                                   "frames, outputs.csv and plot.png; then build the native unit "
                                   "(models/WetClothNative.fmu) and co-simulate the same towel through it, its "
                                   "curves drawn over the first's.")
    p.add_argument("--out", type=path_argument, default=Path("out/demo"), help="output folder (default out/demo)")
    p.add_argument("--fmu", type=path_argument, default=default_fmu_path(),
                   help=f"the unit to use, built there if needed (default {default_fmu_path()})")
    p.add_argument("--duration", type=float, help="simulated time, s (default: the towel preset's [run] duration)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-native", action="store_true", help="without the native unit's run")
    p.set_defaults(func=main)


def main(args) -> int:
    from wetcloth import run_settings
    from wetcloth.fmu.cosim import demo
    from wetcloth.scene import read_scene_file

    # every argument checked before a unit is built (a minute)
    if args.duration is not None:
        try:
            run_settings.check_setting("duration", args.duration)
        except run_settings.RunSettingError as exc:
            raise ValueError(f"--duration: {exc.problems[0][2]}") from None
    run_settings.resolve(read_scene_file(None).get("run"), duration=args.duration)  # and its frames
    check_out_suffix(args.fmu, ".fmu", "--fmu")  # built there if missing: never over a file of another kind
    check_writable_folder(args.out, "--out", make=False)
    check_writable_folder(args.fmu.parent, "--fmu", args.fmu, make=False)
    paths = demo(args.out, fmu=args.fmu, duration=args.duration, progress=not args.no_progress,
                 native=not args.no_native)
    print(f"co-simulated the towel through {paths['fmu']}: frames in {paths['frames']}, "
          f"outputs in {paths['csv']}, plot in {paths['plot']}")
    if "native" in paths:
        print(f"and through {paths['native']}: outputs differ by {paths['native_difference']:.3g} at most "
              f"(both run the same compiled core)")
    elif "native_skipped" in paths:
        print(f"no native unit: {paths['native_skipped']}")
    return 0
