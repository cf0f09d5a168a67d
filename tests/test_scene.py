"""Scenes: presets load, overrides apply, and every bad value gets an error naming it and its range."""

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

import wetcloth
from wetcloth.batch import load_study
from wetcloth.errors import ConfigError, ParameterError
from wetcloth.scene import PARAMETERS, Scene, describe_range, from_dict, load_scene, preset_dir

PRESETS = ["towel", "thesis_fast", "thesis_slow", "thesis_float", "thesis_sink"]


def test_default_scene_is_the_towel_preset():
    assert load_scene() == Scene()
    assert load_scene("towel") == Scene()


@pytest.mark.parametrize("name", PRESETS)
def test_presets_load_by_name_and_path(name):
    by_name = load_scene(name)
    by_path = load_scene(preset_dir() / f"{name}.toml")
    assert by_name == by_path


def test_thesis_cases_are_what_model_md_says():
    """Section 1: fast/slow absorb and are lighter; float/sink do not absorb; sink is heavier."""
    rho = 1000.0
    for name in ("thesis_fast", "thesis_slow", "thesis_float"):
        sc = load_scene(name)
        assert sc.areal_density < rho * sc.thickness, name
    sink = load_scene("thesis_sink")
    assert sink.areal_density > rho * sink.thickness
    for name in ("thesis_float", "thesis_sink"):
        assert load_scene(name).absorption_capacity == 0.0
    assert load_scene("thesis_fast").absorption_rate > load_scene("thesis_slow").absorption_rate > 0
    assert all(load_scene(n).initial_tilt != 0 for n in PRESETS), "one edge must land first"


def test_overrides_apply_and_numbers_take_their_parameters_type():
    sc = load_scene("thesis_fast", nx=33, initial_tilt=10.0)
    assert (sc.nx, sc.initial_tilt) == (33, 10.0)
    assert isinstance(load_scene(width=1).width, float)
    assert load_scene(nx=9.0).nx == 9 and isinstance(Scene(nx=9.0).nx, int)  # a whole float is a whole number


def test_unknown_parameter_suggests_the_nearest_names():
    with pytest.raises(wetcloth.ParameterError, match=r"'absorbtion_rate': unknown parameter; did you mean "
                                                      r"'absorption_rate'\?$"):
        load_scene(absorbtion_rate=0.1)
    with pytest.raises(wetcloth.ParameterError, match=rf"'colour': unknown parameter \(there are {len(wetcloth.scene.PARAMETERS)}; 'wetcloth params'"):
        load_scene(colour="blue")


@pytest.mark.parametrize("name, fixed", [
    ("collider0_x", "collider1_x"), ("collider01_x", "collider1_x"), ("collider00_radus", "collider1_radius"),
    ("grip_key0_time", "grip_key1_time"), ("grip_key01_time", "grip_key1_time"),
    ("collider_key0_time", "collider_key1_time"), ("collider_key007_z", "collider_key7_z"),
])
def test_a_table_number_of_0_or_with_leading_zeros_is_named_not_suggested_back(name, fixed):
    """Numbered names count from 1 without leading zeros: the message says so and names the fixed name (it
    suggested the name itself: 'collider0_x': did you mean 'collider0_x'?), through --set as well."""
    what = re.match(r"[a-z_]+?(?=\d)", name).group().replace("_", " ")
    expected = f"parameter '{name}': {what} numbers start at 1, without leading zeros; did you mean '{fixed}'?"
    with pytest.raises(ParameterError) as info:
        load_scene(**{name: 1.0})
    assert str(info.value) == expected
    with pytest.raises(ParameterError) as info:
        wetcloth.scene.parse_text(name, "1")
    assert str(info.value) == expected


