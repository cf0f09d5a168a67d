"""Batch studies without Dask: study files, run expansion and keys, metrics, results table, plot data."""

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import wetcloth
from wetcloth.batch import StudyError, Study, compute_metrics, first_crossing, heatmap_data, line_data, load_study
from wetcloth.batch.results import make_table, read_table, write_table
from wetcloth.batch import parse_plot_spec
from wetcloth.batch.axes import MAX_RUNS

ROOT = Path(__file__).resolve().parents[1]
STUDIES = sorted((ROOT / "models" / "studies").glob("*.toml"))


def make(**data) -> Study:
    data.setdefault("scene", "thesis_fast")
    data.setdefault("duration", 5.0)
    return Study.from_dict(data, name="t")


# ---------------------------------------------------------------- metrics on hand-made series


def test_first_crossing_interpolates_between_samples():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    y = np.array([0.0, 0.02, 0.08, 0.2])
    # past 0.05 first at t = 2; between (1, 0.02) and (2, 0.08): 1 + 0.03 / 0.06 = 1.5 s
    assert first_crossing(t, y, 0.05, strict=True) == pytest.approx(1.5, rel=1e-12)
    assert first_crossing(t, y, -1.0) == 0.0  # past at the first sample: its time
    assert math.isnan(first_crossing(t, y, 0.5))  # never
    # on the level exactly: '>=' takes that sample, '>' interpolates to the same time
    y2 = np.array([0.0, 0.05, 0.1, 0.2])
    assert first_crossing(t, y2, 0.05) == 1.0
    assert first_crossing(t, y2, 0.05, strict=True) == 1.0


def buras_series(duration=60.0, rate_hz=100.0, m0=0.1575, capacity=3.8, absorption=0.15, v=0.02, t_drop=10.0):
    """Synthetic run: Buras uptake from t = 0 (docs/model.md section 10) and a centroid that floats at
    1 mm until ``t_drop`` s, then goes down at ``v`` m/s."""
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate_hz)
    water = m0 * capacity * (1 - np.exp(-absorption * t / capacity))
    depth = np.where(t < t_drop, 0.001, 0.001 + v * (t - t_drop))
    return dict(time=t, depth=depth, wet_mass=m0 + water, water_mass=water)


def test_metrics_match_hand_computed_values():
    m0, C, R, T, v, t_drop, sink = 0.1575, 3.8, 0.15, 60.0, 0.02, 10.0, 0.05
    series = buras_series(T, 100.0, m0, C, R, v, t_drop)
    names = list(wetcloth.batch.METRICS)
    got = compute_metrics(series, names, sink)
    # depth is piecewise linear and both samples around the crossing lie on the ramp: interpolation is exact
    assert got["time_to_sink"] == pytest.approx(t_drop + (sink - 0.001) / v, rel=1e-12)
    assert got["sank"] is True
    final_water = m0 * C * (1 - math.exp(-R * T / C))
    assert got["final_depth"] == pytest.approx(0.001 + v * (T - t_drop), rel=1e-12)
    assert got["max_depth"] == got["final_depth"]
    assert got["final_wet_mass"] == pytest.approx(m0 + final_water, rel=1e-12)
    assert got["final_water_mass"] == pytest.approx(final_water, rel=1e-12)
    # 90% of the final wet mass: m0 (1 + C (1 - exp(-R t / C))) = 0.9 (m0 + W_T)
    t90_wet = -C / R * math.log(1 - (0.9 * (m0 + final_water) / m0 - 1) / C)
    t90_water = -C / R * math.log(1 - 0.9 * (1 - math.exp(-R * T / C)))
    # linear interpolation of a smooth curve errs by at most h^2/8 * |y''/y'| = (0.01 s)^2 / 8 * R/C ~ 5e-7 s
    assert got["time_to_90_wet_mass"] == pytest.approx(t90_wet, abs=1e-6)
    assert got["time_to_90_water_mass"] == pytest.approx(t90_water, abs=1e-6)


