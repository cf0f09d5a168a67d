"""``wetcloth run``: outputs as CSV and a plot, overrides, and clear errors."""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from wetcloth.cli import main
from wetcloth.simulation import OUTPUT_NAMES


def test_run_writes_csv_and_plot(tmp_path):
    csv_path, plot_path = tmp_path / "o.csv", tmp_path / "p.png"
    code = main(["run", "thesis_float", "--duration", "1", "--fps", "10", "--set", "nx=5", "--set", "ny=5",
                 "--csv", str(csv_path), "--plot", str(plot_path), "--no-progress"])
    assert code == 0
    rows = list(csv.DictReader(open(csv_path)))
    assert list(rows[0]) == ["time", *OUTPUT_NAMES]
    assert [float(r["time"]) for r in rows] == [k / 10 for k in range(11)]
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


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
    code = main(["run", "--csv", str(tmp_path), "--plot", str(tmp_path / "p.png")])
    assert code == 2
    err = capsys.readouterr().err
    assert "--csv" in err and str(tmp_path) in err
    assert not (tmp_path / "p.png").exists()


def test_interrupted_run_closes_its_frame_sequence(tmp_path, monkeypatch):
    """Ctrl-C mid-run: frames.json still counts the frames on disk and says the sequence is incomplete."""
    import wetcloth.commands.run as run_command
    from wetcloth.runner import run as real_run

    def interrupted(*args, on_frame, **kwargs):
        def frame(index, sim):
            if index == 3:
                raise KeyboardInterrupt
            on_frame(index, sim)
        return real_run(*args, on_frame=frame, **kwargs)

    monkeypatch.setattr(run_command, "run", interrupted)
    frames = tmp_path / "frames"
    with pytest.raises(KeyboardInterrupt):
        main(["run", "--duration", "1", "--set", "nx=5", "--set", "ny=5", "--export", str(frames),
              "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png"), "--no-progress"])
    manifest = json.loads((frames / "frames.json").read_text())
    assert manifest["complete"] is False
    assert manifest["frame_count"] == 3 == len(list(frames.glob("cloth_*.ply")))


def test_an_operating_system_error_is_one_clear_line(tmp_path, capsys):
    """Any command: an OSError (here a file standing where a folder must be) is a one-line error, exit 2."""
    (tmp_path / "afile").write_text("")
    code = main(["build-fmu", "--out", str(tmp_path / "afile" / "WetCloth.fmu")])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("wetcloth build-fmu: error:") and "afile" in err and "Traceback" not in err
