"""Runs in bpy (PyPI's bpy, background): the Wet Cloth extension's cache names and bake lifecycle.

    BLENDER_USER_RESOURCES=DIR .venv-blender/bin/python tests/blender/caches_probe.py SPEC.json RESULT.json

SPEC: {"zip": the extension, "work": a folder, "frames": frame count}.  Each case bakes small grids
(role Cloth) in a new saved .blend under WORK/<case>; RESULT holds, per case, what the operators said
and what the cloths play (the assertions are in tests/test_blender_extension_caches.py), or
{"error": traceback} for a case that broke:
  "names": a cloth named as artists name them ('Towel.001', 'my-towel', '2nd_towel');
  "duplicate": a baked towel duplicated (Shift+D) and baked again;
  "same_name": two cloths whose names make the same identifier;
  "stuck": a bake failing on a cloth's USD file (held open), then baked again once it is let go;
  "refused": a bake refused for its cache folder (a file) after a bake;
  "cancel_two": two cloths baked, then a bake cancelled within the first;
  "cache_dir": the Cache folder set to a '//' folder, then empty;
  "modal_delete": the modal bake's cloth deleted between two timer ticks;
  "modal_twice": Bake pressed while a modal bake runs;
  "renamed": a baked towel renamed and baked again.
"""

import ctypes
import json
import os
import sys
import tempfile
import traceback
import warnings

import bpy  # first: bpy makes bmesh importable

from extension_probe import operator, subdivided_plane

MODIFIER = "Wet Cloth cache"


def reported(call, **kwargs) -> dict:
    """``operator(call)`` and the reports Blender printed (on standard output, in background mode)."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    libc.fflush(None)
    saved = os.dup(1)
    with tempfile.TemporaryFile() as fh:
        os.dup2(fh.fileno(), 1)
        try:
            said = operator(call, **kwargs)
        finally:
            libc.fflush(None)
            os.dup2(saved, 1)
            os.close(saved)
        fh.seek(0)
        return said | {"printed": fh.read().decode()}


def new_scene(spec, case: str):
    """An empty scene of spec's frames at 24 fps saved as WORK/<case>/<case>.blend."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.frame_start, scene.frame_end = 1, spec["frames"]
    scene.wetcloth.self_collision = "off"
    folder = os.path.join(spec["work"], case)
    os.makedirs(folder)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, f"{case}.blend"))
    return scene


def cloth(name: str, x: float = 0.0, cuts: int = 3):
    """A grid cloth ``name`` at x (m)."""
    obj = subdivided_plane(0.4, 0.3, cuts, name)
    obj.location.x = x
    obj.wetcloth.role = "CLOTH"
    return obj


def plays(obj) -> dict | None:
    """What ``obj``'s cache modifier plays: the absolute USD path, the prim, whether the file is there, the
    vertices Blender evaluates at the last frame; None without the modifier."""
    modifier = obj.modifiers.get(MODIFIER)
    if modifier is None:
        return None
    path = os.path.normpath(bpy.path.abspath(modifier.cache_file.filepath))
    scene = bpy.context.scene
    scene.frame_set(scene.frame_end)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    moved = any((v.co - w.co).length > 1e-6 for v, w in zip(evaluated.data.vertices, obj.data.vertices))
    scene.frame_set(scene.frame_start)
    manifest = os.path.join(os.path.dirname(path), "frames.json")
    return {"path": path, "prim": modifier.object_path, "exists": os.path.isfile(path), "moved": moved,
            "vertices": len(evaluated.data.vertices), "own_vertices": len(obj.data.vertices),
            "complete": json.load(open(manifest))["complete"] if os.path.isfile(manifest) else None}


def names(spec):
    out = {}
    for name in ("Towel.001", "my-towel", "2nd_towel"):
        new_scene(spec, f"names{len(out)}")
        obj = cloth(name)
        out[name] = operator(bpy.ops.wetcloth.bake) | {"plays": plays(obj)}
    return out


def duplicate(spec):
    new_scene(spec, "duplicate")
    towel = cloth("Towel")
    first = operator(bpy.ops.wetcloth.bake)
    bpy.ops.object.select_all(action="DESELECT")
    towel.select_set(True)
    bpy.context.view_layer.objects.active = towel
    bpy.ops.object.duplicate_move(TRANSFORM_OT_translate={"value": (2.0, 0.0, 0.0)})
    copy = bpy.context.object
    return {"first": first, "copy": copy.name, "second": operator(bpy.ops.wetcloth.bake),
            "plays": {obj.name: plays(obj) for obj in (towel, copy)}}


def same_name(spec):
    out = []
    for a, b in (("Полотенце", "Скатерть"), ("Towel 1", "Towel_1")):
        new_scene(spec, f"same_name{len(out)}")
        objects = (cloth(a, cuts=5), cloth(b, x=2.0))
        out.append(operator(bpy.ops.wetcloth.bake) | {"plays": {o.name: plays(o) for o in objects}})
    return out


