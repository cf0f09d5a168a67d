"""The baked cloth in the .blend: a Mesh Sequence Cache modifier playing the cloth's USD file (its path
relative to the .blend), the wet material, and the check for missing caches when a file loads; the
caches' names (valid USD identifiers, one per cloth) and the check of the cache folder before a bake.

A missing cache would leave the cloth frozen in its rest pose with only a console warning; the
``load_post`` handler instead names every missing file in Blender's interface (a pop-up, and the
Wet Cloth panel), on standard error, and in ``bpy.app.driver_namespace["wetcloth_missing_caches"]``
for scripts and render farms.
"""

from __future__ import annotations

import os
import re
import sys

import bpy
from bpy.app.handlers import persistent

from wetcloth.exporter import sequence_files

#: Name of the Mesh Sequence Cache modifier the bake adds to each cloth.
MODIFIER = "Wet Cloth cache"
#: Key in bpy.app.driver_namespace: [(object name, absolute path)] of the caches missing at the last load.
MISSING = "wetcloth_missing_caches"


def cache_modifier(obj):
    """The bake's Mesh Sequence Cache modifier of ``obj``, or None."""
    modifier = obj.modifiers.get(MODIFIER)
    return modifier if modifier is not None and modifier.type == "MESH_SEQUENCE_CACHE" else None


def cache_path(obj) -> str | None:
    """The absolute path of the USD file ``obj`` plays, or None if it has no baked cache."""
    modifier = cache_modifier(obj)
    if modifier is None or modifier.cache_file is None:
        return None
    return os.path.normpath(bpy.path.abspath(modifier.cache_file.filepath, library=modifier.cache_file.library))


def _relative(path: str) -> str:
    """``path`` relative to the .blend (``//...``) where the file is saved (and on the same drive)."""
    if not bpy.data.filepath:
        return path
    try:
        return bpy.path.relpath(path)
    except ValueError:
        return path


def _identifier(name: str) -> str:
    """``name`` as a USD prim name that is also a file prefix: pxr's Tf.MakeValidIdentifier (of
    ``cloth_<name>`` if it does not start with a letter), each run of '_' made one."""
    from pxr import Tf

    start = name[:1]
    valid = Tf.MakeValidIdentifier(name if start.isascii() and start.isalpha() else f"cloth_{name}")
    return re.sub("_+", "_", valid).strip("_")


def cache_names(names) -> dict[str, str]:
    """The cache name (its folder, USD file and prim) of each cloth name: a valid USD identifier, distinct
    from the others' even on a file system blind to case; a name valid as it is keeps itself, the others
    (in sorted order) get ``_2``, ``_3``... where they would meet."""
    taken, chosen = set(), {}
    for name in sorted(names, key=lambda n: (_identifier(n) != n, n)):
        base = candidate = _identifier(name)
        number = 1
        while candidate.lower() in taken:
            number += 1
            candidate = f"{base}_{number}"
        taken.add(candidate.lower())
        chosen[name] = candidate
    return chosen


def check_folder(folder: str, setting: str) -> None:
    """ValueError unless ``folder`` (absolute; ``setting`` as typed) is a folder the bake can write
    into or create: checked before any bake is touched."""
    if not setting.strip():
        raise ValueError("the Cache folder is empty: set it (Physics properties > Wet Cloth > Scene > Cache "
                         "folder), e.g. //wetcloth_cache for a folder beside the .blend file")
    existing = os.path.abspath(folder)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise ValueError(f"the Cache folder {setting!r} cannot be made: {existing} is a file; choose another "
                         "folder (Physics properties > Wet Cloth > Scene > Cache folder)")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"the Cache folder {setting!r} cannot be written: no permission in {existing}; choose "
                         "another folder (Physics properties > Wet Cloth > Scene > Cache folder)")


