"""Studies that keep their curves: ``series = [...]`` saves every ok run's outputs at the study's
sample_rate as an xarray Dataset in Zarr beside the results table (``NAME.series.zarr``), kept whole
across resumed and interrupted studies; ``[[plot]]`` of kind ``series`` draws them."""

import logging
import math
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import matplotlib.image
import numpy as np
import pandas as pd
import pytest

import wetcloth
from wetcloth.batch import SeriesPlotSpec, Study, StudyError, parse_plot_spec, read_table, run_study
from wetcloth.batch.series import SeriesStore, curves_dataset, series_path, time_grid
from wetcloth.runner import frame_times, run
from wetcloth.scene import PARAMETERS, from_dict

xr = pytest.importorskip("xarray")

SMALL = dict(nx=5, ny=5)


def small_study(name="t", duration=4.0, **data) -> Study:
    """thesis_fast on a 5 x 5 grid for ``duration`` s at 10 Hz, keeping depth and wet mass."""
    data = dict(scene="thesis_fast", duration=duration, sample_rate=10.0, series=["depth", "wet_mass"]) | data
    data["base"] = {k: v for k, v in SMALL.items() if k not in data.get("axes", {})} | data.get("base", {})
    return Study.from_dict(data, name=name)


def fake_curves(study: Study, runs=None, offset=0.0):
    """(run, curves) pairs for ``study``'s runs without simulating: curves made from the run's index."""
    grid = frame_times(study.duration, study.sample_rate)
    out = []
    for i, r in enumerate(study.runs() if runs is None else runs):
        curves = {"time": grid}
        for j, name in enumerate(wetcloth.OUTPUT_NAMES):
            curves[name] = offset + 100.0 * i + j + grid
        out.append((r, curves))
    return out


# ---------------------------------------------------------------- the study file: series and series plots


def test_series_names_are_checked_with_the_other_mistakes():
    study = small_study(series=["wet_mass", "depth"])
    assert study.series == ("wet_mass", "depth")
    assert small_study(series=[]).series == () and Study.from_dict({"duration": 1.0}, name="x").series == ()
    allowed = "(outputs: centroid_x, centroid_y, centroid_z, depth, wet_mass, water_mass)"
    with pytest.raises(StudyError) as info:
        Study.from_dict({"duration": 1.0, "series": ["dpeth", "time", "speed"], "metrics": ["time_to_snk"]},
                        name="x", source="study file x.toml")
    assert str(info.value).splitlines() == [
        "study file x.toml: 4 mistakes",
        "  study 'metrics': 'time_to_snk': unknown metric; did you mean 'time_to_sink'?",
        f"  study 'series': 'dpeth': unknown output; did you mean 'depth'? {allowed}",
        f"  study 'series': 'time': saved with every curve (their dimension): leave it out {allowed}",
        f"  study 'series': 'speed': unknown output {allowed}",
    ]
    with pytest.raises(StudyError, match=r"'series': give a list of the outputs to save, any of: centroid_x, .*"
                                         r"water_mass; got 'depth'"):
        small_study(series="depth")
    with pytest.raises(StudyError, match="repeated output"):
        small_study(series=["depth", "depth"])
    with pytest.raises(StudyError, match=r"'seires': unknown key; did you mean 'series'\?"):
        Study.from_dict({"duration": 1.0, "seires": ["depth"]}, name="x")


def test_series_is_not_part_of_the_run_key():
    # the curves do not change a run's result: keeping them (or not) runs nothing new
    with_curves = small_study(axes={"absorption_rate": [0.5, 1.0]})
    without = small_study(series=[], axes={"absorption_rate": [0.5, 1.0]})
    assert [r.key for r in with_curves.runs()] == [r.key for r in without.runs()]


