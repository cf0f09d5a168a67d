"""Scenes: presets load, overrides apply, and every bad value gets an error naming it and its range."""

import dataclasses
import math

import pytest

import wetcloth
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


def test_overrides_and_text_values():
    sc = load_scene("thesis_fast", nx=33, initial_tilt=10.0)
    assert (sc.nx, sc.initial_tilt) == (33, 10.0)
    assert from_dict({"nx": "17", "width": "0.25", "drag_model": "stokes"}).nx == 17
    assert isinstance(load_scene(width=1).width, float)


def test_unknown_parameter_is_refused_with_the_known_names():
    with pytest.raises(wetcloth.ParameterError, match="'colour'.*unknown parameter.*known: nx, ny"):
        load_scene(colour="blue")


def _bad_values(f: dataclasses.Field):
    md = f.metadata
    if md["choices"]:
        return ["no_such_choice", 3]
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
    with pytest.raises(FileNotFoundError, match="thesis_fast"):
        load_scene(tmp_path / "nope.toml")


def test_broken_toml_names_the_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("nx = = 3")
    with pytest.raises(ValueError, match="bad.toml"):
        load_scene(path)