def attach(obj, usd_path: str, prefix: str) -> None:
    """Play ``usd_path`` on ``obj``: a new cache file, the modifier first in the stack reading the points and
    their attributes (the cache's vertices are the object's, in its order), the wet material."""
    detach(obj, delete_files=False)
    before = set(bpy.data.cache_files)
    bpy.ops.cachefile.open(filepath=usd_path)
    cache = next(c for c in bpy.data.cache_files if c not in before)
    cache.name = f"Wet Cloth {obj.name}"
    cache.filepath = _relative(usd_path)
    modifier = obj.modifiers.new(MODIFIER, "MESH_SEQUENCE_CACHE")
    modifier.cache_file = cache
    modifier.object_path = f"/wetcloth/{prefix}"
    modifier.read_data = {"VERT", "ATTRIBUTES"}  # positions and wetness: the object keeps its faces and UVs
    obj.modifiers.move(len(obj.modifiers) - 1, 0)
    if not any(slot.material for slot in obj.material_slots):
        from wetcloth.exporter.blender_loader import make_material

        material = make_material()
        if obj.material_slots:
            obj.material_slots[0].material = material
        else:
            obj.data.materials.append(material)


def detach(obj, delete_files: bool = True) -> list[str]:
    """Remove the bake from ``obj``: the modifier, its cache file and (``delete_files``) the cache's
    own files (the sequence frames.json describes, nothing else).  The files deleted."""
    modifier = cache_modifier(obj)
    if modifier is None:
        return []
    path, cache = cache_path(obj), modifier.cache_file
    obj.modifiers.remove(modifier)
    if cache is not None and not any(getattr(m, "cache_file", None) == cache for o in bpy.data.objects
                                     for m in o.modifiers):
        # (bpy.ops.cachefile.open leaves it a user more than its modifiers.)  Blender lets go of the
        # USD file once the cache file is gone and the depsgraph updated; USD would refuse to
        # create the file anew while it is open.
        bpy.data.batch_remove([cache])
    deleted = []
    if delete_files and path and os.path.isdir(os.path.dirname(path)):
        folder = os.path.dirname(path)
        for file in sequence_files(folder):
            file.unlink()
            deleted.append(str(file))
        if not os.listdir(folder):
            os.rmdir(folder)
    return deleted


def release(obj, usd_path: str) -> None:
    """Before ``obj``'s bake writes ``usd_path``: remove its previous bake and that of any object playing
    ``usd_path`` (a duplicate's), so that Blender lets go of the file: files kept where the new bake replaces
    them, deleted where ``obj``'s previous bake lies elsewhere (the cloth renamed since) and no other object
    plays it."""
    target = os.path.normpath(usd_path)
    previous = cache_path(obj)
    orphaned = previous not in (None, target) and not any(
        cache_path(other) == previous for other in bpy.data.objects if other != obj)
    for other in bpy.data.objects:
        if other == obj or cache_path(other) == target:
            detach(other, delete_files=other == obj and orphaned)
    bpy.context.evaluated_depsgraph_get().update()


def missing_caches() -> list[tuple[str, str]]:
    """(object, absolute path) of every baked cloth whose USD file is not on disk."""
    found = []
    for obj in bpy.data.objects:
        path = cache_path(obj)
        if path is not None and not os.path.isfile(path):
            found.append((obj.name, path))
    return found


def describe(missing) -> list[str]:
    return [f"Wet Cloth: the cache of {name!r} is missing: {path}; the cloth would stand still. Put the file "
            "back, or bake again (Physics > Wet Cloth > Bake)" for name, path in missing]


@persistent
def check_caches(*_args) -> None:
    """load_post: say in the interface, on standard error and to scripts which caches are missing."""
    missing = missing_caches()
    bpy.app.driver_namespace[MISSING] = missing
    if not missing:
        return
    lines = describe(missing)
    for line in lines:
        print(f"ERROR: {line}", file=sys.stderr)
    if bpy.app.background:
        return

    def popup():
        wm = bpy.context.window_manager
        if wm is not None and wm.windows:
            wm.popup_menu(lambda menu, _context: [menu.layout.label(text=line) for line in lines],
                          title="Wet Cloth: cache missing", icon="ERROR")

    bpy.app.timers.register(popup, first_interval=0.5)


def register() -> None:
    bpy.app.handlers.load_post.append(check_caches)


def unregister() -> None:
    if check_caches in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(check_caches)