def test_series_plots_are_checked_against_the_study():
    axes = {"absorption_rate": [0.5, 1.0], "drag_model": ["face", "stokes"]}
    study = small_study(axes=axes, plot=[{"kind": "series", "color": "drag_model"},
                                         {"kind": "series", "series": "depth"},
                                         {"metric": "time_to_sink", "x": "absorption_rate"}])
    assert study.plots[:2] == (SeriesPlotSpec((), "drag_model"), SeriesPlotSpec(("depth",), None))
    assert study.plots[0].filename("t", study.series) == "t_series_depth_wet_mass_by_drag_model.png"
    assert study.plots[1].filename("t", study.series, "absorption_rate") == "t_series_depth_by_absorption_rate.png"
    for plot, message in [
        ({"kind": "series", "series": ["water_mass"]}, r"series 'water_mass' is not kept; kept: depth, wet_mass"),
        ({"kind": "series", "color": "initial_tilt"},
         r"color 'initial_tilt' is not an axis of this study; axes: absorption_rate, drag_model"),
        ({"kind": "series", "metric": "time_to_sink"}, r"of kind 'series' has series .* and color .*; got"),
        ({"kind": "curves"}, r"kind 'curves' is not a kind of plot; kinds: line, heatmap, series"),
        ({"kind": "heatmap", "metric": "time_to_sink", "x": "absorption_rate"}, r"a heatmap has metric, x and y"),
        ({"kind": "series", "series": 3}, r"series must be an output name or a list of them"),
    ]:
        with pytest.raises(StudyError, match=message):
            small_study(axes=axes, plot=[plot])
    with pytest.raises(StudyError, match=r"a plot of kind 'series' draws the curves the study keeps: give the outputs "
                                         r"to keep as series = \[\.\.\.\]"):
        small_study(series=[], axes=axes, plot=[{"kind": "series"}])
    assert parse_plot_spec("series:absorption_rate") == SeriesPlotSpec(color="absorption_rate")


# ---------------------------------------------------------------- the store, without Dask


def test_curves_dataset_layout_units_and_types():
    study = small_study(axes={"absorption_rate": [0.5, 1.0], "drag_model": ["face", "stokes"], "nx": [5, 7]})
    ds = curves_dataset(fake_curves(study), study)
    assert dict(ds.sizes) == {"run": 8, "time": 41}
    assert list(ds.data_vars) == ["depth", "wet_mass"]
    assert ds["depth"].dims == ("run", "time") and ds["depth"].attrs["units"] == "m"
    assert ds["wet_mass"].attrs["units"] == "kg" and ds["time"].attrs["units"] == "s"
    np.testing.assert_array_equal(ds["time"].values, np.arange(41) / 10.0)
    assert ds["absorption_rate"].attrs["units"] == "1/s" and ds["absorption_rate"].dtype == np.float64
    assert ds["nx"].dtype == np.int64 and "units" not in ds["drag_model"].attrs
    assert list(ds["run"].values) == [r.key for r in study.runs()]


