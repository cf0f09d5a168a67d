"""The Wet Cloth extension's cache names and bake lifecycle in a real Blender (bpy from PyPI, .venv-blender).

One Blender process (tests/blender/caches_probe.py, with its own user folder) installs the extension
built as tests/test_blender_extension.py builds it and bakes small grids, 6 frames each: cloths named
as artists name them, a duplicated cloth, names making one identifier, a bake failing on a USD file
held open, a bake refused for its cache folder, a cancelled two-cloth bake, the Cache folder set to a
'//' folder and emptied, and the modal bake's cloth deleted or Bake pressed again while it runs.
"""

import pytest

from support.blender import probe_extension
from test_blender_extension import PROBE

CACHES_PROBE = PROBE.with_name("caches_probe.py")
FRAMES = 6


@pytest.fixture(scope="module")
def probed(tmp_path_factory):
    """The probe's result: one entry per case (a case that broke holds its traceback under "error")."""
    return probe_extension(tmp_path_factory.mktemp("caches"), CACHES_PROBE, {"frames": FRAMES})


def case(probed, name: str):
    """The probe's result for case ``name``; the test fails with its traceback if the case broke."""
    result = probed[name]
    if isinstance(result, dict) and "error" in result and "result" not in result:
        pytest.fail(f"the probe's case {name!r} broke:\n{result['error']}")
    return result


def assert_plays_its_own(plays: dict, name: str, complete: bool = True):
    """The cloth plays its own cache ``name``: <name>/<name>.usd, prim /wetcloth/<name>, moving, its vertices."""
    assert plays is not None, "no cache modifier"
    assert plays["path"].endswith(f"/{name}/{name}.usd") and plays["exists"], plays
    assert plays["prim"] == f"/wetcloth/{name}"
    assert plays["moved"] and plays["vertices"] == plays["own_vertices"]
    assert plays["complete"] is complete


def test_the_probe_installed_the_extension(probed):
    assert probed["install"] == {"result": ["FINISHED"], "error": None}


@pytest.mark.parametrize("name, cache", [("Towel.001", "Towel_001"), ("my-towel", "my_towel"),
                                         ("2nd_towel", "cloth_2nd_towel")])
def test_a_cloth_of_any_name_bakes_under_a_valid_usd_name(probed, name, cache):
    """'.', '-' and a leading digit are not in a USD prim name: the cache is named by pxr's
    Tf.MakeValidIdentifier (starting with a letter); the bake failed with a pxr traceback."""
    baked = case(probed, "names")[name]
    assert baked["result"] == ["FINISHED"], baked["error"]
    assert_plays_its_own(baked["plays"], cache)


def test_a_duplicated_cloth_and_its_original_both_bake(probed):
    """Shift+D names the copy 'Towel.001' and gives it the original's modifier: both bake, each its own cache
    (both lost their bake)."""
    duplicate = case(probed, "duplicate")
    assert duplicate["first"]["result"] == ["FINISHED"] and duplicate["copy"] == "Towel.001"
    assert duplicate["second"]["result"] == ["FINISHED"], duplicate["second"]["error"]
    assert_plays_its_own(duplicate["plays"]["Towel"], "Towel")
    assert_plays_its_own(duplicate["plays"]["Towel.001"], "Towel_001")


def test_cloths_whose_names_make_one_identifier_get_distinct_caches(probed):
    """Two Cyrillic names (both 'cloth'), 'Towel 1' and 'Towel_1': the valid name keeps itself, the other
    gets '_2' ('A layer already exists with identifier' before)."""
    cyrillic, towels = case(probed, "same_name")
    for baked in (cyrillic, towels):
        assert baked["result"] == ["FINISHED"], baked["error"]
    assert_plays_its_own(cyrillic["plays"]["Полотенце"], "cloth")
    assert_plays_its_own(cyrillic["plays"]["Скатерть"], "cloth_2")
    assert_plays_its_own(towels["plays"]["Towel_1"], "Towel_1")
    assert_plays_its_own(towels["plays"]["Towel 1"], "Towel_1_2")


def test_a_bake_failing_on_a_usd_file_says_so_and_leaves_nothing_open(probed):
    """'Bib''s USD file held open: the bake reports it naming the cloth (a pxr traceback before), and once the
    file is let go the next bake succeeds (the first cloth's file stayed open until the .blend was reopened)."""
    stuck = case(probed, "stuck")
    first = stuck["first"]
    assert first["result"] == ["ERROR"] and "Traceback" not in first["error"]
    assert "'Apron' (6 frames" in first["error"] and "'Bib' (no frame baked" in first["error"]
    assert "cloth 'Bib': cannot write its cache" in first["error"] and "A layer already exists" in first["error"]
    assert stuck["second"]["result"] == ["FINISHED"], stuck["second"]["error"]
    assert_plays_its_own(stuck["plays"]["Apron"], "Apron")
    assert_plays_its_own(stuck["plays"]["Bib"], "Bib")


