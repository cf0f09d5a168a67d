"""A scene built into a unit (``wetcloth build-fmu --scene SCENE``): its parameter values become the
variables' start values, and its mesh file (``cloth_mesh``) goes into the unit's resources.

The builder writes ``resources/wetcloth_scene.json``: ``{"starts": {name: value}, "vertices": n or null}``.
A mesh file is packed as ``resources/meshes/<digest>/<file name>`` and ``cloth_mesh`` starts as that
relative path, which the unit finds in its resources (``mesh_file.SEARCH_FOLDERS``); the digest in the
path means that two units holding the same relative path hold the same file.  ``vertices`` (a mesh
cloth's vertex count) sizes the FMI 3.0 unit's array outputs instead of the grid's ``ny`` and ``nx``.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from wetcloth.errors import ParameterError

#: The file in the unit's resources folder.
SCENE_NAME = "wetcloth_scene.json"
#: Where mesh files go in the resources folder.
MESH_FOLDER = "meshes"


@dataclass(frozen=True)
class PackedScene:
    """Start values by scene parameter, a mesh cloth's vertex count (else None) and, when building, the
    mesh file to pack (else None)."""

    starts: dict[str, Any]
    vertices: int | None = None
    mesh: Path | None = None


def pack(scene_path: str | Path) -> PackedScene:
    """The packed form of scene file ``scene_path`` (a path or preset name), checked whole; a
    ParameterError (ConfigError) for a scene the unit cannot start from."""
    from wetcloth.mesh_file import is_mesh_path, locate
    from wetcloth.scene import PARAMETERS, RESERVED_KEYS, from_dict, read_scene_file
    from wetcloth.topology import build_topology

    data = read_scene_file(scene_path)
    scene = from_dict({k: v for k, v in data.items() if k not in RESERVED_KEYS})
    if scene.colliders:
        raise ParameterError("collider1", "a unit has no colliders yet (they are not FMU variables): run this "
                                          "scene with 'wetcloth run', or remove its [[collider]] tables")
    starts = {name: getattr(scene, name) for name in PARAMETERS}
    if not is_mesh_path(scene.cloth_mesh):
        return PackedScene(starts)
    mesh = locate(scene.cloth_mesh)
    digest = hashlib.sha256(mesh.read_bytes()).hexdigest()[:16]
    starts["cloth_mesh"] = f"{MESH_FOLDER}/{digest}/{mesh.name}"
    return PackedScene(starts, vertices=build_topology(scene).n, mesh=mesh)


def write(packed: PackedScene, resources: Path) -> list[Path]:
    """Write ``packed`` into a unit's ``resources`` folder; the files written (the scene file first)."""
    target = resources / SCENE_NAME
    target.write_text(json.dumps({"starts": packed.starts, "vertices": packed.vertices}, indent=1), encoding="utf-8")
    written = [target]
    if packed.mesh is not None:
        copy = resources / packed.starts["cloth_mesh"]
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(packed.mesh, copy)
        written.append(copy)
    return written


def load(resources: str | Path | None) -> PackedScene | None:
    """The scene packed into a unit's ``resources`` folder, or None (a unit built without --scene); makes
    the folder one where relative mesh paths are found."""
    if not resources:
        return None
    path = Path(resources) / SCENE_NAME
    if not path.is_file():
        return None
    from wetcloth import mesh_file

    data = json.loads(path.read_text(encoding="utf-8"))
    folder = Path(resources).resolve()
    if folder not in mesh_file.SEARCH_FOLDERS:
        mesh_file.SEARCH_FOLDERS.append(folder)
    return PackedScene(dict(data["starts"]), data.get("vertices"))