def test_store_appends_skips_what_it_has_and_rewrites_a_new_layout(tmp_path):
    study = small_study(axes={"absorption_rate": [0.5, 1.0, 1.5, 2.0]})
    pairs = fake_curves(study)
    store = SeriesStore(tmp_path / "s.series.zarr")
    assert store.open() is None and store.complete_keys(["depth"]) == set()
    assert store.write(curves_dataset(pairs[:2], study)) == 2
    assert store.write(curves_dataset(pairs[1:3], study), store.complete_keys(study.series)) == 1  # run 2 is there
    ds = xr.open_zarr(store.path)
    assert list(ds["run"].values) == [r.key for r, _ in pairs[:3]]
    np.testing.assert_array_equal(ds["depth"].values, np.vstack([c["depth"] for _, c in pairs[:3]]))
    # a longer study (another time grid) and another output: the store is rewritten with both, NaN where none
    longer = small_study(duration=6.0, series=["depth", "water_mass"], axes={"absorption_rate": [3.0]})
    assert store.write(curves_dataset(fake_curves(longer), longer)) == 1
    ds = xr.open_zarr(store.path)
    assert dict(ds.sizes) == {"run": 4, "time": 61} and set(ds.data_vars) == {"depth", "wet_mass", "water_mass"}
    old = ds.isel(run=slice(0, 3))
    np.testing.assert_array_equal(old["depth"].values[:, :41], np.vstack([c["depth"] for _, c in pairs[:3]]))
    assert np.isnan(old["depth"].values[:, 41:]).all() and np.isnan(old["water_mass"].values).all()
    assert np.isnan(ds["wet_mass"].values[3]).all() and np.isfinite(ds["water_mass"].values[3]).all()
    assert store.complete_keys(["depth", "wet_mass"]) == {r.key for r, _ in pairs[:3]}
    # a run held without one of the outputs asked for gets its curves replaced, not duplicated
    assert store.write(curves_dataset(fake_curves(study, offset=0.5)[:1], study.replace(series=("depth", "water_mass"))),
                       store.complete_keys(["depth", "water_mass"])) == 1
    ds = xr.open_zarr(store.path)
    keys = list(ds["run"].values)
    assert len(keys) == len(set(keys)) == 4
    first = ds.sel(run=pairs[0][0].key)
    np.testing.assert_array_equal(first["water_mass"].values[:41], pairs[0][1]["water_mass"] + 0.5)
    assert not list(tmp_path.glob(".*"))  # no temporary folder or backup left behind


def test_studies_sharing_a_table_share_its_store(tmp_path):
    # two studies with other axes (one of whole numbers) take turns at one store: every run once, each
    # with its own axis values and NaN (or nothing) on the other study's axis
    by_nx = small_study(name="a", axes={"nx": [5, 7, 9]})
    by_rate = small_study(name="b", axes={"absorption_rate": [0.5, 1.0, 2.0]})
    store = SeriesStore(tmp_path / "shared.series.zarr")
    a, b = fake_curves(by_nx), fake_curves(by_rate, offset=1000.0)
    for study, pairs in ((by_nx, a[:1]), (by_rate, b[:2]), (by_nx, a[1:]), (by_rate, b[2:])):
        store.write(curves_dataset(pairs, study), store.complete_keys(study.series))
    ds = xr.open_zarr(store.path).load()
    assert sorted(ds["run"].values) == sorted(r.key for r, _ in a + b)
    for r, curves in a + b:
        one = ds.sel(run=r.key)
        np.testing.assert_array_equal(one["wet_mass"].values, curves["wet_mass"])
        for axis, value in r.point.items():
            assert float(one[axis]) == value
    assert np.isnan(ds.sel(run=a[0][0].key)["absorption_rate"]) and np.isnan(ds.sel(run=b[0][0].key)["nx"])


def _failing_after(monkeypatch, count: int):
    """Make the count+1-th file zarr writes fail (as if the writer were killed there)."""
    import zarr.storage

    original = zarr.storage.LocalStore.set
    calls = {"n": 0}

    async def set_(self, key, value):
        calls["n"] += 1
        if calls["n"] > count:
            raise OSError(28, "No space left on device (simulated)")
        return await original(self, key, value)

    monkeypatch.setattr(zarr.storage.LocalStore, "set", set_)
    return calls


