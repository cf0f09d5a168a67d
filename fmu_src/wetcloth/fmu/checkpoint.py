"""An FMU state of one unit (``fmi2GetFMUstate``), its bytes (``fmi2SerializeFMUstate``), the checks before restoring it.

A ``Checkpoint`` holds what the unit needs to continue exactly: its variable values, the values
it refused, whether it was initialized, the start time, the frame counter and the leaves of
``Simulation.snapshot()`` (state arrays, step control, ...).  The snapshot is taken generically:
every key but ``scene`` is a number, a string, a numpy array or a dataclass of those (then its
fields are leaves ``key.field``); no list of keys is written here, so the core may add some.

Bytes, version 1 (all integers little-endian)::

    19 bytes   magic "wetcloth-fmu-state\\n"
    uint16     format version (1)
    32 bytes   SHA-256 of everything that follows
    uint32     header length H
    H bytes    header, UTF-8 JSON: {"wetcloth": version, "scene_id": hex digest of the fixed
               parameters, "scene": {name: value} or null, "unit": {"values", "refused",
               "initialized", "start_time", "frames"}, "leaves": {key: {"kind": "float"|"int"|
               "bool"|"str", "value": v} or {"kind": "array", "dtype": "<f8", "shape": [...],
               "offset": bytes into the data, "nbytes": n}}}
    the rest   the arrays' raw data, C order, in the dtypes named

Reading runs no code (no pickle): JSON, then raw little-endian numbers of whitelisted dtypes, each
bound-checked against the data.  Anything else is refused with ``StateError``.  The SHA-256 has no
key (anyone can recompute it), so ``fitting_simulation`` also checks what a state holds, as a
parameter is checked: a start time within +-MAX_TIME s, the running unit's grid, and contents the
cloth can be in (``Simulation.check_snapshot``), all before anything changes.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

from wetcloth.errors import ParameterError
from wetcloth.fmu.vocabulary import check_variable
from wetcloth.scene import INPUT, PARAMETERS, Scene, from_dict
from wetcloth._core import MAX_TIME
from wetcloth.simulation import Simulation

MAGIC = b"wetcloth-fmu-state\n"
VERSION = 1
_PREAMBLE = struct.Struct("<H32sI")  # version, SHA-256 of the rest, header length
#: Array dtypes a state may hold (little-endian or byte-order free).
DTYPES = ("<f8", "<f4", "<i8", "<i4", "<u8", "|b1")
MAX_DIMENSIONS = 8


class StateError(ValueError):
    """Bytes or an object that are not an FMU state this unit wrote, or that do not fit its simulation."""


@dataclass(frozen=True)
class Checkpoint:
    """One unit's FMU state: plain values, and the snapshot's leaves of its simulation (if started)."""

    values: dict[str, Any]  # parameter and input values, by variable name
    refused: dict[str, str]  # variable -> why its last value was refused (pending error)
    initialized: bool
    start_time: float  # s, the master's time of the simulation's t = 0
    frames: int  # mesh frames written
    scene: Scene | None  # the simulation's scene (None before initialization)
    leaves: dict[str, Any]  # Simulation.snapshot() without "scene", dataclasses flattened


def scene_id(scene: Scene) -> str:
    """Identity of a scene: SHA-256 of its fixed parameters, its colliders' and keys' fields among them (inputs
    may change during a run)."""
    fixed = {name: value for name, value in scene.to_dict().items()
             if name not in PARAMETERS or PARAMETERS[name].metadata["fmu"] != INPUT}
    return hashlib.sha256(json.dumps(fixed, sort_keys=True).encode()).hexdigest()


# ------------------------------------------------------------------------------------ snapshot leaves
def leaves_of(snapshot: dict) -> dict[str, Any]:
    """The snapshot's values but the scene, a dataclass value (the core's ``State``) as its fields."""
    leaves = {}
    for key, value in snapshot.items():
        if key == "scene":
            continue
        if dataclasses.is_dataclass(value):
            leaves |= {f"{key}.{f.name}": getattr(value, f.name) for f in dataclasses.fields(value)}
        else:
            leaves[key] = value
    return leaves


def snapshot_from(leaves: dict[str, Any], scene: Scene, template: dict) -> dict:
    """A snapshot for ``Simulation.restore``: ``leaves`` put back in the shape of the live ``template``
    (arrays copied, so that the checkpoint can be restored again)."""
    snapshot = {"scene": scene}
    for key, value in template.items():
        if key == "scene":
            continue
        if dataclasses.is_dataclass(value):
            snapshot[key] = dataclasses.replace(value, **{f.name: _copy(leaves[f"{key}.{f.name}"])
                                                           for f in dataclasses.fields(value)})
        else:
            snapshot[key] = _copy(leaves[key])
    return snapshot


def _copy(value):
    return value.copy() if isinstance(value, np.ndarray) else value


def _kind(value) -> tuple:
    """What a leaf is, as compared between a state and a live snapshot."""
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.str, value.shape)
    if isinstance(value, (bool, np.bool_)):
        return ("bool",)
    if isinstance(value, (int, np.integer)):
        return ("int",)
    if isinstance(value, (float, np.floating)):
        return ("float",)
    if isinstance(value, str):
        return ("str",)
    raise StateError(f"a snapshot value of type {type(value).__name__} cannot be part of an FMU state")


def check_leaves(leaves: dict[str, Any], live: dict[str, Any]) -> None:
    """StateError unless ``leaves`` has the keys, kinds, dtypes and shapes of the ``live`` snapshot's leaves."""
    if set(leaves) != set(live):
        missing, extra = sorted(set(live) - set(leaves)), sorted(set(leaves) - set(live))
        raise StateError(f"the state does not fit this simulation: missing {missing or 'nothing'}, "
                         f"unknown {extra or 'nothing'}")
    for key in sorted(live):
        if _kind(leaves[key]) != _kind(live[key]):
            raise StateError(f"the state's {key!r} is {_describe(leaves[key])}, this simulation's is {_describe(live[key])}")