def test_metrics_for_a_cloth_that_never_sinks_or_absorbs():
    t = np.linspace(0.0, 10.0, 101)
    series = dict(time=t, depth=np.full_like(t, 0.0006), wet_mass=np.full_like(t, 0.1575), water_mass=np.zeros_like(t))
    got = compute_metrics(series, ["time_to_sink", "time_to_90_wet_mass", "time_to_90_water_mass"], 0.05)
    assert math.isnan(got["time_to_sink"]) and got["sank"] is False
    assert got["time_to_90_wet_mass"] == 0.0  # already at 100 % of its final mass at t = 0
    assert math.isnan(got["time_to_90_water_mass"])  # no water: undefined


def test_unknown_metric_is_rejected():
    with pytest.raises(ValueError, match="unknown metric 'sink_time'"):
        compute_metrics(buras_series(), ["sink_time"], 0.05)


# ---------------------------------------------------------------- study files


@pytest.mark.parametrize("path", STUDIES, ids=[p.stem for p in STUDIES])
def test_example_studies_parse(path):
    study = load_study(path)
    assert study.runs() and study.name == path.stem
    study.check_plots(study.plots)


def test_grid_axes_cross_in_file_order_with_ranges_and_base():
    s = make(base={"nx": 5, "ny": 5}, axes={
        "absorption_capacity": [3.6, 4.0],
        "initial_tilt": {"start": 0, "stop": 90, "step": 30},  # stop included: 0 30 60 90
        "absorption_rate": {"start": 0.1, "stop": 1.0, "num": 2, "log": True},
    })
    runs = s.runs()
    assert len(runs) == 2 * 4 * 2
    assert [r.point for r in runs[:3]] == [
        {"absorption_capacity": 3.6, "initial_tilt": 0.0, "absorption_rate": 0.1},
        {"absorption_capacity": 3.6, "initial_tilt": 0.0, "absorption_rate": 1.0},
        {"absorption_capacity": 3.6, "initial_tilt": 30.0, "absorption_rate": 0.1},
    ]
    first = runs[0].params
    assert first["nx"] == 5 and first["ny"] == 5  # [base]
    assert first["initial_height"] == 0.1  # from the thesis_fast scene file
    assert first["thickness"] == wetcloth.Scene().thickness  # Scene default
    assert len({r.key for r in runs}) == len(runs)


def test_range_values_are_rounded_so_keys_match_a_list():
    by_range = make(axes={"absorption_rate": {"start": 0.1, "stop": 0.3, "num": 3}})
    by_list = make(axes={"absorption_rate": [0.1, 0.2, 0.3]})
    assert [r.point["absorption_rate"] for r in by_range.runs()] == [0.1, 0.2, 0.3]
    assert [r.key for r in by_range.runs()] == [r.key for r in by_list.runs()]


def test_integer_parameters_take_integer_ranges():
    s = make(axes={"nx": {"start": 5, "stop": 9, "step": 2}})
    assert [r.point["nx"] for r in s.runs()] == [5, 7, 9]
    assert all(isinstance(r.point["nx"], int) for r in s.runs())
    with pytest.raises(StudyError, match="nx takes whole numbers"):
        make(axes={"nx": {"start": 5, "stop": 6, "num": 3}})


def test_random_axes_are_joint_seeded_draws_crossed_with_the_grid():
    data = dict(samples=3, seed=7, axes={
        "initial_tilt": [0.0, 45.0],
        "absorption_rate": {"random": "uniform", "low": 0.1, "high": 0.5},
        "absorption_capacity": {"random": "loguniform", "low": 3.5, "high": 7.0},
    })
    runs = make(**data).runs()
    assert len(runs) == 2 * 3
    draws = [(r.point["absorption_rate"], r.point["absorption_capacity"]) for r in runs]
    assert draws[:3] == draws[3:]  # the same three joint draws for each grid point
    assert all(0.1 <= a < 0.5 and 3.5 <= c <= 7.0 for a, c in draws)
    assert [r.key for r in make(**data).runs()] == [r.key for r in runs]  # reproducible: resumable
    assert [r.key for r in make(**(data | {"seed": 8})).runs()] != [r.key for r in runs]