def test_a_bake_refused_for_its_cache_folder_keeps_the_last_bake(probed):
    """A Cache folder that is a file is refused before the last bake is touched (it removed the modifier)."""
    refused = case(probed, "refused")
    assert refused["first"]["result"] == ["FINISHED"]
    assert refused["second"]["result"] == ["ERROR"]
    assert "the Cache folder '//notes.txt' cannot be made" in refused["second"]["error"]
    assert "notes.txt is a file" in refused["second"]["error"]
    assert_plays_its_own(refused["plays"], "Towel")


def test_a_cancelled_bake_keeps_the_previous_bake_of_a_cloth_not_reached(probed):
    """Cancelled within the first cloth: the second keeps its previous bake and the report says so (it was
    removed, files too, while the report said its frames were kept)."""
    cancel = case(probed, "cancel_two")
    assert cancel["first"]["result"] == ["FINISHED"] and cancel["cancelled"]["result"] == ["CANCELLED"]
    assert_plays_its_own(cancel["plays"]["Apron"], "Apron", complete=False)
    assert cancel["plays"]["Bib"] == cancel["before"]["Bib"]
    assert_plays_its_own(cancel["plays"]["Bib"], "Bib")
    said = cancel["cancelled"]["printed"]
    assert f"'Apron' ({FRAMES // 2} of {FRAMES} frames kept" in said
    assert "'Bib' (not reached: its previous bake is kept)" in said


def test_the_cache_folder_takes_blend_relative_paths_and_refuses_an_empty_one(probed):
    """'//my_cache' is set without a warning (the property said it does not support '//') and baked into;
    an empty Cache folder is refused naming the setting (the bake wrote into Blender's working folder)."""
    cache_dir = case(probed, "cache_dir")
    assert cache_dir["warnings"] == []
    relative = cache_dir["relative"]
    assert relative["result"] == ["FINISHED"] and relative["value"] == "//my_cache"
    assert "/cache_dir/my_cache/Towel/Towel.usd" in relative["plays"]["path"]
    empty = cache_dir["empty"]
    assert empty["result"] == ["ERROR"] and "the Cache folder is empty" in empty["error"]
    assert "Cache folder" in empty["error"] and "//wetcloth_cache" in empty["error"]
    assert empty["working"] == [] and empty["plays"] == relative["plays"]


def test_a_cloth_deleted_during_a_modal_bake_stops_it_with_a_report(probed):
    """The cloth deleted between two timer ticks: the bake stops naming it and says where its frame is
    (ReferenceError before), and the next bake may start."""
    deleted = case(probed, "modal_delete")
    assert deleted["stopped"] == "error: cloth 'Towel' was deleted during the bake"
    assert deleted["done"] == 1
    assert "'Towel' (deleted during the bake: frames baked 1, left in " in deleted["closed"]
    assert deleted["closed"].split("left in ")[1].split(")")[0].endswith("/Towel/Towel.usd")
    assert deleted["running"] is False


def test_a_second_bake_while_one_runs_is_refused(probed):
    """Bake pressed while a modal bake runs: refused, saying a bake is running ('A layer already exists'
    before); the first bake finishes and a bake after it runs."""
    twice = case(probed, "modal_twice")
    assert twice["second"].startswith("a bake is running")
    assert twice["operator"]["result"] == ["ERROR"] and "a bake is running" in twice["operator"]["error"]
    assert twice["closed"].startswith(f"Wet Cloth: baked 'Towel' ({FRAMES} frames")
    assert twice["after"]["result"] == ["FINISHED"], twice["after"]["error"]
    assert_plays_its_own(twice["plays"], "Towel")


def test_a_renamed_cloth_baked_again_leaves_no_cache_of_its_old_name(probed):
    """'Towel' baked, renamed 'Sheet', baked again: the bake writes Sheet/ and deletes Towel/, its own previous
    bake that nothing plays any more (it was left on disk)."""
    renamed = case(probed, "renamed")
    assert renamed["first"]["result"] == ["FINISHED"] and renamed["first"]["folders"] == ["Towel"]
    assert renamed["second"]["result"] == ["FINISHED"], renamed["second"]["error"]
    assert renamed["second"]["folders"] == ["Sheet"]
    assert_plays_its_own(renamed["plays"], "Sheet")