def test_a_writer_stopped_at_any_file_leaves_the_store_readable_and_resumable(tmp_path, monkeypatch):
    study = small_study(axes={"absorption_rate": [0.5, 1.0, 1.5, 2.0, 2.5]})
    pairs = fake_curves(study)
    base = tmp_path / "base.series.zarr"
    SeriesStore(base).write(curves_dataset(pairs[:3], study))
    calls = _failing_after(monkeypatch, 10**9)
    SeriesStore(tmp_path / "count.series.zarr").write(curves_dataset(pairs[:3], study))
    shutil.copytree(base, tmp_path / "probe.series.zarr")
    calls["n"] = 0
    SeriesStore(tmp_path / "probe.series.zarr").write(curves_dataset(pairs[3:], study))
    files = calls["n"]  # files an append writes
    assert files > 5
    monkeypatch.undo()
    expected = np.vstack([c["wet_mass"] for _, c in pairs])
    for stop in range(files):
        path = tmp_path / f"cut{stop}.series.zarr"
        shutil.copytree(base, path)
        _failing_after(monkeypatch, stop)
        with pytest.raises(OSError, match="simulated"):
            SeriesStore(path).write(curves_dataset(pairs[3:], study))
        monkeypatch.undo()
        ds = xr.open_zarr(path)  # readable, with the runs it had
        assert list(ds["run"].values) == [r.key for r, _ in pairs[:3]], stop
        np.testing.assert_array_equal(ds["wet_mass"].values, expected[:3])
        store = SeriesStore(path)  # the next writer continues from there
        assert store.write(curves_dataset(pairs[2:], study), store.complete_keys(study.series)) == 2
        ds = xr.open_zarr(path)
        assert list(ds["run"].values) == [r.key for r, _ in pairs], stop
        np.testing.assert_array_equal(ds["wet_mass"].values, expected)


@pytest.mark.filterwarnings("ignore:Object at .*partial is not recognized:UserWarning")
def test_a_writer_killed_by_sigkill_leaves_the_store_readable(tmp_path):
    """A process that appends batches of curves, killed (SIGKILL) mid-way: the store opens, holds whole
    batches only, and the next writer completes it.  (A kill in the middle of a write leaves its ``.partial``
    file, which zarr warns it does not recognise when the store opens: expected here.)"""
    path = tmp_path / "k.series.zarr"
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_batch_series import small_study, fake_curves
        from wetcloth.batch.series import SeriesStore, curves_dataset
        study = small_study(duration=60.0, axes={{"absorption_rate": {{"start": 0.01, "stop": 4.0, "num": 400}}}})
        pairs = fake_curves(study)
        store = SeriesStore({str(path)!r})
        for i in range(0, len(pairs), 4):
            store.write(curves_dataset(pairs[i:i + 4], study))
            print(i + 4, flush=True)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        written = 0
        while written < 12:  # a few batches in: then kill it in the middle of the next ones
            line = proc.stdout.readline()
            assert line, "the writer stopped early"
            written = int(line)
        time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    study = small_study(duration=60.0, axes={"absorption_rate": {"start": 0.01, "stop": 4.0, "num": 400}})
    pairs = fake_curves(study)
    ds = xr.open_zarr(path)
    held = list(ds["run"].values)
    assert written <= len(held) < len(pairs) and len(held) % 4 == 0
    assert held == [r.key for r, _ in pairs[:len(held)]]
    np.testing.assert_array_equal(ds["depth"].values, np.vstack([c["depth"] for _, c in pairs[:len(held)]]))
    store = SeriesStore(path)
    store.write(curves_dataset(pairs, study), store.complete_keys(study.series))
    ds = xr.open_zarr(path)
    assert list(ds["run"].values) == [r.key for r, _ in pairs]


# ---------------------------------------------------------------- studies on a local Dask cluster


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0",
                                  silence_logs=logging.CRITICAL) as cluster, distributed.Client(cluster) as c:
        yield c


def direct_series(study: Study, params: dict) -> dict:
    result = run(from_dict(params), study.duration, study.sample_rate, shapes=0, progress=False)
    return {name: result.column(name) for name in ("time", *study.series)}


