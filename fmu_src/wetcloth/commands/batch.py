"""``wetcloth batch``: run a parameter study on Dask (a local cluster by default), one table row per run;
with a ``[sensitivity]`` table, also its sensitivity indices; with ``--dry-run``, only its run list
and an estimate of their time."""

from __future__ import annotations

import sys
from pathlib import Path

from wetcloth.batch.engines import ENGINES
from wetcloth.batch.results import KEY
from wetcloth.commands.common import (INTERRUPTED, check_fmu_file, check_writable_folder, csv_path, path_argument,
                                      scheduler_argument)
from wetcloth.errors import Mistakes
from wetcloth.scene import preset_dir

#: Where results go without --out: <study name>.parquet in this folder.
DEFAULT_OUT_DIR = Path("out/batch")
#: Exit status of a study whose runs all failed, or a sensitivity study that ran but could not compute
#: every metric's indices.
INCOMPLETE = 1
#: How many refused runs an error names (then how many more there are).
NAMED_RUNS = 3


def add_parser(sub) -> None:
    p = sub.add_parser(
        "batch",
        help="run a parameter study (many scenes) on Dask",
        description=(
            "Run every scene of a study file on Dask: with no --scheduler a local cluster of processes "
            "(one per core, or --workers N) starts and stops by itself; with --scheduler the study runs "
            "on that cluster. Results go to a Parquet table, one row per run; a rerun skips the runs "
            "already in it. A study with series = [...] keeps its runs' curves beside it (<table>.series.zarr, "
            "an xarray Dataset). A study with a [sensitivity] table also writes its sensitivity indices "
            "(<table>_sensitivity.csv) and their bar plot. See docs/batch.md."
        ),
    )
    shipped = ", ".join(sorted(f.stem for f in (preset_dir() / "studies").glob("*.toml")))
    p.add_argument("study", type=path_argument,
                   help=f"study TOML file, or the name of one shipped with wetcloth ({shipped}); see docs/batch.md")
    p.add_argument("--scheduler", type=scheduler_argument, metavar="ADDRESS",
                   help="address of a running Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local cluster: number of worker processes (default: one per core); "
                        "with --scheduler: wait until N workers are connected")
    p.add_argument("--out", type=path_argument, metavar="FILE",
                   help="results table, Parquet (default: out/batch/<study name>.parquet)")
    p.add_argument("--csv", type=csv_path, metavar="FILE", help="also write the results as CSV")
    p.add_argument("--engine", choices=ENGINES, help="simulate with the Python simulator (default) or the FMU through fmpy")
    p.add_argument("--fmu", type=path_argument, metavar="PATH", help="FMU for --engine fmu (default: models/WetCloth.fmu)")
    p.add_argument("--plot", action="append", default=[], metavar="METRIC:AXIS[,AXIS2]",
                   help="plot a metric against one axis, or as a heatmap over two axes; series:AXIS: the kept "
                        "curves coloured by AXIS (repeatable)")
    p.add_argument("--plot-dir", type=path_argument, metavar="DIR", help="where plots go (default: beside the results table)")
    p.add_argument("--retry-errors", action="store_true", help="run again the runs recorded with status 'error'")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--dry-run", action="store_true",
                   help="list the runs (done, failed, to run) and estimate their time from short timed runs "
                        "in this process; start no cluster, run nothing")
    p.set_defaults(func=main)


def _with_unit(study):
    """The study with the unit its FMU engine runs: models/WetCloth.fmu (built if missing or stale), or
    for a scene with colliders or grip keys (built into a unit, not variables) a unit built from the
    scene file, out/batch/STUDY.fmu."""
    from wetcloth import batch
    from wetcloth.fmu.builder import build_fmu, is_stale
    from wetcloth.scene import from_dict

    scene = from_dict(study.runs()[0].params)
    if scene.colliders or scene.grip_keys or scene.collider_keys:
        unit = build_fmu(DEFAULT_OUT_DIR / f"{study.name}.fmu", scene=study.scene)
        print(f"built {unit}: the scene's colliders and grip keys are in it")
        return study.replace(fmu=str(unit))
    default = batch.default_fmu_path()
    if is_stale(default):  # missing or older than wetcloth's sources: as 'wetcloth build-fmu' would
        print(f"building {build_fmu(default)}")
    return study


