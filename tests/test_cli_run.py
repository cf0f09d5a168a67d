"""``wetcloth run``: outputs as CSV and a plot, overrides, clear errors, and runs stopped early
(blow-up, Ctrl-C, a full disk) keeping what they computed; ``params`` and ``--version``."""

import csv
import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import full_disk
import pytest

import wetcloth
from wetcloth.cli import main
from wetcloth.commands.params import _row_lines
from wetcloth.runner import run
from wetcloth.simulation import OUTPUT_NAMES


def test_run_writes_csv_and_plot(tmp_path):
    csv_path, plot_path = tmp_path / "o.csv", tmp_path / "p.png"
    code = main(["run", "thesis_float", "--duration", "1", "--fps", "10", "--set", "nx=5", "--set", "ny=5",
                 "--csv", str(csv_path), "--plot", str(plot_path), "--no-progress"])
    assert code == 0
    rows = list(csv.DictReader(open(csv_path)))
    assert list(rows[0]) == ["time", *OUTPUT_NAMES, "step_error"]
    assert [float(r["time"]) for r in rows] == [k / 10 for k in range(11)]
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("export", [False, True])
def test_run_reports_each_frames_step_error(tmp_path, capsys, export):
    """Frame steps (``implicit_euler``, ``tolerance = 0``, one step a frame): the CSV's ``step_error`` of
    each frame is the error estimate of the step that reached it (``error_estimate`` after an ``advance``
    of one frame, run here), with frames exported or not; the command prints the largest and its time, and
    where the cloth ends (above the water here)."""
    settings = dict(nx=7, ny=7, integrator="implicit_euler", tolerance=0.0, max_step=0.125, pinned_edge="y_max",
                    initial_tilt=0.0, water_level=-50.0, floor_level=-100.0)
    csv_path = tmp_path / "o.csv"
    extra = ["--export", str(tmp_path / "frames")] if export else []
    code = main(["run", "--duration", "1", "--fps", "8", *[a for k, v in settings.items() for a in ("--set", f"{k}={v}")],
                 "--csv", str(csv_path), "--plot", str(tmp_path / "p.png"), "--no-progress", *extra])
    assert code == 0
    written = [float(r["step_error"]) for r in csv.DictReader(open(csv_path))]
    sim = wetcloth.Simulation(wetcloth.load_scene(**settings))
    expected = [0.0]  # t = 0: no step
    for _ in range(8):
        sim.advance(0.125)
        expected.append(sim.error_estimate)
    assert written == pytest.approx(expected, rel=1e-15) and min(expected[1:]) > 0.0
    worst = max(range(9), key=expected.__getitem__)
    out = capsys.readouterr().out
    assert f"at most {expected[worst] * 1000:.3g} mm in a frame (t = {worst / 8:g} s; column step_error)" in out
    assert f"centroid {-sim.outputs()['depth']:.2f} m above the water" in out  # in air, 50 m over it


def test_bad_override_names_parameter_and_range(tmp_path, capsys):
    code = main(["run", "--set", "thickness=-1", "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png")])
    assert code == 2
    err = capsys.readouterr().err
    assert "thickness" in err and "0 < thickness <= 1 m" in err
    assert not (tmp_path / "o.csv").exists()