def test_keys_follow_parameters_and_run_settings():
    s = make(axes={"absorption_rate": [0.2, 0.3]})
    keys = [r.key for r in s.runs()]
    assert [r.key for r in make(axes={"absorption_rate": [0.3]}).runs()] == keys[1:]  # a subset: same keys
    assert [r.key for r in make(duration=6.0, axes={"absorption_rate": [0.2, 0.3]}).runs()] != keys
    assert [r.key for r in make(sink_depth=0.1, axes={"absorption_rate": [0.2, 0.3]}).runs()] != keys
    assert [r.key for r in s.replace(engine="fmu").runs()] != keys


def test_invalid_values_parse_and_fail_per_run_not_up_front():
    s = make(axes={"absorption_rate": [-1.0, 0.2], "nx": [1, 5]})  # ranges are checked per run
    assert len(s.runs()) == 4


@pytest.mark.parametrize("data, key, match", [
    (dict(axes={"absorbtion_rate": [0.1]}), "axes.absorbtion_rate", "'absorbtion_rate': unknown parameter; did you mean 'absorption_rate'"),
    (dict(axes={"mesh_format": ["ply", "obj"]}), "axes.mesh_format", "'mesh_format' is an FMU-only parameter, not a scene"),
    (dict(axes={"absorption_rate": ["fast"]}), "axes.absorption_rate", r"expected a number, got 'fast' .*; allowed: 0 <= absorption_rate <= 10000 1/s"),
    (dict(axes={"drag_model": [1.0]}), "axes.drag_model", "expected a string"),
    (dict(axes={"absorption_rate": [0.1, 0.1]}), "axes.absorption_rate", "repeated values"),
    (dict(axes={"absorption_rate": []}), "axes.absorption_rate", "at least one value"),
    (dict(axes={"absorption_rate": {"start": 0.1, "stop": 0.2}}), "axes.absorption_rate", "exactly one of num or step"),
    (dict(axes={"absorption_rate": {"start": 0.1, "stop": 0.2, "step": -0.1}}), "axes.absorption_rate", "step must be"),
    (dict(axes={"absorption_rate": {"random": "gauss", "mean": 1, "std": 1}}), "axes.absorption_rate", "random must be one of"),
    (dict(axes={"absorption_rate": {"random": "uniform", "low": 0.1, "high": 0.5}}), "samples", "need samples >= 1"),
    (dict(samples=4), "samples", "only for sampled axes"),
    (dict(base={"nx": 5}, axes={"nx": [5, 7]}), "axes.nx", "also set in"),
    (dict(metrics=["time_to_sink", "sink_tme"]), "metrics", "'sink_tme': unknown metric; did you mean 'sink_time'|'sink_tme': unknown metric; known: time_to_sink"),
    (dict(engine="modelica"), "engine", "allowed: python, fmu"),
    (dict(duration=-1.0), "duration", "finite number > 0"),
    (dict(sample_rate=0), "sample_rate", "finite number > 0"),
    (dict(colour={}), "colour", "unknown key; known: name, description"),
    (dict(plot=[{"metric": "final_depth", "x": "nx"}]), "plot", "not an axis of this study"),
])
def test_bad_study_errors_name_the_key(data, key, match):
    with pytest.raises(StudyError, match=match) as info:
        make(**data)
    assert info.value.key == key


def test_scene_path_relative_to_the_study_file(tmp_path):
    (tmp_path / "bare.toml").write_text("nx = 5\n")
    study = tmp_path / "s.toml"
    study.write_text('scene = "bare.toml"\nduration = 2.0\n[axes]\nabsorption_rate = [0.5]\n')
    assert load_study(study).runs()[0].params["nx"] == 5


def test_a_study_preset_loads_by_name_and_a_misspelled_one_gets_the_nearest():
    assert load_study("sink_map").name == "sink_map"
    with pytest.raises(FileNotFoundError, match="'sinkmap' is not a file: .*did you mean 'sink_map'\\?$"):
        load_study("sinkmap")


@pytest.mark.parametrize("name", ["../../x", "/tmp/x", "..", "a/b", "a\\b", ""])
def test_a_study_name_cannot_leave_the_output_folder(name):
    with pytest.raises(StudyError, match="must be a plain file name"):
        make(name=name)