def test_study_keeps_its_curves_in_a_dataset_that_xarray_opens(client, tmp_path):
    # one value out of range: that run is an error row, and has no curves
    study = small_study(axes={"absorption_rate": [-1.0, 0.5, 2.0], "drag_model": ["face", "stokes"]})
    out = tmp_path / "curves.parquet"
    report = run_study(study, out, client=client)
    assert (report.ok, report.failed) == (4, 2)
    path = tmp_path / "curves.series.zarr"
    assert series_path(out) == path == report.series_path
    ds = xr.open_zarr(path)
    table = read_table(out).set_index("run_key")
    ok = [r for r in study.runs() if table.loc[r.key, "status"] == "ok"]
    assert ds["depth"].dims == ("run", "time") and dict(ds.sizes) == {"run": 4, "time": 41}
    assert sorted(ds["run"].values) == sorted(r.key for r in ok)
    np.testing.assert_array_equal(ds["time"].values, time_grid(study.duration, study.sample_rate))
    assert (ds["time"].attrs["units"], ds["depth"].attrs["units"], ds["wet_mass"].attrs["units"]) == ("s", "m", "kg")
    assert ds["absorption_rate"].attrs["units"] == PARAMETERS["absorption_rate"].metadata["unit"] == "1/s"
    for key in ds["run"].values:  # the axes along run are the table's values
        run_ = ds.sel(run=key)
        assert float(run_["absorption_rate"]) == table.loc[key, "absorption_rate"]
        assert str(run_["drag_model"].values) == table.loc[key, "drag_model"]
    for r in ok:  # the curves are the runs' own: the same code in another process, identical numbers
        direct = direct_series(study, r.params)
        np.testing.assert_array_equal(ds.sel(run=r.key)["depth"].values, direct["depth"])
        np.testing.assert_array_equal(ds.sel(run=r.key)["wet_mass"].values, direct["wet_mass"])
        # the table's final values are the curves' last samples
        assert table.loc[r.key, "final_wet_mass"] == ds.sel(run=r.key)["wet_mass"].values[-1]
    # the report's Dataset: the study's ok runs, in run order
    assert list(report.series["run"].values) == [r.key for r in ok]


def test_resume_keeps_the_series_whole(client, tmp_path):
    out = tmp_path / "r.parquet"
    path = series_path(out)
    study = small_study(axes={"absorption_rate": [0.5, 1.0, 1.5, 2.0, 2.5, 3.0]})
    seen = []

    def interrupt_after_two(row):
        seen.append(row["run_key"])
        if len(seen) == 2:
            raise KeyboardInterrupt  # as Ctrl-C would, in the client, between two results

    with pytest.raises(KeyboardInterrupt):
        run_study(study, out, client=client, on_result=interrupt_after_two)
    assert list(xr.open_zarr(path)["run"].values) == seen == list(read_table(out)["run_key"])
    first = xr.open_zarr(path).load()
    report = run_study(study, out, client=client)
    assert (report.ran, report.skipped, report.for_curves) == (4, 2, 0)
    ds = xr.open_zarr(path).load()
    keys = [r.key for r in study.runs()]
    assert sorted(ds["run"].values) == sorted(keys) and len(set(ds["run"].values)) == 6  # each once
    xr.testing.assert_identical(ds.sel(run=seen), first)  # the curves done before are as they were
    # done: a third invocation runs nothing and leaves the store alone
    stamp = (path / ".zmetadata").stat().st_mtime_ns
    again = run_study(study, out, client=client)
    assert again.ran == 0 and (path / ".zmetadata").stat().st_mtime_ns == stamp
    xr.testing.assert_identical(again.series.load(), ds.sel(run=keys))
    # a wider axis adds the new runs' curves only
    wider = small_study(axes={"absorption_rate": [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5]})
    assert run_study(wider, out, client=client).ran == 1
    ds7 = xr.open_zarr(path).load()
    assert len(ds7["run"]) == 7 and len(set(ds7["run"].values)) == 7
    xr.testing.assert_identical(ds7.sel(run=keys), ds.sel(run=keys))
    # the table has runs whose curves the store lacks (a study killed between the two, or curves asked
    # for after it ran): those run again, their rows replaced, nothing doubled
    shutil.rmtree(path)
    curves = run_study(wider, out, client=client)
    assert (curves.ran, curves.for_curves, curves.skipped) == (7, 7, 0)
    assert "(7 of them again, for curves missing from" in curves.summary()
    table = read_table(out)
    assert sorted(table["run_key"]) == sorted(r.key for r in wider.runs())  # each once
    xr.testing.assert_identical(xr.open_zarr(path).load().sel(run=keys), ds.sel(run=keys))