@pytest.mark.parametrize("name", ["width", "length"])
@pytest.mark.parametrize("value", [1e-300, 5e-324, 9.99e-4])
def test_a_cloth_side_below_a_millimetre_is_refused_naming_the_range(name, value):
    """A side near 0 made zero rest lengths and masses (numpy's divide-by-zero warnings, a motionless cloth)."""
    with pytest.raises(ParameterError) as info:
        load_scene(**{name: value})
    assert str(info.value) == f"parameter '{name}': {value!r} is out of range; allowed: 0.001 <= {name} <= 100 m"
    assert getattr(load_scene(width=1e-3, length=1e-3), name) == 1e-3  # both: the cells stay near square


@pytest.mark.parametrize("value", [1e-300, 5e-324, 9.9e-7])
def test_a_max_step_too_small_to_advance_time_at_1e9_s_is_refused_naming_the_range(value):
    """max_step = 1e-300 s was accepted; a step then never ended (t + max_step == t from t ~ 1e-284 s on).
    The least max_step keeps time advancing up to the latest time a state may hold (1e9 s)."""
    with pytest.raises(ParameterError) as info:
        load_scene(max_step=value)
    assert str(info.value) == f"parameter 'max_step': {value!r} is out of range; allowed: 1e-06 <= max_step <= 1 s"
    assert 1e9 + wetcloth.scene.SMALLEST_MAX_STEP > 1e9
    assert load_scene(max_step=1e-6).max_step == 1e-6


def _bad_values(f: dataclasses.Field):
    md = f.metadata
    if md["choices"]:
        return ["no_such_choice", 3]
    if md["text"]:  # free text: its contents are checked with the scene (tests/test_mesh_input.py)
        return [3, True]
    bad = [md["hi"] * 2 + 1, "abc", True, math.nan]
    bad.append(md["lo"] if md["lo_open"] else md["lo"] - 1)
    if f.type == "int":
        bad.append(2.5)
    return bad


@pytest.mark.parametrize("name", list(PARAMETERS))
def test_each_bad_value_names_the_parameter_and_its_range(name):
    f = PARAMETERS[name]
    for value in _bad_values(f):
        with pytest.raises(wetcloth.ParameterError) as err:
            Scene().replace(**{name: value})
        message = str(err.value)
        assert f"'{name}'" in message, message
        assert describe_range(f) in message, message
        assert err.value.name == name


def test_range_text_reads_like_a_bound():
    assert describe_range(PARAMETERS["thickness"]) == "0 < thickness <= 1 m"
    assert describe_range(PARAMETERS["drag_model"]) == "one of 'face', 'stokes'"


def test_cloth_starting_below_the_floor_is_refused():
    with pytest.raises(wetcloth.ParameterError, match="initial_height.*floor"):
        Scene(initial_height=-2.0, floor_level=-1.0)


def test_missing_scene_file_lists_the_presets(tmp_path):
    with pytest.raises(FileNotFoundError, match="presets: .*thesis_fast"):
        load_scene(tmp_path / "nope.toml")


def test_a_misspelled_preset_gets_the_nearest_names():
    with pytest.raises(FileNotFoundError, match="'tablcloth' is not a file: .*did you mean 'tablecloth'\\?$"):
        load_scene("tablcloth")


def test_broken_toml_names_the_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("nx = = 3")
    with pytest.raises(ValueError, match="scene file '.*bad.toml': not valid TOML"):
        load_scene(path)


def test_a_scene_file_that_starts_with_a_byte_order_mark_is_read(tmp_path):
    """Notepad (before Windows 10's 1903) starts a UTF-8 file with a byte-order mark; b60f040 refused it as
    "not valid TOML: Invalid statement (at line 1, column 1)"."""
    path = tmp_path / "notepad.toml"
    path.write_bytes("nx = 9\nwidth = 0.3\n".encode("utf-8-sig"))
    scene = load_scene(path)
    assert (scene.nx, scene.width) == (9, 0.3)