def test_cli_refuses_a_study_whose_name_leaves_the_output_folder(tmp_path, monkeypatch, capsys):
    from wetcloth.cli import main

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    for name in ("../../escaped", str(tmp_path / "absolute")):
        (work / "s.toml").write_text(f'name = "{name}"\nscene = "thesis_fast"\nduration = 1.0\n'
                                     '[axes]\nabsorption_rate = [-1.0]\n')  # a run that needs no cluster
        assert main(["batch", "s.toml", "--no-progress"]) == 2
        assert "study file s.toml: study 'name':" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["s.toml", "work"]  # nothing written anywhere


@pytest.mark.parametrize("data, key, match", [
    (dict(axes={"absorption_rate": {"start": 0.1, "stop": 1.0, "num": 100_000_000}}), "axes.absorption_rate",
     f"num is 1e[+]08; at most {MAX_RUNS} runs per study"),
    (dict(axes={"absorption_rate": {"start": 0.1, "stop": 1.0, "num": 1e8}}), "axes.absorption_rate", "num is 1e[+]08"),
    (dict(axes={"absorption_rate": {"start": 0.0, "stop": 1.0, "step": 1e-12}}), "axes.absorption_rate",
     "step 1e-12 from 0 to 1 gives 1e[+]12; at most"),
    (dict(samples=100_000_000, axes={"absorption_rate": {"random": "uniform", "low": 0.1, "high": 0.5}}), "samples",
     "the axes span 1e[+]08; at most"),
    (dict(axes={"absorption_rate": {"start": 0.1, "stop": 1.0, "num": 1000}, "initial_tilt": {"start": 0, "stop": 90, "num": 1000}}),
     "axes", "the axes span 1e[+]06; at most"),
    (dict(duration=1e6, sample_rate=1000.0), "sample_rate", "1e[+]06 s at 1000 frames/s is 1e[+]09 frames; at most 200000"),
])
def test_work_beyond_sane_bounds_is_refused_naming_the_bound(data, key, match):
    """Refused at once (no values are made: 1e12 values would not fit in memory)."""
    with pytest.raises(StudyError, match=match) as info:
        make(**data)
    assert info.value.key == key


def test_every_mistake_of_a_study_file_at_once(tmp_path):
    path = tmp_path / "typos.toml"
    path.write_text('scene = "thesis_fast"\nduraton = 5.0\nmetrics = ["time_to_snk"]\n'
                    '[base]\nnx = "9"\n[axes]\nabsorbtion_rate = [0.1]\n')
    with pytest.raises(StudyError) as info:
        load_study(path)
    assert str(info.value).splitlines() == [
        f"study file {path}: 4 mistakes",
        "  study 'duraton': unknown key; did you mean 'duration'?",
        "  study 'base.nx': expected a number, got '9' (text: write the number without quotes); allowed: 2 <= nx <= 1024",
        "  study 'axes.absorbtion_rate': 'absorbtion_rate': unknown parameter; did you mean 'absorption_rate'?",
        "  study 'metrics': 'time_to_snk': unknown metric; did you mean 'time_to_sink'?",
    ]


def test_plot_specs():
    assert parse_plot_spec("time_to_sink:absorption_rate") == wetcloth.batch.PlotSpec("time_to_sink", "absorption_rate")
    spec = parse_plot_spec("time_to_sink:absorption_capacity,absorption_rate")
    assert (spec.x, spec.y) == ("absorption_capacity", "absorption_rate")
    with pytest.raises(StudyError, match="METRIC:AXIS"):
        parse_plot_spec("time_to_sink")


# ---------------------------------------------------------------- results table and plot data