def _describe(value) -> str:
    kind = _kind(value)
    return f"an array of {kind[1]} {kind[2]}" if kind[0] == "array" else f"a {kind[0]}"


# ------------------------------------------------------------------------------------ fit to a unit
def fitting_simulation(state, names: set[str], sim: Simulation | None = None) -> Simulation | None:
    """The simulation ``state`` restores into (``sim`` if it runs the same scene, else a new one; None
    before initialization), after checking everything: that ``state`` is a Checkpoint of a unit with
    the variables ``names``, holding valid values consistent with its scene, a start time within
    +-MAX_TIME s, the grid of ``sim`` (a running unit's grid is fixed), and leaves that fit that
    simulation's snapshot, with contents the cloth can be in (``Simulation.check_snapshot``);
    StateError otherwise.  Nothing is changed."""
    if not isinstance(state, Checkpoint):
        raise StateError(f"not a WetCloth FMU state: a {type(state).__name__}")
    if not (isinstance(state.start_time, (int, float)) and abs(state.start_time) <= MAX_TIME):
        raise StateError(f"the state's start time {state.start_time!r} s is not a finite number within "
                         f"+-{MAX_TIME:g} s")
    if set(state.values) != names:
        raise StateError(f"the state is of a unit with other variables (missing {sorted(names - set(state.values))}, "
                         f"unknown {sorted(set(state.values) - names)})")
    try:
        for name, value in state.values.items():
            check_variable(name, value)
    except ParameterError as exc:
        raise StateError(f"the state holds an invalid value: {exc}") from None
    if not set(state.refused) <= names:
        raise StateError("the state refuses variables this unit does not have")
    if not state.initialized:
        return None
    if state.scene is None:
        raise StateError("the state of an initialized unit has no scene")
    scene = state.scene.to_dict()
    if any(scene[name] != value for name, value in state.values.items() if name in scene):
        raise StateError("the state's variable values differ from its simulation's scene")
    if sim is not None and (state.scene.nx, state.scene.ny) != (sim.scene.nx, sim.scene.ny):
        raise StateError(f"the state is of a cloth of nx x ny = {state.scene.nx} x {state.scene.ny} particles, this "
                         f"unit runs {sim.scene.nx} x {sim.scene.ny} (fixed once it is initialized)")
    if sim is None or scene_id(sim.scene) != scene_id(state.scene):
        try:
            sim = Simulation(state.scene)
        except ParameterError as exc:
            raise StateError(f"the state's scene is not valid: {exc}") from None
    live = sim.snapshot()
    check_leaves(state.leaves, leaves_of(live))
    try:
        sim.check_snapshot(snapshot_from(state.leaves, state.scene, live))
    except ValueError as exc:
        raise StateError(str(exc)) from None
    return sim


# ------------------------------------------------------------------------------------ bytes
def _scalar(value):
    """A leaf scalar as a plain Python value and its kind."""
    kind = _kind(value)[0]
    return {"bool": bool, "int": int, "float": float, "str": str}[kind](value), kind


def to_bytes(checkpoint: Checkpoint) -> bytes:
    """The checkpoint as bytes (the layout in this module's docstring)."""
    leaves, chunks, offset = {}, [], 0
    for key, value in checkpoint.leaves.items():
        if isinstance(value, np.ndarray):
            array = np.ascontiguousarray(value, dtype=value.dtype.newbyteorder("<"))
            if array.dtype.str not in DTYPES:
                raise StateError(f"snapshot array {key!r} has dtype {array.dtype.str}, not one of {DTYPES}")
            data = array.tobytes()
            leaves[key] = {"kind": "array", "dtype": array.dtype.str, "shape": list(array.shape),
                           "offset": offset, "nbytes": len(data)}
            chunks.append(data)
            offset += len(data)
        else:
            plain, kind = _scalar(value)
            leaves[key] = {"kind": kind, "value": plain}
    scene = checkpoint.scene
    header = {
        "wetcloth": _version(),
        "scene_id": scene_id(scene) if scene is not None else None,
        "scene": scene.to_dict() if scene is not None else None,
        "unit": {"values": checkpoint.values, "refused": checkpoint.refused, "initialized": checkpoint.initialized,
                 "start_time": checkpoint.start_time, "frames": checkpoint.frames},
        "leaves": leaves,
    }
    text = json.dumps(header, allow_nan=True).encode("utf-8")
    body = struct.pack("<I", len(text)) + text + b"".join(chunks)
    return MAGIC + struct.pack("<H32s", VERSION, hashlib.sha256(body).digest()) + body


