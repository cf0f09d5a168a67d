"""``wetcloth run`` and ``params`` refuse what they would otherwise ignore or misread: export options
without ``--export``, abbreviated options, extra arguments after ``--version``, a ``--set`` given twice
or of a run setting, numbers with underscores; and the run's own refusals name what to change."""

import json

import pytest

import wetcloth
from wetcloth.cli import main
from wetcloth.runner import run

#: A quick run: a 3 x 3 towel for a tenth of a second.
QUICK = ["--duration", "0.1", "--set", "nx=3", "--set", "ny=3", "--no-progress"]


def _outputs(tmp_path) -> list[str]:
    return ["--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png")]


def _refused(argv, capsys) -> str:
    """The one stderr line of a command refused with exit 2 (by argparse or by the command)."""
    try:
        code = main(argv)
    except SystemExit as stop:
        code = stop.code
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err, err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize("option", [["--writer", "meshio"], ["--first-frame", "3"], ["--faces", "triangles"],
                                    ["--overwrite"], ["--format", "obj"], ["--format", "ply"]])
def test_export_options_without_export_are_refused(tmp_path, capsys, option):
    line = _refused(["run", *QUICK, *_outputs(tmp_path), *option], capsys)
    assert line == (f"wetcloth run: error: {option[0]} applies to an export only: add --export DIR "
                    f"(or leave out {option[0]})")
    assert not (tmp_path / "o.csv").exists()


def test_usd_refuses_only_a_writer_asked_for_and_says_which_writes_it(tmp_path, capsys):
    line = _refused(["run", *QUICK, *_outputs(tmp_path), "--export", str(tmp_path / "d"), "--format", "usd",
                     "--writer", "trimesh"], capsys)
    assert line == ("wetcloth run: error: --writer trimesh does not apply to --format usd: usd-core writes USD files; "
                    "leave out --writer (it chooses the library of ply and obj frames)")
    assert main(["run", *QUICK, *_outputs(tmp_path), "--export", str(tmp_path / "d"), "--format", "usd"]) == 0
    assert json.loads((tmp_path / "d" / "frames.json").read_text())["writer"] == "usd-core"


@pytest.mark.parametrize("argv, message", [
    (["run", "--durat", "1"], "unrecognized arguments: --durat"),
    (["--vers", "params"], "unrecognized arguments: --vers"),  # not taken for --version
    (["--version", "extra"], "--version takes no other arguments, got extra"),
    (["--version", "run"], "--version takes no other arguments, got run"),
])
def test_abbreviations_and_extra_arguments_are_refused(capsys, argv, message):
    assert _refused(argv, capsys).endswith(message)


@pytest.mark.parametrize("option, text, expected", [
    ("--duration", "1_0", "a number"), ("--fps", "3_0", "a number"), ("--first-frame", "1_0", "a whole number"),
    ("--first-frame", "1.5", "a whole number"), ("--duration", "x", "a number"),
])
def test_numbers_with_underscores_are_refused(tmp_path, capsys, option, text, expected):
    line = _refused(["run", *QUICK, *_outputs(tmp_path), "--export", str(tmp_path / "d"), option, text], capsys)
    assert line == f"wetcloth run: error: argument {option}: expected {expected}, got {text!r}"


def test_a_parameter_set_twice_is_refused(tmp_path, capsys):
    line = _refused(["run", *QUICK, *_outputs(tmp_path), "--set", "nx=5", "--set", "nx=6"], capsys)
    assert line == "wetcloth run: error: --set nx is given 3 times (3, 5, 6): give each parameter once"
    data = tmp_path / "m.csv"
    data.write_text("time,depth\n0,0\n1,0.1\n")
    line = _refused(["fit", "towel", "--data", str(data), "--params", "drag_normal", "--set", "nx=5", "--set", "nx=6"],
                    capsys)
    assert line == "wetcloth fit: error: --set nx is given 2 times (5, 6): give each parameter once"


@pytest.mark.parametrize("name", ["duration", "fps"])
def test_a_run_setting_given_to_set_names_its_option(tmp_path, capsys, name):
    line = _refused(["run", *QUICK, *_outputs(tmp_path), "--set", f"{name}=1"], capsys)
    assert line == f"wetcloth run: error: --set {name}: {name} is a run setting, not a scene parameter: use --{name}"