def test_a_study_that_adds_series_later_runs_again_only_for_the_curves(client, tmp_path):
    out = tmp_path / "later.parquet"
    axes = {"absorption_rate": [-1.0, 0.5, 1.0]}
    plain = run_study(small_study(series=[], axes=axes), out, client=client)
    assert plain.series is None and not series_path(out).exists()
    report = run_study(small_study(axes=axes), out, client=client)  # the error row is kept, not rerun
    assert (report.ran, report.for_curves, report.skipped) == (2, 2, 1)
    assert len(read_table(out)) == 3 and len(xr.open_zarr(series_path(out))["run"]) == 2
    # without a table nothing is saved, and the report still has this call's curves
    mem = run_study(small_study(axes=axes), client=client)
    assert mem.series_path is None and len(mem.series["run"]) == 2


def test_cli_writes_the_store_and_draws_the_series_plot(client, tmp_path, capsys):
    from wetcloth.cli import main

    study_file = tmp_path / "curves.toml"
    study_file.write_text(
        'scene = "thesis_fast"\nduration = 3.0\nseries = ["depth", "wet_mass"]\n[base]\nnx = 5\nny = 5\n'
        '[axes]\nabsorption_rate = [0.5, 1.0, 2.0]\ndrag_model = ["face", "stokes"]\n'
        '[[plot]]\nkind = "series"\ncolor = "absorption_rate"\n'
    )
    out = tmp_path / "res" / "c.parquet"
    argv = ["batch", str(study_file), "--scheduler", client.scheduler.address, "--out", str(out),
            "--plot", "series:drag_model", "--no-progress"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    store = tmp_path / "res" / "c.series.zarr"
    assert f"wrote {out}, {store}, " in printed
    assert len(xr.open_zarr(store)["run"]) == 6
    for name in ("c_series_depth_wet_mass_by_absorption_rate.png", "c_series_depth_wet_mass_by_drag_model.png"):
        image = matplotlib.image.imread(out.parent / name)
        assert image.shape[0] > 300 and image.shape[1] > 300
        assert image[..., :3].std() > 0.05  # drawn: not a blank page
    # a dry run says which runs would run again for their curves
    shutil.rmtree(store)
    assert main(["batch", str(study_file), "--out", str(out), "--dry-run", "--workers", "2"]) == 0
    assert f"in {out}: 0 done, 0 failed; 6 to run (6 of them again, for curves missing from {store})" in \
        capsys.readouterr().out
    # a series plot in a study without series is refused, as other plot mistakes are
    study_file.write_text(study_file.read_text().replace('series = ["depth", "wet_mass"]\n', ""))
    assert main(["batch", str(study_file), "--out", str(out), "--no-progress"]) == 2
    assert "a plot of kind 'series' draws the curves the study keeps" in capsys.readouterr().err


def test_series_plot_of_numbers_and_text(tmp_path):
    from wetcloth.batch import plot_series

    study = small_study(axes={"absorption_rate": {"start": 0.1, "stop": 10.0, "num": 3, "log": True},
                              "drag_model": ["face", "stokes"]})
    ds = curves_dataset(fake_curves(study), study)
    for spec in (SeriesPlotSpec(("depth",), "absorption_rate"), SeriesPlotSpec((), "drag_model"), SeriesPlotSpec()):
        path = plot_series(ds, spec, tmp_path / f"{spec.color}.png", study=study)
        assert matplotlib.image.imread(path).shape[0] > 200
    with pytest.raises(ValueError, match="cannot plot the curves of water_mass"):
        plot_series(ds, SeriesPlotSpec(("water_mass",)), tmp_path / "x.png")
    with pytest.raises(ValueError, match="none were kept"):
        wetcloth.batch.plot(pd.DataFrame(), SeriesPlotSpec(), tmp_path / "y.png")