def test_a_whole_number_beyond_every_float_is_named_not_a_crash(tmp_path):
    """A TOML integer too large for a float (309 digits and more): b60f040 crashed with a traceback
    (OverflowError: int too large to convert to float) in the scene's and the study's number checks."""
    huge = "1" + "0" * 400
    scene = tmp_path / "huge.toml"
    scene.write_text(f"width = {huge}\n[run]\nduration = {huge}\n")
    with pytest.raises(ConfigError, match=r"huge.toml': 'width' is a whole number beyond 1.8e308, outside every "
                                          r"range \(2 such numbers\)"):
        load_scene(scene)
    study = tmp_path / "study.toml"
    study.write_text(f'scene = "thesis_fast"\n[axes]\nabsorption_rate = {{ start = 0, stop = {huge}, num = 3 }}\n')
    with pytest.raises(ConfigError, match=r"'axes.absorption_rate.stop' is a whole number beyond 1.8e308"):
        load_study(study)
    digits = tmp_path / "digits.toml"
    digits.write_text("nx = " + "9" * 5000 + "\n")
    with pytest.raises(ConfigError, match=r"digits.toml': not valid TOML: Exceeds the limit"):
        load_scene(digits)
    with pytest.raises(ParameterError, match=r"'width': a whole number beyond 1.8e308 is out of range"):
        Scene(width=int(huge))


def test_numpy_numbers_are_numbers(tmp_path):
    """``Scene(nx=n) for n in np.arange(...)``: NumPy's integers and floats are taken as Python's (b60f040 refused
    them: "expected a number, got np.int64(7)"); a fraction is still no whole number, a NumPy bool no number."""
    scene = Scene(nx=np.int64(7), ny=np.int32(5), width=np.float32(0.25), thickness=np.int64(1))
    assert (scene.nx, scene.ny, scene.width, scene.thickness) == (7, 5, 0.25, 1.0)
    assert type(scene.nx) is int and type(scene.width) is float
    sim = wetcloth.Simulation(Scene(nx=5, ny=5))
    sim.set_inputs(water_level=np.float32(0.5))
    assert sim.scene.water_level == 0.5
    with pytest.raises(ParameterError, match=r"'nx': expected a whole number, got np.float32\(3.5\)"):
        Scene(nx=np.float32(3.5))
    with pytest.raises(ParameterError, match=r"'nx': expected a number, got np.True_"):
        Scene(nx=np.bool_(True))


def test_binary_or_unreadable_scene_file_is_named(tmp_path):
    binary = tmp_path / "towel.png"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00")
    with pytest.raises(ValueError, match=r"scene file '.*towel.png': not a text \(TOML\) file: byte 0x89"):
        load_scene(binary)
    with pytest.raises(ValueError, match=f"scene file '{tmp_path}': cannot be read: Is a directory"):
        load_scene(tmp_path)


def test_a_scene_file_with_several_mistakes_reports_all_of_them_at_once(tmp_path):
    """Unknown names (with the nearest ones), wrong types, out of range, [run] mistakes: one error,
    one line each, naming the file."""
    path = tmp_path / "three.toml"
    path.write_text('widht = 0.5\nnx = 3.5\nthickness = -1.0\n[run]\nduraton = 1.0\nfps = "fast"\n')
    with pytest.raises(wetcloth.ConfigError) as info:
        load_scene(path)
    assert str(info.value).splitlines() == [
        f"scene file {path}: 5 mistakes",
        "  parameter 'widht': unknown parameter; did you mean 'width'?",
        "  parameter 'nx': expected a whole number, got 3.5; allowed: 2 <= nx <= 1024",
        "  parameter 'thickness': -1.0 is out of range; allowed: 0 < thickness <= 1 m",
        "  [run] 'duraton': unknown run setting; did you mean 'duration'?",
        "  [run] 'fps': expected a number, got 'fast' (text: write the number without quotes); allowed: 0 < fps <= 10000 1/s",
    ]


@pytest.mark.parametrize("text, message", [
    ("run = 5\n", "setting 'run': must be the table [run]"),
    ('[run]\nduration = "abc"\n', "[run] 'duration': expected a number, got 'abc' (text: write the number without quotes); "
                                "allowed: 0 < duration <= 1e+06 s"),
    ("duration = 3.0\n", "parameter 'duration' is a run setting: put it in the [run] table"),
    ("description = 3\n", "parameter 'description': must be text"),
])
def test_run_table_and_other_keys_are_checked(tmp_path, text, message):
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(wetcloth.ConfigError) as info:
        load_scene(path)
    assert str(info.value) == f"scene file {path}: {message}" or str(info.value).startswith(f"scene file {path}: {message}")