def hand_table() -> pd.DataFrame:
    rows = [  # capacity x rate, two repeats per cell (another axis 'initial_tilt')
        dict(run_key="a", absorption_capacity=4.0, absorption_rate=0.2, initial_tilt=0.0, time_to_sink=30.0, sank=True, status="ok", error=None),
        dict(run_key="b", absorption_capacity=4.0, absorption_rate=0.2, initial_tilt=45.0, time_to_sink=20.0, sank=True, status="ok", error=None),
        dict(run_key="c", absorption_capacity=4.0, absorption_rate=0.4, initial_tilt=0.0, time_to_sink=math.nan, sank=False, status="ok", error=None),
        dict(run_key="d", absorption_capacity=4.0, absorption_rate=0.4, initial_tilt=45.0, time_to_sink=10.0, sank=True, status="ok", error=None),
        dict(run_key="e", absorption_capacity=6.0, absorption_rate=0.2, initial_tilt=0.0, time_to_sink=math.nan, sank=None, status="error", error="BlowUpError: x"),
        dict(run_key="f", absorption_capacity=6.0, absorption_rate=0.2, initial_tilt=45.0, time_to_sink=math.nan, sank=None, status="error", error="BlowUpError: y"),
        dict(run_key="g", absorption_capacity=6.0, absorption_rate=0.4, initial_tilt=0.0, time_to_sink=math.nan, sank=False, status="ok", error=None),
    ]
    return make_table(rows, ["absorption_capacity", "absorption_rate", "initial_tilt"])


def test_heatmap_and_line_data():
    values, ok, runs = heatmap_data(hand_table(), "time_to_sink", "absorption_capacity", "absorption_rate")
    assert list(values.columns) == [4.0, 6.0] and list(values.index) == [0.2, 0.4]
    assert values.loc[0.2, 4.0] == 25.0  # mean of 30 and 20
    assert values.loc[0.4, 4.0] == 10.0  # the run that never sank is not averaged in
    assert math.isnan(values.loc[0.2, 6.0]) and ok.loc[0.2, 6.0] == 0 and runs.loc[0.2, 6.0] == 2  # all errors
    assert math.isnan(values.loc[0.4, 6.0]) and ok.loc[0.4, 6.0] == 1  # ran, never sank
    line = line_data(hand_table(), "time_to_sink", "absorption_rate")
    assert line.loc[0.2, "mean"] == 25.0 and line.loc[0.2, "count"] == 2 and line.loc[0.2, "never"] == 0
    assert line.loc[0.4, "mean"] == 10.0 and line.loc[0.4, "count"] == 3 and line.loc[0.4, "never"] == 2


def test_results_table_round_trips_through_parquet(tmp_path):
    table = hand_table()
    path = write_table(table, tmp_path / "r.parquet")
    back = read_table(path)
    pd.testing.assert_frame_equal(back, table, check_dtype=False)
    assert str(back["sank"].dtype) == "boolean" and back["sank"].isna().sum() == 2
    assert back.loc[back.run_key == "e", "error"].item() == "BlowUpError: x"
    assert not list(tmp_path.glob(".*tmp"))  # written atomically, no temporary left over
    assert len(read_table(tmp_path / "missing.parquet")) == 0


@pytest.mark.parametrize("duration", [3.0, 2.05])
def test_a_study_run_gives_the_frames_and_values_of_runner_run_bit_for_bit(duration):
    """python_series (what a study's workers call) against runner.run's columns, on a run of the sensitivity
    example (its towel lands on the water within these seconds); 2.05 s ends on a frame of its own."""
    from wetcloth.batch.engines import RUN_SERIES, python_series
    from wetcloth.runner import run
    from wetcloth.scene import from_dict

    study = load_study(ROOT / "models" / "studies" / "towel_sink_sensitivity.toml")
    params = study.runs()[0].params
    series = python_series(params, duration, study.sample_rate)
    result = run(from_dict(params), duration, study.sample_rate, shapes=0, progress=False, warn=None)
    assert list(series) == list(RUN_SERIES)
    for name in RUN_SERIES:
        expected = result.column(name)
        assert series[name].dtype == expected.dtype and series[name].tobytes() == expected.tobytes(), name