def main(args) -> int:
    from wetcloth import batch  # imports dask: only when the command runs

    study = batch.load_study(args.study)
    mistakes, plot_specs = Mistakes(), []  # every --plot mistake at once
    for text in args.plot:
        with mistakes.collect():
            plot_specs.append(batch.parse_plot_spec(text))
    with mistakes.collect():
        study.check_plots(plot_specs)
    mistakes.raise_if_any()
    out = args.out if args.out is not None else DEFAULT_OUT_DIR / f"{study.name}.parquet"  # the name is a plain file name
    if out.suffix.lower() == ".csv":
        raise ValueError(f"--out {out} is the Parquet results table; give --csv FILE for a CSV copy")
    check_writable_folder(out.parent, "--out", out)  # before a unit is built or anything runs
    existing = _existing_table(out)
    if args.plot_dir is not None:
        check_writable_folder(args.plot_dir, "--plot-dir")
    if args.engine is not None:
        study = study.replace(engine=args.engine)
    if args.fmu is not None:
        study = study.replace(fmu=str(args.fmu))
    if study.engine == "fmu" and study.fmu:
        check_fmu_file(Path(study.fmu), "--fmu" if args.fmu is not None else "the study's fmu")
    _refuse_invalid_runs(study, existing, out, args.retry_errors)  # before a unit is built or anything runs
    if study.engine == "fmu" and not study.fmu:
        study = _with_unit(study)
    if args.dry_run:
        return dry_run(study, out, args)
    try:
        report = batch.run_study(
            study,
            out=out,
            scheduler=args.scheduler,
            workers=args.workers,
            progress=not args.no_progress,
            retry_errors=args.retry_errors,
            announce=lambda line: print(line, file=sys.stderr, flush=True),
        )
    except KeyboardInterrupt:
        if out.exists():
            print(f"wetcloth batch: interrupted; the finished runs are in {out}: run the same command again to resume",
                  file=sys.stderr)
        else:
            print("wetcloth batch: interrupted before any run was saved: run the same command again to start",
                  file=sys.stderr)
        return INTERRUPTED
    table = report.table
    print(report.summary())
    failed = table[table["status"] != "ok"]
    status = 0
    if len(table) and len(failed) == len(table):  # nothing to show for the study: say so in the status
        print(f"wetcloth batch: every run of the study failed; the first: {failed['error'].iloc[0].splitlines()[0]}",
              file=sys.stderr)
        status = INCOMPLETE
    written = [str(out)]
    if report.series_path is not None and report.series_path.exists():
        written.append(str(report.series_path))
    if args.csv is not None:
        written.append(str(batch.write_csv(table, args.csv)))
    plot_dir = args.plot_dir if args.plot_dir is not None else out.parent
    for spec in [*study.plots, *plot_specs]:
        # named after the table, so that runs with another --out keep their plots apart
        if isinstance(spec, batch.SeriesPlotSpec):
            name = spec.filename(out.stem, study.series, study.axis_names[0] if study.axis_names else None)
        else:
            name = spec.filename(out.stem)
        written.append(str(batch.plot(table, spec, plot_dir / name, study=study, series=report.series)))
    if study.sensitivity is not None:
        result = batch.sensitivity_indices(study, table)
        print(batch.format_indices(result))
        written.append(str(batch.write_csv(result.indices, out.with_name(f"{out.stem}_sensitivity.csv"))))
        written.append(str(batch.plot_sensitivity(result, plot_dir / f"{out.stem}_sensitivity.png", study=study)))
        if result.problems:
            print(f"wetcloth batch: no sensitivity indices for {', '.join(result.problems)} (why: above)", file=sys.stderr)
            status = INCOMPLETE
    print("wrote " + ", ".join(written))
    return status


