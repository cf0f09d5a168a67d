"""A scene built into a unit (``wetcloth build-fmu --scene SCENE``): its parameter values become the
variables' start values, its colliders are built in (their number, shapes and files; their number fields are
parameters, ``vocabulary.collider_specs``, starting as the scene has them), its grip keys and collider keys
too (fixed: they are not variables), and its mesh files (``cloth_mesh``, mesh colliders' ``file``) go into the
unit's resources.

The builder writes ``resources/wetcloth_scene.json``: ``{"starts": {name: value}, "vertices": n or null,
"colliders": [{field: value}], "grip_keys": [{"time": s, "x": m, "y": m, "z": m}], "collider_keys":
[{"collider": k, "time": s, "x": m, "y": m, "z": m, "rx": deg, "ry": deg, "rz": deg}], "faces": [[vertex, ...]],
"uv": [[u, v]]}``.  A mesh file is packed as ``resources/meshes/<digest>/<file name>``
and named by that relative path, which the unit finds in its resources (``mesh_file.SEARCH_FOLDERS``);
the digest in the path means that two units holding the same relative path hold the same file.
``vertices`` (a mesh cloth's vertex count) sizes the FMI 3.0 unit's array outputs instead of the
grid's ``ny`` and ``nx``; ``faces`` and ``uv`` (a mesh cloth's, else empty) are its constant array outputs.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: The file in the unit's resources folder.
SCENE_NAME = "wetcloth_scene.json"
#: Where mesh files go in the resources folder.
MESH_FOLDER = "meshes"


@dataclass(frozen=True)
class PackedScene:
    """Start values by scene parameter, a mesh cloth's vertex count (else None), the colliders (their fields,
    mesh files by their packed paths), the grip keys and the collider keys (their fields), when building, the
    mesh files to pack (packed path -> file), and a mesh cloth's ``faces`` (k rows of 3 or 4 vertex indices)
    and ``uv`` (n rows of 2) as its exported frames have them (``exporter.cloth_faces``; else empty)."""

    starts: dict[str, Any]
    vertices: int | None = None
    colliders: tuple = ()
    grip_keys: tuple = ()
    files: dict = field(default_factory=dict)
    collider_keys: tuple = ()
    faces: tuple = ()
    uv: tuple = ()

    def fixtures(self) -> dict:
        """What of the scene is built in beside the variables: ``colliders``, ``grip_keys`` and
        ``collider_keys``, for ``scene.from_dict``."""
        return {"colliders": list(self.colliders), "grip_keys": list(self.grip_keys),
                "collider_keys": list(self.collider_keys)}

    @property
    def mesh(self) -> Path | None:
        """The cloth's mesh file being packed, if any."""
        return self.files.get(self.starts.get("cloth_mesh"))


def _packed_path(path: Path) -> str:
    """Where mesh file ``path`` goes in the resources (by its contents' digest)."""
    return f"{MESH_FOLDER}/{hashlib.sha256(path.read_bytes()).hexdigest()[:16]}/{path.name}"


def fixtures_of(scene) -> tuple[tuple, tuple, dict]:
    """A ``Scene``'s colliders and grip keys (their fields) as a unit built from it carries them, and the
    mesh colliders' files to pack (packed path -> file); its collider keys: ``collider_keys_of``."""
    from wetcloth.mesh_file import locate

    files, colliders = {}, []
    for collider in scene.colliders:
        fields = dataclasses.asdict(collider)
        if collider.shape == "mesh":
            source = locate(collider.file)
            fields["file"] = _packed_path(source)
            files[fields["file"]] = source
        colliders.append(fields)
    return tuple(colliders), tuple(dataclasses.asdict(key) for key in scene.grip_keys), files


def collider_keys_of(scene) -> tuple:
    """A ``Scene``'s collider keys (their fields) as a unit built from it carries them."""
    return tuple(dataclasses.asdict(key) for key in scene.collider_keys)