def test_console_script_is_installed(tmp_path):
    exe = Path(sys.executable).with_name("wetcloth")
    result = subprocess.run([str(exe), "run", "--set", "colour=blue"], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2
    assert "unknown parameter" in result.stderr and "colour" in result.stderr


def test_blow_up_keeps_the_good_outputs_and_frames(tmp_path, capsys):
    """Fixed steps far beyond explicit Euler's limit blow up within 0.1 s: the command fails with the
    guard's message, yet the outputs of every frame before the blow-up are written (finite), and
    frames.json counts the frames on disk and marks the sequence incomplete."""
    csv_path, frames = tmp_path / "o.csv", tmp_path / "frames"
    code = main(["run", "--duration", "1", "--set", "integrator=explicit_euler", "--set", "tolerance=0",
                 "--set", "max_step=0.01", "--set", "nx=9", "--set", "ny=9", "--csv", str(csv_path),
                 "--plot", str(tmp_path / "p.png"), "--export", str(frames), "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert "Last good time" in err and "outputs up to t =" in err
    rows = list(csv.DictReader(open(csv_path)))
    assert 0 < len(rows) < 30
    assert all(math.isfinite(float(value)) for row in rows for value in row.values())
    manifest = json.loads((frames / "frames.json").read_text())
    assert manifest["complete"] is False
    assert manifest["frame_count"] == len(rows) == len(list(frames.glob("cloth_*.ply")))


def test_unwritable_outputs_are_refused_before_simulating(tmp_path, capsys, monkeypatch):
    """A --csv path that is a directory is refused at once, naming the option; nothing is simulated."""
    import wetcloth.commands.run as run_command

    def no_simulating(*args, **kwargs):
        raise AssertionError("simulated before checking the outputs")

    monkeypatch.setattr(run_command, "run", no_simulating)
    folder = tmp_path / "o.csv"
    folder.mkdir()
    code = main(["run", "--csv", str(folder), "--plot", str(tmp_path / "p.png")])
    assert code == 2
    err = capsys.readouterr().err
    assert "--csv" in err and str(folder) in err and "cannot write there" in err, err
    assert not (tmp_path / "p.png").exists()


@pytest.mark.parametrize("command", [["run"], ["batch", "models/studies/sink_map.toml"]])
def test_a_csv_output_not_named_csv_is_refused(tmp_path, capsys, command):
    """``--csv x.parquet`` wrote CSV text under a Parquet name (bb80f15): refused by the option's own check."""
    with pytest.raises(SystemExit) as stop:
        main([*command, "--csv", str(tmp_path / "x.parquet")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "argument --csv" in err and "x.parquet: a CSV file's name ends in .csv" in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_plot_of_an_unknown_image_format_is_refused_before_simulating(tmp_path, capsys, monkeypatch):
    """b60f040 simulated first, then stopped at the plot with matplotlib's "Format 'txt' is not supported"
    (no option named) and without the run's summary."""
    import wetcloth.commands.run as run_command

    def no_simulating(*args, **kwargs):
        raise AssertionError("simulated before checking the outputs")

    monkeypatch.setattr(run_command, "run", no_simulating)
    code = main(["run", "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.txt")])
    err = capsys.readouterr().err
    assert code == 2 and "--plot" in err and "'.txt' is not an image format; allowed: " in err and ".png" in err, err
    assert list(tmp_path.iterdir()) == []


def test_frames_beyond_blenders_last_frame_are_refused_before_simulating(tmp_path, capsys, monkeypatch):
    """31 frames from --first-frame 1048570 would end at 1048600, past Blender's last frame 1048574 (MAXFRAME),
    where no scene frame can show them: b60f040 simulated and wrote them."""
    import wetcloth.commands.run as run_command

    def no_simulating(*args, **kwargs):
        raise AssertionError("simulated before checking the outputs")

    monkeypatch.setattr(run_command, "run", no_simulating)
    code = main(["run", "--duration", "1", "--fps", "30", "--first-frame", "1048570", "--export", str(tmp_path / "f"),
                 "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png")])
    err = capsys.readouterr().err
    assert code == 2 and ("error: --first-frame 1048570 with 31 frames ends at frame 1048600, beyond Blender's last "
                          "frame 1048574; allowed: a --first-frame up to 1048544") in err, err
    assert list(tmp_path.iterdir()) == []


def _frames_on_disk(frames: Path) -> int:
    return len(list(frames.glob("cloth_*.ply")))


def test_ctrl_c_keeps_the_outputs_and_prints_one_line(tmp_path):
    """A terminal's Ctrl-C (SIGINT to the process group) mid-run: exit 130, one line naming what was
    kept, no traceback; the CSV and plot of the frames computed are written, frames.json counts the
    frames on disk.  The run is long (600 s, 18 000 frames; the 9 x 9 towel falls asleep and then
    costs little more than its frame files), so that it cannot end before the signal comes."""
    frames, csv_path, plot_path = tmp_path / "frames", tmp_path / "o.csv", tmp_path / "p.png"
    proc = subprocess.Popen([sys.executable, "-m", "wetcloth.cli", "run", "--duration", "600", "--set", "nx=9",
                             "--set", "ny=9", "--export", str(frames), "--csv", str(csv_path), "--plot", str(plot_path),
                             "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 60
        while _frames_on_disk(frames) < 5 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wetcloth run: interrupted; outputs up to t = "), err
    assert str(csv_path) in lines[0] and str(plot_path) in lines[0] and f"frames in {frames}" in lines[0]
    manifest = json.loads((frames / "frames.json").read_text())
    assert manifest["complete"] is False and manifest["frame_count"] == _frames_on_disk(frames) >= 5
    rows = list(csv.DictReader(open(csv_path)))
    assert len(rows) >= manifest["frame_count"] and float(rows[-1]["time"]) < 600
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_ctrl_c_while_the_outputs_are_written_keeps_them_whole(tmp_path, monkeypatch, capsys):
    """Ctrl-C arrives after the run, while its plot is written: the plot is still written whole, then the
    command stops with exit 130 and one line naming what was kept (the plot was lost before)."""
    from wetcloth import plotting

    drawing = plotting.plot_run

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.5)  # the signal's handler runs here
        return drawing(*args, **kwargs)

    monkeypatch.setattr(plotting, "plot_run", interrupted)
    csv_path, plot_path = tmp_path / "o.csv", tmp_path / "p.png"
    code = main(["run", "thesis_fast", "--duration", "0.2", "--set", "nx=5", "--set", "ny=5", "--csv", str(csv_path),
                 "--plot", str(plot_path), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 130, err
    assert err.strip() == f"wetcloth run: interrupted; outputs up to t = 0.2 s are in {csv_path} and {plot_path}"
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_ctrl_c_during_a_frame_callback_stops_the_run_after_it():
    """Ctrl-C arrives while a frame callback runs library code that catches BaseException (as trimesh's
    vertex normals do): the callback finishes, and the run stops after it with the frames so far."""
    def swallowing(index, sim):
        if index == 3:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)  # the signal's handler runs here
            except BaseException:
                pass

    with pytest.raises(KeyboardInterrupt) as info:
        run(wetcloth.load_scene("thesis_fast", nx=5, ny=5), duration=1.0, fps=30.0, on_frame=swallowing, progress=False,
            warn=None)
    assert len(info.value.partial_result.rows) == 4


@pytest.mark.parametrize("disk", full_disk.DISKS)
def test_a_full_disk_keeps_files_whole_and_the_manifest_true(tmp_path, disk):
    """The export folder is a disk of 64 kB: it fills up after a few frames.  The real error is shown,
    every file is whole or absent, no temporary files are left, frames.json counts the frames on disk,
    and the CSV and plot of the frames computed are written (they go to another disk)."""
    csv_path, plot_path = tmp_path / "o.csv", tmp_path / "p.png"
    found = full_disk.run(disk, tmp_path, 64 * 1024, f"""
        import contextlib, io, json, trimesh
        from wetcloth.cli import main

        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            code = main(["run", "thesis_fast", "--duration", "3", "--fps", "10", "--set", "nx=5", "--set", "ny=5",
                         "--export", str(DISK / "frames"), "--csv", {str(csv_path)!r}, "--plot", {str(plot_path)!r},
                         "--no-progress"])
        frames = DISK / "frames"
        vertices = [len(trimesh.load(p, process=False).vertices) for p in sorted(frames.glob("cloth_*.ply"))]
        print(json.dumps(dict(code=code, err=err.getvalue(), names=sorted(p.name for p in frames.iterdir()),
                              vertices=vertices, manifest=json.loads((frames / "frames.json").read_text()))))
    """)
    err = found["err"]
    assert found["code"] == 2 and "Traceback" not in err, err
    assert err.startswith("wetcloth run: error: cannot write ") and "No space left on device" in err.splitlines()[0], err
    assert not [n for n in found["names"] if n.endswith((".part", ".tmp"))], found["names"]
    assert 0 < len(found["vertices"]) < 31 and set(found["vertices"]) == {25}  # whole frames only
    assert found["manifest"]["frame_count"] == len(found["vertices"]) and found["manifest"]["complete"] is False
    rows = list(csv.DictReader(open(csv_path)))
    assert len(rows) >= len(found["vertices"]) and f"outputs up to t = {float(rows[-1]['time']):g} s" in err
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_work_beyond_sane_bounds_is_refused_naming_the_bound(tmp_path, capsys):
    for options, bound in ((["--fps", "1e9"], "0 < fps <= 10000 1/s"),
                           (["--duration", "1e5", "--fps", "1000"], "at most 200000 per run")):
        assert main(["run", *options, "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and bound in err, err


def test_a_run_that_would_take_hours_is_warned_about_with_cheaper_settings(tmp_path):
    """The lightest fabric allowed (5 g/m2) at the largest stretch_stiffness holds explicit Euler to steps of
    3e-8 s: the warning comes a few seconds in (from a timed sample of the run itself), names the cheaper
    settings, and Ctrl-C then stops it."""
    proc = subprocess.Popen([sys.executable, "-m", "wetcloth.cli", "run", "--duration", "1000", "--set",
                             "areal_density=0.005", "--set", "stretch_stiffness=1e8", "--set",
                             "integrator=explicit_euler", "--set", "nx=5", "--set", "ny=5",
                             "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png"), "--no-progress"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    lines = []
    reader = threading.Thread(target=lambda: lines.append(proc.stderr.readline()), daemon=True)
    reader.start()
    try:
        reader.join(timeout=60)  # until the warning comes (or the run ends, or a minute passes)
        os.killpg(proc.pid, signal.SIGINT)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    warning = lines[0] if lines else ""
    assert warning.startswith("wetcloth run: warning: this run will take about "), warning
    assert re.search(r"steps of 2\.\de-08 s", warning), warning
    assert "integrator 'implicit_euler'" in warning, warning
    assert "areal_density = 0.005 kg/m2, stretch_stiffness = 1e+08 N/m" in warning, warning
    assert "a shorter duration (now 1000 s)" in warning and proc.returncode == 130


def test_cost_advice_names_the_expensive_settings_and_never_what_is_set():
    from wetcloth.advice import cheaper_settings, estimate_cost
    from wetcloth.progress import Sample

    big = wetcloth.Scene(nx=1000, ny=1000)
    cost = estimate_cost(big, 10.0, Sample(elapsed=8.0, steps=0, simulated=0.0, time=0.0), stable_step=1e-7)
    assert not cost.exact and cost.steps == pytest.approx(1e8) and cost.seconds == pytest.approx(8e8)
    advice = "; ".join(cheaper_settings(big, cost, 10.0, 1e-7))
    assert "fewer particles (nx x ny = 1000 x 1000 = 1e+06" in advice and "integrator 'implicit_euler'" in advice
    implicit = wetcloth.Scene(nx=1000, ny=1000, integrator="implicit_euler")
    assert "implicit_euler" not in "; ".join(cheaper_settings(implicit, cost, 10.0, math.inf))


@pytest.mark.parametrize("max_step, tolerance, duration, took", [(1e-6, 5e-6, 1e5, "about 116 days"),
                                                                 (1e-6, 5e-6, 1e9, None),
                                                                 (1e-5, 0.0, 1e4, "about 1.2 days")])
def test_a_tiny_max_step_is_named_as_what_makes_the_run_long(max_step, tolerance, duration, took):
    """Steps held at a tiny max_step: the warning said only 'cheaper: a shorter duration'; a run of ~1e300
    steps printed ~300 digits of years.  Now max_step is named with its value, and beyond 1000 years it says so."""
    from wetcloth.advice import cost_warning
    from wetcloth.progress import Sample

    scene = wetcloth.Scene(max_step=max_step, tolerance=tolerance)
    sample = Sample(elapsed=2.0, steps=20000, simulated=20000 * max_step, time=20000 * max_step)
    warning = cost_warning(scene, duration, sample, stable_step=math.inf)
    took = took or "more than 1000 years"
    bound = "is every step (tolerance = 0: fixed steps)" if tolerance == 0.0 else "bounds every step"
    assert warning.startswith(f"this run will take {took} ("), warning
    assert (f"cheaper: a larger max_step (max_step = {max_step:g} s {bound}, and so makes the run this long); "
            f"a shorter duration (now {duration:g} s)") in warning, warning


def test_blow_up_advice_never_suggests_what_is_already_set():
    from wetcloth import _core
    from wetcloth.integrators import INTEGRATORS

    def blow_up_advice(scene, stable_step):
        return _core.blow_up_advice(INTEGRATORS[scene.integrator], scene.tolerance, scene.max_step, stable_step)

    sim = wetcloth.Simulation(wetcloth.load_scene(nx=3, ny=3, integrator="implicit_euler", tolerance=1e-4))
    sim._buffers.vel[2, 0] = 1e9  # as if exploded: the guard refuses the next step
    with pytest.raises(wetcloth.BlowUpError) as info:
        sim.advance(0.01)
    message = str(info.value)
    assert (f"use a smaller max_step (now {sim.scene.max_step:g} s) or a smaller tolerance (now 0.0001)."
            in message), message
    assert "'implicit_euler' (stable" not in message and "tolerance > 0" not in message
    explicit = wetcloth.Scene(integrator="explicit_euler", tolerance=0.0)
    assert blow_up_advice(explicit, stable_step=1.0) == (
        "use integrator 'implicit_euler' (stable at any step), a smaller max_step "
        f"(now {explicit.max_step:g} s) or a tolerance > 0 (steps adapted to an error bound)")
    # Fixed steps above the scheme's stability bound: the advice names the bound.
    assert blow_up_advice(explicit, stable_step=9.04e-5) == (
        "use integrator 'implicit_euler' (stable at any step), a smaller max_step "
        f"(now {explicit.max_step:g} s; explicit_euler is stable on this cloth at rest at steps up to 9e-05 s, a "
        "cautious bound) or a tolerance > 0 (steps adapted to an error bound)")


def test_progress_moves_by_wall_time_within_a_frame(tmp_path, capfd, monkeypatch):
    """One frame every 5 s of simulated time: the bar still moves while the frame is computed.
    (The default grid: its frame takes about a second, where a 9 x 9 cloth's now took less than
    tqdm's 0.1 s between two redraws, so no redraw fell inside the frame.)"""
    from wetcloth import progress

    monkeypatch.setattr(progress, "SHOW_AFTER", 0.0)
    monkeypatch.setattr(progress, "POLL", 0.01)
    run(wetcloth.load_scene("thesis_fast"), duration=5.0, fps=0.2, progress=True)
    states = re.findall(r"\| (\d+\.\d)/5\.0 sim s", capfd.readouterr().err)
    assert any(0.0 < float(n) < 5.0 for n in states), states


def test_empty_paths_are_refused(capsys):
    for option in ("--export", "--csv", "--plot"):
        with pytest.raises(SystemExit) as info:
            main(["run", option, ""])
        assert info.value.code == 2
        assert f"argument {option}: needs a path, got an empty string" in capsys.readouterr().err


def test_version_and_params(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    expected = f"wetcloth {wetcloth.__version__} (compiled core: {wetcloth.core_build.running()} build)\n"
    assert info.value.code == 0 and capsys.readouterr().out == expected
    assert main(["params", "thesis_sink", "--json"]) == 0
    rows = {r["name"]: r for r in json.loads(capsys.readouterr().out)}
    assert len(rows) == len(wetcloth.scene.PARAMETERS) + 2  # and duration, fps of [run]
    assert rows["thickness"] == dict(name="thickness", table="", value=0.0004, default=0.002, unit="m",
                                     range="0 < thickness <= 1 m", min=0.0, min_exclusive=True, max=1.0, choices=None,
                                     fmu="parameter", doc=wetcloth.scene.PARAMETERS["thickness"].metadata["doc"])
    assert rows["duration"]["table"] == "run" and rows["integrator"]["choices"] == list(wetcloth.scene.INTEGRATORS)
    assert main(["params"]) == 0
    table = capsys.readouterr().out.splitlines()
    assert table[0].split()[:4] == ["name", "value", "default", "unit"]
    assert any(re.match(r"thickness +0\.002 +0\.002 +m +envelope thickness", line) for line in table), table


def test_params_keeps_its_columns_beside_a_long_path(capsys, monkeypatch):
    """A preset's mesh file (a long absolute path) runs past its column on a line of its own: the other
    rows keep their columns and the terminal's width (before, the path widened the value column for all
    and pushed the meanings past the width)."""
    monkeypatch.setenv("COLUMNS", "100")
    assert main(["params", "tablecloth"]) == 0
    lines = capsys.readouterr().out.splitlines()
    meaning = lines[0].index("meaning")
    assert next(line for line in lines if "the cloth's mesh file" in line).index("the cloth's mesh file") == meaning
    assert all(len(line) <= 100 for line in lines if "round_tablecloth.ply" not in line)
    # a value 1 or 2 characters too long for its column also goes on alone (not glued to the next cell)
    assert _row_lines(["x", "a" * 25, "d"], [1, 24]) == ["x  " + "a" * 25, " " * 29 + "d"]


def test_a_reader_that_leaves_stops_the_command_quietly():
    """``wetcloth params | head -1``: the pipe closed before the table is written (its reader gone) stops the
    command with exit 1 or more and nothing on stderr (before: 'error: [Errno 32] Broken pipe')."""
    proc = subprocess.Popen([sys.executable, "-m", "wetcloth.cli", "params"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    proc.stdout.close()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0 and err == ""


def test_an_operating_system_error_is_one_clear_line(tmp_path, capsys):
    """Any command: an OSError (here a file standing where a folder must be) is a one-line error, exit 2."""
    (tmp_path / "afile").write_text("")
    code = main(["build-fmu", "--out", str(tmp_path / "afile" / "WetCloth.fmu")])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("wetcloth build-fmu: error:") and "afile" in err and "Traceback" not in err


def test_the_plotted_cloth_shapes_are_evenly_spread_frames_including_both_ends():
    """``shapes`` frames of the run are kept for the plot: first, last and evenly between (frame
    times are exact multiples of 1/fps, so the times compare exactly)."""
    from wetcloth.runner import shape_frames
    from wetcloth.scene import Scene

    assert shape_frames(11, 3) == [0, 5, 10] and shape_frames(11, 0) == [] and shape_frames(2, 4) == [0, 1]
    result = run(Scene(nx=4, ny=4), 1.0, 10.0, shapes=3, progress=False, warn=None)
    assert [shape.time for shape in result.shapes] == [0.0, 0.5, 1.0]
    assert all(shape.positions.shape == (16, 3) and shape.wetness.shape == (16,) for shape in result.shapes)


@pytest.mark.parametrize("command", ["run", "params", "build-fmu", "demo", "batch", "fit", "blender-extension"])
def test_every_commands_help_prints_its_text_as_written(capsys, command):
    """argparse formats an option's help with %, not a description: b60f040's fit description showed '95 %%'."""
    with pytest.raises(SystemExit) as stop:
        main([command, "--help"])
    out = capsys.readouterr().out
    assert stop.value.code == 0 and f"usage: wetcloth {command}" in out
    assert "%%" not in out