def test_an_earlier_export_is_refused_naming_overwrite_and_counting_only_frames(tmp_path, capsys):
    """11 frames and frames.json and the loader: '... and 8 more' frames, and the option that replaces them."""
    argv = ["run", *QUICK, *_outputs(tmp_path), "--duration", "1", "--fps", "10", "--export", str(tmp_path / "d")]
    assert main(argv) == 0
    capsys.readouterr()
    line = _refused(argv, capsys)
    assert line.endswith("already holds another run's frames (cloth_0001.ply, cloth_0002.ply, cloth_0003.ply and 8 "
                         "more); choose a new directory, delete them first or pass --overwrite to replace that run")
    assert main([*argv, "--overwrite"]) == 0


def test_frame_names_are_padded_to_the_last_frames_number(tmp_path):
    assert main(["run", *QUICK, *_outputs(tmp_path), "--fps", "10", "--export", str(tmp_path / "d"),
                 "--first-frame", "9999"]) == 0
    assert sorted(p.name for p in (tmp_path / "d").glob("cloth_*")) == ["cloth_09999.ply", "cloth_10000.ply"]


def test_too_many_frames_from_python_name_duration_not_fps():
    with pytest.raises(ValueError) as refused:
        run(wetcloth.load_scene(nx=3, ny=3), 1e7, 30)
    assert str(refused.value) == ("duration 1e+07 s at fps 30 is 3e+08 frames; at most 200000 per run: a duration "
                                  "up to 6666.63 s at this fps")


def test_params_refuses_a_scene_that_run_refuses(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(f'cloth_mesh = "{tmp_path / "missing.obj"}"\n')
    line = _refused(["params", str(scene)], capsys)
    assert line.startswith("wetcloth params: error: parameter 'cloth_mesh': ") and "cannot be read" in line
    assert main(["params", "--json"]) == 0


@pytest.mark.parametrize("text, expected", [("3.5", "expected a whole number, got 3.5"),
                                            ("1_0", "expected a number, got '1_0'")])
def test_set_reads_a_number_as_a_scene_file_does(tmp_path, capsys, text, expected):
    """--set nx=3.5 said 'expected a number' where a scene file's 3.5 says 'a whole number', and
    --set nx=1_0 was read as 10 (Python's int reads underscores; TOML and the scene file do not)."""
    line = _refused(["run", *QUICK[:2], "--set", f"nx={text}", *_outputs(tmp_path)], capsys)
    assert line.startswith(f"wetcloth run: error: --set: parameter 'nx': {expected}; allowed: 2 <= nx <= ")


@pytest.mark.parametrize("missing", ["{tmp}/elsewhere/thesis_sink.toml", "{tmp}/towel.toml"])
def test_a_missing_scene_path_is_refused_not_read_as_the_preset_of_its_name(tmp_path, capsys, missing):
    """A path with a folder names a file only: a missing one ran the preset of the same name (exit 0)."""
    path = missing.format(tmp=tmp_path)
    line = _refused(["run", path, *QUICK, *_outputs(tmp_path)], capsys)
    assert line.startswith(f"wetcloth run: error: scene {path!r} is not a file: unknown scene preset; did you mean")
    assert not (tmp_path / "o.csv").exists()


def test_a_preset_is_still_named_bare(tmp_path, monkeypatch):
    """A bare name, with or without .toml, names the preset (no such file in the working folder)."""
    monkeypatch.chdir(tmp_path)
    assert wetcloth.load_scene("thesis_sink.toml") == wetcloth.load_scene("thesis_sink")
    assert wetcloth.load_scene("thesis_sink") != wetcloth.load_scene("towel")


def test_an_empty_collider_table_is_refused_not_dropped(tmp_path, capsys):
    """An empty [[collider]] table vanished and the next was numbered as collider 1: its error then named
    collider2 while 'there is no collider 1'."""
    scene = tmp_path / "two.toml"
    scene.write_text('nx = 3\nny = 3\n[[collider]]\n[[collider]]\nshape = "box"\nz = -0.5\n')
    line = _refused(["run", str(scene), *QUICK[:2], *_outputs(tmp_path)], capsys)
    assert line.endswith("parameter 'collider1': [[collider]] table 1 is empty: give its fields, or delete it")