def _existing_table(out: Path):
    """The results table at ``out`` (empty if there is none yet); a file there that is not one is refused,
    naming --out, before anything runs (a rerun would read it, and then overwrite it)."""
    from wetcloth.batch import read_table

    if out.is_dir():
        raise ValueError(f"--out {out} is a folder: give the results table's file name, e.g. {out / 'study.parquet'}")
    try:
        return read_table(out)
    except (OSError, ValueError) as exc:
        raise ValueError(f"--out {out} holds something that is not a wetcloth results table (a Parquet file "
                         f"with a run_key column; {str(exc).splitlines()[0]}): give another --out") from None


def _refuse_invalid_runs(study, existing, out: Path, retry_errors: bool) -> None:
    """Refuse the study, before any run, if a run still to run has a value its scene refuses (a value out
    of range, a mesh file that is not there): a ValueError naming the first few runs (as the dry run
    numbers them) and why."""
    from wetcloth.batch.execution import runs_to_do, series_store
    from wetcloth.scene import from_dict

    store = series_store(study, out)
    curves = store.complete_keys(study.series) if store is not None else None
    runs = study.runs()
    todo = {r.key for r in runs_to_do(runs, existing, retry_errors, curves)}
    refused = []
    for number, run in enumerate(runs, 1):
        if run.key in todo:
            try:
                from_dict(run.params)
            except ValueError as exc:
                refused.append(f"run {number}: " + " ".join(line.strip() for line in str(exc).splitlines()))
    if refused:
        more = f"; and {len(refused) - NAMED_RUNS} more" if len(refused) > NAMED_RUNS else ""
        has = "run has" if len(refused) == 1 else "runs have"
        raise ValueError(f"study {study.name!r}: {len(refused)} of its {len(runs)} {has} a value that "
                         f"is refused, so nothing was run (fix the axes or [base]; --dry-run lists the runs): "
                         + "; ".join(refused[:NAMED_RUNS]) + more)


def dry_run(study, out: Path, args) -> int:
    """Print the runs of ``study`` (done, failed or to run by the table at ``out``) and an estimate of
    their time; run nothing, start no cluster."""
    from wetcloth.batch import preview, read_table
    from wetcloth.batch.execution import series_store

    existing = read_table(out)
    store = series_store(study, out)
    curves = store.complete_keys(study.series) if store is not None else None
    listing = preview.run_listing(study, existing, args.retry_errors, curves)
    counts = listing["state"].value_counts()
    recorded = set(existing.loc[existing["status"] == "ok", KEY]) if len(existing) else set()  # ok, without curves
    n_again = sum(r.key in recorded for r, state in zip(study.runs(), listing["state"]) if state == "to run")
    again = f" ({n_again} of them again, for curves missing from {store.path})" if n_again else ""
    how = study.sensitivity.describe(len(study.axes)) if study.sensitivity is not None else (
        f"{study.sampling} sampling" if any(a.is_random for a in study.axes) else "grid")
    print(f"{study.name}: {len(listing)} runs ({how}); in {out}: {counts.get('done', 0)} done, "
          f"{counts.get('failed', 0)} failed{' (kept: --retry-errors runs them again)' if counts.get('failed') else ''}; "
          f"{counts.get('to run', 0)} to run{again}")
    print(preview.format_listing(listing))
    todo = [r for r, state in zip(study.runs(), listing["state"]) if state == "to run"]
    from dask.system import CPU_COUNT  # as the local cluster would count them

    if args.workers is not None:
        workers = args.workers
    elif args.scheduler is None:
        workers = CPU_COUNT
    else:
        workers = None  # a remote cluster's workers are not asked for in a dry run
    estimate = preview.estimate_time(study, todo)
    # a local cluster's start, warm-up and stop (a remote one is running already)
    startup = preview.startup_time(workers, CPU_COUNT) if args.scheduler is None and estimate.runs else None
    print(preview.format_estimate(estimate, workers, startup=startup))
    return 0