def test_one_type_rule_for_every_source(tmp_path):
    """Scene files, Python overrides, --set, studies and a scene file's [run] table: text is no number (one
    message everywhere; [run]'s had no hint before), and nx = 3.0 is the whole number 3."""
    from wetcloth.batch import Study
    from wetcloth.scene import parse_text

    refused = "expected a number, got '0.5' (text: write the number without quotes)"
    path = tmp_path / "text.toml"
    path.write_text('width = "0.5"\n')
    run_path = tmp_path / "run_text.toml"
    run_path.write_text('[run]\nduration = "0.5"\n')
    for attempt in (lambda: load_scene(path), lambda: load_scene(width="0.5"), lambda: load_scene(run_path),
                    lambda: Study.from_dict({"duration": 1.0, "base": {"width": "0.5"}}),
                    lambda: Study.from_dict({"duration": 1.0, "axes": {"width": ["0.5"]}})):
        with pytest.raises(ValueError, match=re.escape(refused)):
            attempt()
    with pytest.raises(ValueError, match="expected a number, got '\"0.5\"'"):  # --set width='"0.5"'
        parse_text("width", '"0.5"')
    path.write_text("nx = 3.0\n")
    study = Study.from_dict({"duration": 1.0, "base": {"nx": 3.0}, "axes": {"ny": [3.0]}})
    assert load_scene(path).nx == load_scene(nx=3.0).nx == parse_text("nx", "3.0") == study.runs()[0].params["nx"] == 3
    assert study.runs()[0].params["ny"] == 3 and parse_text("width", "0.5") == 0.5


def test_run_settings_one_rule(tmp_path):
    """Given > the scene file's [run] > the defaults, for the command line and for studies alike."""
    from wetcloth import run_settings
    from wetcloth.batch import Study

    assert run_settings.resolve(None) == run_settings.RunSettings(10.0, 30.0)
    assert run_settings.resolve({"duration": 90.0}) == run_settings.RunSettings(90.0, 30.0)
    assert run_settings.resolve({"duration": 90.0, "fps": 10}, duration=5.0) == run_settings.RunSettings(5.0, 10.0)
    bare = tmp_path / "bare.toml"
    bare.write_text("nx = 5\n")
    assert Study.from_dict({"scene": str(bare)}).duration == run_settings.DEFAULTS["duration"]
    assert Study.from_dict({"scene": "thesis_fast"}).duration == 90.0  # thesis_fast.toml [run]
    assert Study.from_dict({"scene": "thesis_fast", "duration": 5}).duration == 5.0


@pytest.mark.parametrize("name", sorted(p.stem for p in (Path(__file__).resolve().parents[1] / "models").glob("*.toml")))
def test_every_preset_runs_a_moment(name):
    """Each scene preset in models/ loads by name and runs 0.05 s to a finite state."""
    sim = wetcloth.Simulation(load_scene(name))
    sim.advance(0.05)
    assert sim.state.is_finite()



def test_a_new_collider_or_grip_key_list_replaces_the_scenes_whole():
    """``colliders=()`` (or another list) and ``grip_keys=()`` replace a scene's table lists, from a file or a
    Scene; a flattened name changes one field of one collider."""
    assert load_scene("bucket", colliders=()).colliders == ()
    assert load_scene("bucket").replace(colliders=()).colliders == ()
    assert load_scene("lift").replace(grip_keys=()).grip_keys == ()
    sphere = load_scene("tablecloth_sphere", colliders=({"shape": "sphere", "radius": 0.05},))
    assert [c.radius for c in sphere.colliders] == [0.05]
    assert load_scene("tablecloth", collider1_radius=0.3).colliders[0].radius == 0.3