def _built(colliders) -> tuple:
    """What of colliders (their fields) is built into a unit: each one's shape and file (its number fields
    are the unit's parameters, ``vocabulary.COLLIDER_VARIABLES``)."""
    return tuple((c["shape"], c["file"]) for c in colliders)


def check_carries(fmu: str | Path, resources: str | Path, scene) -> None:
    """ValueError unless the unit ``fmu`` (its extracted ``resources`` folder) carries ``scene``'s colliders
    (their number, shapes and files), grip keys and collider keys (built in by ``build-fmu --scene``: they are
    not variables)."""
    packed = load(resources) or PackedScene({})
    colliders, grip_keys, _ = fixtures_of(scene)
    moves = collider_keys_of(scene)
    if (_built(packed.colliders), packed.grip_keys, packed.collider_keys) != (_built(colliders), grip_keys, moves):
        have = f"{len(packed.colliders)} colliders and {len(packed.grip_keys)} grip keys"
        want = f"{len(colliders)} and {len(grip_keys)}"
        if packed.collider_keys or moves:
            have += f" ({len(packed.collider_keys)} collider keys)"
            want += f" ({len(moves)} collider keys)"
        raise ValueError(f"the FMU {fmu} carries {have}, not this scene's ({want}, or other shapes, files or key "
                         f"fields): colliders' shapes and files and the keys are built into a unit, not variables; "
                         f"build one from the scene ('wetcloth build-fmu --scene SCENE'), and vary them with engine "
                         f"'python'")


def pack(scene_path: str | Path) -> PackedScene:
    """The packed form of scene file ``scene_path`` (a path or preset name), checked whole; a
    ParameterError (ConfigError) for a scene the unit cannot start from."""
    from wetcloth.mesh_file import is_mesh, locate
    from wetcloth.scene import PARAMETERS, RESERVED_KEYS, from_dict, read_scene_file
    from wetcloth.topology import build_topology

    data = read_scene_file(scene_path)
    scene = from_dict({k: v for k, v in data.items() if k not in RESERVED_KEYS})
    starts = {name: getattr(scene, name) for name in PARAMETERS}
    colliders, grip_keys, files = fixtures_of(scene)
    vertices, faces, uv = None, (), ()
    if is_mesh(scene.cloth_mesh):
        from wetcloth.exporter import cloth_faces

        mesh = locate(scene.cloth_mesh)
        starts["cloth_mesh"] = _packed_path(mesh)
        files[starts["cloth_mesh"]] = mesh
        topology = build_topology(scene)
        vertices = topology.n
        _, uvs, file_faces = cloth_faces(topology)
        faces, uv = tuple(map(tuple, file_faces.tolist())), tuple(map(tuple, uvs.astype(float).tolist()))
    return PackedScene(starts, vertices=vertices, colliders=tuple(colliders), grip_keys=grip_keys, files=files,
                       collider_keys=collider_keys_of(scene), faces=faces, uv=uv)


def text(packed: PackedScene) -> str:
    """The contents of ``SCENE_NAME``."""
    return json.dumps({"starts": packed.starts, "vertices": packed.vertices, **packed.fixtures(),
                       "faces": packed.faces, "uv": packed.uv}, indent=1)


def write(packed: PackedScene, resources: Path) -> list[Path]:
    """Write ``packed`` into a unit's ``resources`` folder; the files written (the scene file first)."""
    target = resources / SCENE_NAME
    target.write_text(text(packed), encoding="utf-8")
    written = [target]
    for relative, source in packed.files.items():
        copy = resources / relative
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, copy)
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
    return PackedScene(dict(data["starts"]), data.get("vertices"), tuple(data.get("colliders", ())),
                       tuple(data.get("grip_keys", ())), collider_keys=tuple(data.get("collider_keys", ())),
                       faces=tuple(map(tuple, data.get("faces", ()))), uv=tuple(map(tuple, data.get("uv", ()))))