def from_bytes(data: bytes) -> Checkpoint:
    """The checkpoint in ``data``; StateError for anything that is not a state written by ``to_bytes``."""
    data = bytes(data)
    if not data.startswith(MAGIC) or len(data) < len(MAGIC) + _PREAMBLE.size:
        raise StateError(f"not a serialized WetCloth FMU state ({len(data)} bytes without the "
                         f"{MAGIC.strip().decode()!r} header)")
    version, digest, header_length = _PREAMBLE.unpack_from(data, len(MAGIC))
    if version != VERSION:
        raise StateError(f"serialized WetCloth FMU state of format version {version}; this unit reads version {VERSION}")
    body = data[len(MAGIC) + 34:]
    if hashlib.sha256(body).digest() != digest:
        raise StateError("serialized WetCloth FMU state is corrupt or truncated (its SHA-256 checksum does not match)")
    if header_length > len(body) - 4:
        raise StateError("serialized WetCloth FMU state is truncated (header longer than the data)")
    arrays = memoryview(body)[4 + header_length:]
    try:
        header = json.loads(body[4:4 + header_length].decode("utf-8"))
        return _checkpoint(header, arrays)
    except StateError:
        raise
    except ParameterError as exc:
        raise StateError(f"serialized WetCloth FMU state holds an invalid scene: {exc}") from None
    except (ValueError, TypeError, KeyError, AttributeError, RecursionError, OverflowError) as exc:
        raise StateError(f"serialized WetCloth FMU state is malformed ({type(exc).__name__}: {exc})") from None


def _checkpoint(header: dict, arrays: memoryview) -> Checkpoint:
    unit = header["unit"]
    values, refused = dict(unit["values"]), dict(unit["refused"])
    if not all(isinstance(k, str) and isinstance(v, (str, int, float)) and not isinstance(v, bool)
               for k, v in values.items()):
        raise StateError("serialized WetCloth FMU state: variable values must be numbers or strings")
    if not all(isinstance(k, str) and isinstance(v, str) for k, v in refused.items()):
        raise StateError("serialized WetCloth FMU state: refusals must be text")
    initialized, start_time, frames = unit["initialized"], unit["start_time"], unit["frames"]
    if not (isinstance(initialized, bool) and isinstance(start_time, float) and math.isfinite(start_time)
            and isinstance(frames, int) and not isinstance(frames, bool) and frames >= 0):
        raise StateError("serialized WetCloth FMU state: bad unit record (initialized, start_time, frames)")
    scene = None
    if header["scene"] is not None:
        scene = from_dict(dict(header["scene"]))
        if scene_id(scene) != header["scene_id"]:
            raise StateError("serialized WetCloth FMU state: its scene does not match its scene identity")
    leaves = {str(key): _leaf(str(key), dict(spec), arrays) for key, spec in dict(header["leaves"]).items()}
    return Checkpoint(values=values, refused=refused, initialized=initialized, start_time=start_time,
                      frames=frames, scene=scene, leaves=leaves)


def _leaf(key: str, spec: dict, arrays: memoryview):
    kind = spec["kind"]
    if kind != "array":
        value = spec["value"]
        expected = {"bool": bool, "int": int, "float": float, "str": str}[kind]
        if type(value) is not expected and not (expected is float and type(value) is int):
            raise StateError(f"serialized WetCloth FMU state: {key!r} is not a {kind}")
        return expected(value)
    dtype, shape, offset, nbytes = spec["dtype"], spec["shape"], spec["offset"], spec["nbytes"]
    if dtype not in DTYPES:
        raise StateError(f"serialized WetCloth FMU state: {key!r} has dtype {dtype!r}, not one of {DTYPES}")
    if not (isinstance(shape, list) and len(shape) <= MAX_DIMENSIONS
            and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape)):
        raise StateError(f"serialized WetCloth FMU state: {key!r} has a bad shape {shape!r}")
    if not (isinstance(offset, int) and isinstance(nbytes, int) and 0 <= offset and 0 <= nbytes
            and offset + nbytes <= len(arrays) and nbytes == math.prod(shape) * np.dtype(dtype).itemsize):
        raise StateError(f"serialized WetCloth FMU state: {key!r} lies outside its data")
    return np.frombuffer(arrays[offset:offset + nbytes], dtype=dtype).reshape(shape).astype(dtype.replace("<", "="))


def _version() -> str:
    from wetcloth import __version__

    return __version__