def stuck(spec):
    """'Bib''s USD file held open (as by another program in Blender), baked; let go, baked again."""
    from pxr import Sdf

    new_scene(spec, "stuck")
    objects = (cloth("Apron"), cloth("Bib", x=2.0))
    folder = os.path.join(spec["work"], "stuck", "wetcloth_cache", "Bib")
    held = Sdf.Layer.New(Sdf.FileFormat.FindByExtension("usd"), os.path.join(folder, "Bib.usd"))  # no file
    first = operator(bpy.ops.wetcloth.bake)
    del held
    second = operator(bpy.ops.wetcloth.bake)
    return {"first": first, "second": second, "plays": {o.name: plays(o) for o in objects}}


def refused(spec):
    scene = new_scene(spec, "refused")
    towel = cloth("Towel")
    first = operator(bpy.ops.wetcloth.bake)
    with open(os.path.join(spec["work"], "refused", "notes.txt"), "w") as fh:
        fh.write("a file, not a folder\n")
    scene.wetcloth.cache_directory = "//notes.txt"
    return {"first": first, "second": operator(bpy.ops.wetcloth.bake), "plays": plays(towel)}


def cancel_two(spec):
    new_scene(spec, "cancel_two")
    objects = (cloth("Apron"), cloth("Bib", x=2.0))
    first = operator(bpy.ops.wetcloth.bake)
    before = {o.name: plays(o) for o in objects}
    objects[0].wetcloth.preset = "DENIM"
    cancelled = reported(bpy.ops.wetcloth.bake, cancel_after=spec["frames"] // 2)
    return {"first": first, "before": before, "cancelled": cancelled, "plays": {o.name: plays(o) for o in objects}}


def cache_dir(spec):
    scene = new_scene(spec, "cache_dir")
    towel = cloth("Towel")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene.wetcloth.cache_directory = "//my_cache"
    relative = operator(bpy.ops.wetcloth.bake) | {"plays": plays(towel), "value": scene.wetcloth.cache_directory}
    scene.wetcloth.cache_directory = ""
    working = os.path.join(spec["work"], "cache_dir", "working")
    os.makedirs(working)
    os.chdir(working)
    empty = operator(bpy.ops.wetcloth.bake) | {"plays": plays(towel), "working": os.listdir(working)}
    return {"warnings": [str(w.message) for w in caught], "relative": relative, "empty": empty}


def modal_delete(spec):
    """operators.Baking run by frame_loop.tick as the modal operator runs it; the cloth deleted between ticks."""
    from wetcloth.exporter.blender_extension.frame_loop import advance, tick
    from wetcloth.exporter.blender_extension.operators import Baking

    new_scene(spec, "modal_delete")
    towel = cloth("Towel")
    baking = Baking(bpy.context)
    advance(baking)  # one frame, as a timer tick bakes
    bpy.data.objects.remove(towel)
    stopped = status = None
    while True:
        stopped, status = tick(baking, "TIMER", 0.1)
        if status is None:
            break
    return {"stopped": stopped, "done": baking.done, "closed": baking.close(), "running": Baking.running is not None}


def modal_twice(spec):
    """A second bake (the operator, and Baking as its invoke makes one) while a modal bake runs."""
    from wetcloth.exporter.blender_extension.frame_loop import advance, tick
    from wetcloth.exporter.blender_extension.operators import Baking

    new_scene(spec, "modal_twice")
    towel = cloth("Towel")
    first = Baking(bpy.context)
    advance(first)
    try:
        Baking(bpy.context)
        second = None
    except ValueError as exc:
        second = str(exc)
    operated = operator(bpy.ops.wetcloth.bake)
    while tick(first, "TIMER", 0.1)[1] is not None:
        pass
    closed = first.close()
    return {"second": second, "operator": operated, "closed": closed, "after": operator(bpy.ops.wetcloth.bake),
            "plays": plays(towel)}


def renamed(spec):
    """'Towel' baked, renamed 'Sheet' and baked again: the cache folder's contents after each bake."""
    new_scene(spec, "renamed")
    towel = cloth("Towel")
    folder = bpy.path.abspath(bpy.context.scene.wetcloth.cache_directory)
    first = operator(bpy.ops.wetcloth.bake) | {"folders": sorted(os.listdir(folder))}
    towel.name = "Sheet"
    second = operator(bpy.ops.wetcloth.bake) | {"folders": sorted(os.listdir(folder))}
    return {"first": first, "second": second, "plays": plays(towel)}


CASES = (names, duplicate, same_name, stuck, refused, cancel_two, cache_dir, modal_delete, modal_twice, renamed)


def main(spec_path, result_path):
    spec = json.load(open(spec_path))
    result = {"install": operator(bpy.ops.extensions.package_install_files, filepath=spec["zip"],
                                  repo="user_default", enable_on_install=True)}
    for case in CASES:
        try:
            result[case.__name__] = case(spec)
        except Exception:
            result[case.__name__] = {"error": traceback.format_exc()}
    with open(result_path, "w") as fh:
        json.dump(result, fh)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