def test_importing_wetcloth_does_not_import_dask():
    code = ("import sys, wetcloth; assert 'study' in wetcloth.__all__ and callable(wetcloth.study); "
            "print(sorted(m for m in ('dask', 'distributed', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


# ---------------------------------------------------------------- --dry-run, sensitivity exit status, dashboard line


def test_dry_run_lists_runs_done_failed_and_to_run_and_estimates_their_time(tmp_path, monkeypatch, capsys):
    """Nothing runs and no cluster starts: the listing says which runs the table already holds, and
    the estimate comes from short runs of the scene in this process (here whole 2 s runs)."""
    from wetcloth.batch import cluster, preview
    from wetcloth.cli import main

    study_file = tmp_path / "dry.toml"
    study_file.write_text('scene = "thesis_fast"\nduration = 2.0\n[base]\nnx = 5\nny = 5\n'
                          '[axes]\nabsorption_rate = [0.25, 0.5, 1.0, 2.0]\ninitial_tilt = [0.0, 30.0]\n')
    out = tmp_path / "dry.parquet"
    study = load_study(study_file)
    runs = study.runs()
    done = [dict(run_key=runs[2].key, status="ok", error=None), dict(run_key=runs[3].key, status="error", error="X: y")]
    write_table(make_table(done), out)
    stamp = out.stat().st_mtime_ns

    def no_cluster(*args, **kwargs):
        raise AssertionError("a dry run starts no cluster")

    monkeypatch.setattr(cluster, "dask_client", no_cluster)
    assert main(["batch", str(study_file), "--out", str(out), "--workers", "2", "--dry-run"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == (f"dry: 8 runs (grid); in {out}: 1 done, 1 failed (kept: --retry-errors runs them again); "
                          "6 to run")
    assert printed[1].split() == ["run", "absorption_rate", "initial_tilt", "state"]
    assert [line.split()[-1] for line in printed[2:10]] == ["run", "run", "done", "failed", "run", "run", "run", "run"]
    assert printed[4].split()[:3] == ["3", "0.50", "0.0"]
    estimate = printed[10]
    # 6 to run, timed at the pace of 3 of them or more
    assert re.fullmatch(r"estimated time: about \S+ \S+ per run x 6 runs = \S+ \S+ of computing; about \S+ \S+ on 2 "
                        r"workers of a local cluster, \S+ \S+ of it to start the cluster, warm up its workers and "
                        r"stop it \([3-6] of the runs timed in this process for up to 1 s each, .*\)", estimate), estimate
    assert out.stat().st_mtime_ns == stamp and sorted(p.name for p in tmp_path.iterdir()) == ["dry.parquet", "dry.toml"]
    # with --retry-errors the failed run is to run again
    listing = preview.run_listing(study, read_table(out), retry_errors=True)
    assert listing["state"].tolist() == ["to run"] * 2 + ["done"] + ["to run"] * 5


def test_time_estimate_extrapolates_the_timed_part_of_a_run_to_its_duration():
    """A run timed whole is estimated at the time it took; a run timed for one chunk (0.05 s of
    simulated time: a budget of 0 s stops after the first) at that pace over its whole duration."""
    from wetcloth.batch import preview

    study = make(duration=1.0, base={"nx": 5, "ny": 5}, axes={"absorption_rate": [0.5, 1.0]})
    whole = preview.estimate_time(study, study.runs(), budget=60.0)
    assert whole.runs == 2 and len(whole.timed) == 2
    for p in whole.timed:
        assert p.simulated == pytest.approx(1.0) and p.seconds == pytest.approx(p.elapsed, rel=1e-9)
    assert whole.per_run == pytest.approx(np.mean([p.elapsed for p in whole.timed]), rel=1e-9)
    assert whole.compute == pytest.approx(2 * whole.per_run) and whole.wall(2) == pytest.approx(whole.per_run)
    part = preview.estimate_time(study, study.runs()[:1], budget=0.0).timed[0]
    assert part.simulated == pytest.approx(0.05) and part.seconds == pytest.approx(part.elapsed / 0.05, rel=1e-9)


def test_time_estimate_times_more_runs_while_its_total_budget_lasts():
    """The first ``probes`` runs timed are spread over the study; more are timed, each once, until
    the total budget is spent (a study's runs can differ in cost by 50x: three are too few)."""
    from wetcloth.batch import preview

    order = preview.probe_order(10, 3)
    assert order[:3] == [0, 4, 9] and sorted(order) == list(range(10))
    assert preview.probe_order(2, 3) == [0, 1] and preview.probe_order(0, 3) == []
    study = make(duration=0.2, base={"nx": 5, "ny": 5}, axes={"absorption_rate": [0.25, 0.5, 0.75, 1.0, 1.25]})
    assert len(preview.estimate_time(study, study.runs(), probes=2, total=0.0).timed) == 2
    assert len(preview.estimate_time(study, study.runs(), probes=2, total=60.0).timed) == 5


def test_sensitivity_study_whose_runs_all_fail_exits_1_naming_them(tmp_path, capsys):
    """A table whose runs all failed (values out of range: run_study records them without a worker; the
    command would refuse them): the command reports which runs the design misses, writes an empty indices
    table and a plot that says why, and exits 1."""
    from wetcloth.batch import run_study
    from wetcloth.cli import main

    study_file = tmp_path / "sa.toml"
    study_file.write_text('scene = "thesis_fast"\nduration = 1.0\nmetrics = ["final_depth"]\n'
                          '[axes]\nthickness = { low = -2.0, high = -1.0 }\nabsorption_rate = { low = 0.1, high = 1.0 }\n'
                          '[sensitivity]\nsamples = 2\n')
    out = tmp_path / "sa.parquet"
    assert run_study(load_study(study_file), out).failed == 8
    assert main(["batch", str(study_file), "--out", str(out), "--no-progress"]) == 1
    captured = capsys.readouterr()
    assert "sa: 8 runs, 8 already in " in captured.out
    message = " ".join(captured.out.split("  final_depth (m)\n", 1)[1].split("\nwrote ")[0].split())  # unwrapped
    assert message.startswith("no indices: the sobol design needs a value from each of its 8 runs, and 8 failed (after "
                              "fixing the cause, --retry-errors runs them again): run ")
    assert "ParameterError: parameter 'thickness': " in message and message.endswith("; and 5 more")
    assert captured.err.splitlines() == [
        "wetcloth batch: every run of the study failed; the first: ParameterError: parameter 'thickness': "
        + captured.err.split("'thickness': ", 1)[1].split("\n")[0],
        "wetcloth batch: no sensitivity indices for final_depth (why: above)"]
    assert pd.read_csv(tmp_path / "sa_sensitivity.csv").empty and (tmp_path / "sa_sensitivity.png").exists()


def small_study_file(folder: Path) -> Path:
    path = folder / "small.toml"
    path.write_text('scene = "thesis_fast"\nduration = 2.0\n[axes]\nabsorption_rate = [0.5]\n')
    return path


@pytest.mark.parametrize("address", ["notanaddress", "tcp://host", "tcp://host:99999", "tcp://:8786", "foo://host:8786"])
def test_a_malformed_scheduler_address_is_refused_before_any_connection(address, tmp_path, monkeypatch, capsys):
    """It was taken to Dask's Client: an error, a 120 s hang, then a traceback of Client.__del__.  Now argparse
    refuses it (batch and fit) with one line naming --scheduler and the form, and so does dask_client."""
    import distributed

    from wetcloth.batch.cluster import check_scheduler_address, dask_client
    from wetcloth.cli import main

    def no_connection(*args, **kwargs):
        raise AssertionError("no connection is attempted")

    monkeypatch.setattr(distributed, "Client", no_connection)
    for argv in (["batch", str(small_study_file(tmp_path)), "--out", str(tmp_path / "t.parquet")],
                 ["fit", "towel", "--data", str(tmp_path / "m.csv"), "--params", "absorption_rate", "--global"]):
        with pytest.raises(SystemExit) as info:
            main([*argv, "--scheduler", address])
        assert info.value.code == 2
        last = capsys.readouterr().err.splitlines()[-1]
        assert last.startswith(f"wetcloth {argv[0]}: error: argument --scheduler: {address!r} is not a Dask "
                               "scheduler's address (") and last.endswith("); expected the form tcp://host:8786"), last
    with pytest.raises(ValueError, match="expected the form tcp://host:8786"), dask_client(scheduler=address):
        pass
    assert check_scheduler_address("tcp://head:8786") == "tcp://head:8786" and check_scheduler_address("head:8786")


@pytest.mark.parametrize("dry_run", [False, True])
@pytest.mark.parametrize("option, value, named", [("--out", "afile/t.parquet", "afile/t.parquet"),
                                                  ("--plot-dir", "afile", "afile"),
                                                  ("--plot-dir", "afile/plots", "afile/plots")])
def test_an_output_path_through_a_file_is_refused_up_front(option, value, named, dry_run, tmp_path, monkeypatch,
                                                           capsys):
    """Such an --out was found only once the study had run (a dry run took it); such a --plot-dir after, as
    a raw '[Errno 17] File exists'.  Now both are refused before anything, as fit --out is: one line."""
    from wetcloth import batch
    from wetcloth.cli import main
    from wetcloth.commands import batch as command

    def nothing(*args, **kwargs):
        raise AssertionError("refused before anything runs")

    monkeypatch.setattr(batch, "run_study", nothing)
    monkeypatch.setattr(command, "dry_run", nothing)
    monkeypatch.chdir(tmp_path)
    Path("afile").write_text("x")
    argv = ["batch", str(small_study_file(tmp_path)), option, value, *(["--dry-run"] if dry_run else [])]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"wetcloth batch: error: {option} {named}: cannot write there ("), err
    assert "afile" in err.split("cannot write there")[1], err


def test_dashboard_line_names_the_link_or_says_there_is_none():
    from types import SimpleNamespace

    from wetcloth.batch.cluster import dashboard_line

    scheduler = SimpleNamespace(address="tcp://head:8786")
    assert dashboard_line(SimpleNamespace(dashboard_link="http://head:8787/status", scheduler=scheduler)) == \
        "Dask dashboard: http://head:8787/status"
    assert dashboard_line(SimpleNamespace(dashboard_link=None, scheduler=scheduler)) == \
        "Dask dashboard: none (the scheduler at tcp://head:8786 reports no dashboard address)"


def test_every_study_snippet_of_the_docs_is_a_valid_study():
    """The TOML blocks of docs/batch.md (the study file, lhs sampling, [sensitivity]) parse as studies."""
    import tomllib

    docs = (ROOT / "docs" / "batch.md").read_text()
    blocks = re.findall(r"```toml\n(.*?)```", docs, re.S)
    assert len(blocks) >= 3
    for block in blocks:
        study = Study.from_dict(tomllib.loads(block), name="docs")
        assert study.runs()


def test_a_studys_mesh_files_are_found_from_its_folder_wherever_it_runs(tmp_path, monkeypatch):
    """``cloth_mesh`` in [base] and on an axis is relative to the study file, as its ``scene`` is and as a scene
    file's mesh is: on b60f040 it was looked for from the working folder, and every run of a study started
    elsewhere failed ("'square.obj' cannot be read: No such file or directory")."""
    folder = tmp_path / "study"
    folder.mkdir()
    square = "v -0.1 -0.1 0.2\nv 0.1 -0.1 0.2\nv 0.1 0.1 0.2\nv -0.1 0.1 0.2\n"
    (folder / "square.obj").write_text(square + "f 1 2 3 4\n")
    (folder / "split.obj").write_text(square + "f 1 2 3\nf 1 3 4\n")
    (folder / "mesh.toml").write_text('scene = "thesis_fast"\nduration = 1.0\n[base]\ncloth_mesh = "square.obj"\n'
                                      '[axes]\nabsorption_rate = [0.1, 0.2]\n')
    (folder / "meshes.toml").write_text('scene = "thesis_fast"\nduration = 1.0\n'
                                        '[axes]\ncloth_mesh = ["square.obj", "split.obj"]\n')
    monkeypatch.chdir(tmp_path)
    for name, files in (("mesh", ["square.obj", "square.obj"]), ("meshes", ["square.obj", "split.obj"])):
        runs = load_study(folder / f"{name}.toml").runs()
        assert [r.params["cloth_mesh"] for r in runs] == [str((folder / f).resolve()) for f in files]
        for run in runs:
            assert wetcloth.scene.from_dict(run.params).cloth_mesh == run.params["cloth_mesh"]
