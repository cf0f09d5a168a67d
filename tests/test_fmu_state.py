"""FMU state: get/set and serialize cover the whole unit, so rolled-back and resumed runs repeat exactly;
a state is plain numbers and text, and whatever bytes or objects a master passes that this unit did
not write are refused without harm (each in a child process)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_fmu_support import SMALL, Unit, extracted_fmu, run_child

from wetcloth.simulation import OUTPUT_NAMES

#: A scene whose state has everything moving: falling, tilted, absorbing, with an input change.
VALUES = SMALL | {"initial_tilt": 30.0, "absorption_rate": 0.5}


def run(unit: Unit, steps: int, h: float = 0.05, level_at: int | None = 3) -> list[tuple]:
    """Step ``steps`` times, raising the water level at step ``level_at``; outputs after every step."""
    rows = []
    for k in range(steps):
        if k == level_at:
            unit.set(water_level=0.02)
        assert unit.step(h) == 0
        rows.append(tuple(unit.outputs()[n] for n in OUTPUT_NAMES))
    return rows


def test_restored_state_repeats_the_run_exactly():
    unit = Unit(VALUES)
    try:
        run(unit, 6, level_at=None)
        t_saved = unit.time
        state = unit.fmu.getFMUstate()
        first = run(unit, 10)
        unit.fmu.setFMUstate(state)
        unit.time = t_saved
        second = run(unit, 10)
        unit.fmu.setFMUstate(state)  # a state can be restored again
        unit.time = t_saved
        third = run(unit, 10)
        unit.fmu.freeFMUstate(state)
    finally:
        unit.close()
    assert first == second == third  # bit for bit: the whole state, step controller included, came back
    assert len(set(first)) == len(first)  # and the run was not standing still


def test_restore_brings_back_inputs_set_after_the_snapshot():
    unit = Unit(VALUES)
    try:
        state = unit.fmu.getFMUstate()
        unit.set(water_level=0.3)
        unit.step(0.1)
        unit.fmu.setFMUstate(state)
        unit.time = 0.0
        assert unit.get("water_level") == 0.0
        unit.fmu.freeFMUstate(state)
    finally:
        unit.close()


def test_serialized_state_resumes_in_a_fresh_instance():
    uninterrupted = Unit(VALUES, name="whole")
    try:
        run(uninterrupted, 6, level_at=None)
        saved_time = uninterrupted.time
        saved = uninterrupted.fmu.serializeFMUstate(uninterrupted.fmu.getFMUstate())
        expected = run(uninterrupted, 10)
    finally:
        uninterrupted.close()
    assert isinstance(saved, bytes) and len(saved) > 0

    # A new instance with other parameters (the same grid: a running unit's grid is fixed): the
    # deserialized state replaces all of it.
    fresh = Unit(SMALL | {"initial_tilt": 5.0, "absorption_rate": 0.1, "water_level": 0.1}, name="resumed")
    try:
        state = fresh.fmu.deSerializeFMUstate(saved)
        fresh.fmu.setFMUstate(state)
        fresh.fmu.freeFMUstate(state)
        fresh.time = saved_time  # the master resumes from the saved communication point
        assert fresh.get("initial_tilt") == VALUES["initial_tilt"] and fresh.get("water_level") == 0.0
        resumed = run(fresh, 10)
    finally:
        fresh.close()
    assert resumed == expected


def test_state_of_one_instance_does_not_leak_into_another():
    a, b = Unit(VALUES, name="a"), Unit(VALUES, name="b")
    try:
        run(a, 4, level_at=None)
        state = a.fmu.getFMUstate()
        before = b.outputs()
        run(a, 4)
        assert b.outputs() == before
        a.fmu.freeFMUstate(state)
        assert np.isfinite(list(a.outputs().values())).all()
    finally:
        a.close()
        b.close()


# ------------------------------------------------------------------------------------------ bad states
CHILD_BAD_STATES = r"""
import ctypes, json, math, os, pickle, sys
sys.path.insert(0, sys.argv[2])
from pathlib import Path
import fmpy
import numpy as np
import test_fmu_support as support
from fmpy.fmi2 import fmi2FMUstate
from wetcloth.fmu import checkpoint
support._BUILT["dir2"], support._BUILT["md2"] = Path(sys.argv[1]), fmpy.read_model_description(sys.argv[1])
marker = Path(sys.argv[3])

class Payload:  # what a crafted pickle state would do on loading: create a file
    def __reduce__(self):
        return (open, (str(marker), "w"))

def valid_bytes():
    unit = support.Unit(support.SMALL, name="source")
    unit.step(0.1)
    data = unit.fmu.serializeFMUstate(unit.fmu.getFMUstate())
    unit.close()
    return data

good = valid_bytes()
decoded = checkpoint.from_bytes(good)
missing_leaf = checkpoint.to_bytes(checkpoint.Checkpoint(**{**decoded.__dict__, "leaves": {
    k: v for k, v in decoded.leaves.items() if k != "anchor"}}))
wrong_shape = checkpoint.to_bytes(checkpoint.Checkpoint(**{**decoded.__dict__, "leaves": {
    k: (v[:, :-1] if k == "state.pos" else v) for k, v in decoded.leaves.items()}}))
bad_value = checkpoint.to_bytes(checkpoint.Checkpoint(**{**decoded.__dict__, "values": {
    **decoded.values, "mesh_format": "stl"}}))
flipped = bytearray(good); flipped[len(good) // 2] ^= 0xFF
keep = []  # Python objects whose addresses a master passes as FMU states

def pointer(obj):
    keep.append(obj)
    return fmi2FMUstate(id(obj))

def freed_state(frees):
    state = unit.fmu.getFMUstate()
    for _ in range(frees):
        unit.fmu.freeFMUstate(state)
    return state

def target(payload):  # a freed state of this unit, raw memory (as another unit's state), or a Python object
    if payload in ("freed", "freed_twice"):
        return freed_state(1 if payload == "freed" else 2)
    if payload == "raw_memory":
        buffer = ctypes.create_string_buffer(b"\x01" * 256)
        keep.append(buffer)
        return fmi2FMUstate(ctypes.addressof(buffer))
    return pointer(payload)

SEQUENCES = {
    "random": [("deserialize", os.urandom(4096))],
    "empty": [("deserialize", b"")],
    "one_byte": [("deserialize", b"\x00")],
    "truncated": [("deserialize", good[: len(good) // 2])],
    "flipped_byte": [("deserialize", bytes(flipped))],
    "pickle_payload": [("deserialize", pickle.dumps(Payload()))],
    "magic_then_pickle": [("deserialize", checkpoint.MAGIC + pickle.dumps(Payload()))],
    "missing_leaf": [("deserialize", missing_leaf)],
    "wrong_shape": [("deserialize", wrong_shape)],
    "invalid_value": [("deserialize", bad_value)],
    "twice_then_step": [("deserialize", b"\x01"), ("deserialize", os.urandom(64))],
    "set_a_dict": [("set", {"format": "wetcloth-fmu-state/1"})],
    "set_missing_keys": [("set", checkpoint.Checkpoint(**{**decoded.__dict__, "leaves": {}}))],
    "serialize_a_list": [("serialize", [1, 2, 3])],
    "set_freed": [("set", "freed")],
    "set_freed_twice": [("set", "freed_twice")],
    "serialize_freed": [("serialize", "freed")],
    "set_raw_memory": [("set", "raw_memory")],
    "serialize_raw_memory": [("serialize", "raw_memory")],
}
for name, calls in SEQUENCES.items():
    unit = support.Unit(support.SMALL, name=name)
    unit.step(0.1)
    before = unit.outputs()
    statuses = []
    for kind, payload in calls:
        if kind == "deserialize":
            statuses.append(unit._call(unit.fmu.deSerializeFMUstate, payload))
        elif kind == "set":
            statuses.append(unit._call(unit.fmu.setFMUstate, target(payload)))
        else:
            statuses.append(unit._call(unit.fmu.serializeFMUstate, target(payload)))
    after_refusal = unit.outputs()
    step = unit.step(0.1)
    record = {"case": name, "statuses": statuses, "step": step, "unchanged": after_refusal == before,
              "finite": all(math.isfinite(v) for v in unit.outputs().values()), "errors": unit.errors()}
    # and a state this unit wrote is still accepted afterwards
    state = unit.fmu.deSerializeFMUstate(good)
    unit.fmu.setFMUstate(state)
    unit.fmu.freeFMUstate(state)
    unit.time = 0.1
    record["restored_step"] = unit.step(0.1)
    unit.close()
    print(json.dumps(record), flush=True)
print(json.dumps({"case": "marker", "exists": marker.exists()}))
"""


@pytest.fixture(scope="module")
def bad_states(tmp_path_factory):
    directory, _ = extracted_fmu()
    marker = tmp_path_factory.mktemp("state") / "payload_ran"
    records, done = run_child(CHILD_BAD_STATES, directory, Path(__file__).parent, marker)
    return {r["case"]: r for r in records} | {"stderr": done.stderr}


BAD_STATES = ["random", "empty", "one_byte", "truncated", "flipped_byte", "pickle_payload", "magic_then_pickle",
              "missing_leaf", "wrong_shape", "invalid_value", "twice_then_step", "set_a_dict", "set_missing_keys",
              "serialize_a_list", "set_freed", "set_freed_twice", "serialize_freed", "set_raw_memory",
              "serialize_raw_memory"]


@pytest.mark.parametrize("case", BAD_STATES)
def test_a_state_this_unit_did_not_write_is_refused_and_the_unit_still_steps(bad_states, case):
    """Refused with an error status (pythonfmu's only one there is Fatal) and a message; the instance
    keeps its state, steps on, and takes a good state afterwards; the host process survives."""
    record = bad_states[case]
    assert all(status >= 3 for status in record["statuses"]), record
    assert record["unchanged"] and record["finite"], record
    assert record["step"] == 0 and record["restored_step"] == 0, record


def test_refusals_name_the_reason(bad_states):
    stderr = bad_states["stderr"]  # the class-level decoder logs through Python's logging
    for reason in ("without the 'wetcloth-fmu-state' header", "checksum does not match",
                   "missing ['anchor']", "'state.pos' is an array of <f8 (3, 80)", "'mesh_format'"):
        assert reason in stderr, reason
    for case in ("set_a_dict", "set_missing_keys", "set_freed", "set_freed_twice", "set_raw_memory"):
        assert "not a WetCloth FMU state: a pointer this unit did not hand out, or one already freed" in \
            "\n".join(bad_states[case]["errors"]), case
    assert stderr.count("FMU state not serialized: not a WetCloth FMU state") >= 3


def test_a_crafted_pickle_state_runs_no_code(bad_states):
    assert bad_states["marker"]["exists"] is False


# ------------------------------------------------------------------------------------------ the format
def test_the_byte_format_is_generic_over_the_snapshot_and_needs_no_pickle(monkeypatch):
    """Keys the core may add (a multistep history array, an integer) round-trip without code changes;
    decoding works with pickle disabled; arrays come back equal and writable."""
    import pickle

    import wetcloth
    from wetcloth.fmu import checkpoint

    sim = wetcloth.Simulation(wetcloth.Scene(**SMALL))
    sim.advance(0.1)
    leaves = checkpoint.leaves_of(sim.snapshot()) | {"history": np.arange(12.0).reshape(2, 6), "order": 2,
                                                     "converged": True, "method": "bdf2"}
    state = checkpoint.Checkpoint(values={"nx": 9}, refused={}, initialized=True, start_time=0.0, frames=0,
                                  scene=sim.scene, leaves=leaves)
    data = checkpoint.to_bytes(state)
    monkeypatch.setattr(pickle, "loads", lambda *a, **k: pytest.fail("pickle used"))
    monkeypatch.setattr(pickle, "Unpickler", None)
    back = checkpoint.from_bytes(data)
    assert data.startswith(checkpoint.MAGIC) and back.scene == sim.scene and back.values == {"nx": 9}
    assert set(back.leaves) == set(leaves)
    for key, value in leaves.items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(back.leaves[key], value)
            assert back.leaves[key].flags.writeable
        else:
            assert back.leaves[key] == value and type(back.leaves[key]) is type(value), key
    checkpoint.check_leaves(back.leaves, leaves)  # same keys, kinds, dtypes and shapes as the live one
    with pytest.raises(checkpoint.StateError, match="missing \\['history'\\]"):
        checkpoint.check_leaves({k: v for k, v in back.leaves.items() if k != "history"}, leaves)


def test_a_state_names_its_scene_and_refuses_a_changed_one():
    import wetcloth
    from wetcloth.fmu import checkpoint

    scene = wetcloth.Scene(**SMALL)
    state = checkpoint.Checkpoint(values={}, refused={}, initialized=True, start_time=0.0, frames=0, scene=scene,
                                  leaves={})
    data = bytearray(checkpoint.to_bytes(state))
    assert checkpoint.scene_id(scene) == checkpoint.scene_id(scene.replace(water_level=0.3))  # inputs may change
    assert checkpoint.scene_id(scene) != checkpoint.scene_id(scene.replace(nx=10))
    # Change the scene inside the header and recompute the checksum: the identity no longer matches.
    text = bytes(data).replace(b'"nx": 9', b'"nx": 7')
    body = text[len(checkpoint.MAGIC) + 34:]
    forged = checkpoint.MAGIC + checkpoint.struct.pack("<H32s", checkpoint.VERSION,
                                                        checkpoint.hashlib.sha256(body).digest()) + body
    with pytest.raises(checkpoint.StateError, match="scene identity"):
        checkpoint.from_bytes(forged)


# ------------------------------------------------------------------------------------------ before initialization
CHILD_BEFORE_INIT = r"""
import json, sys
sys.path.insert(0, sys.argv[2])
from pathlib import Path
import fmpy
import test_fmu_support as support
support._BUILT["dir2"], support._BUILT["md2"] = Path(sys.argv[1]), fmpy.read_model_description(sys.argv[1])
source = support.Unit(support.SMALL, name="source")
source.step(0.1)
state = source.fmu.getFMUstate()
target = support.Unit(name="target", initialize=False)
target.fmu.setupExperiment(startTime=0.0)
restored = target._call(target.fmu.setFMUstate, state)
enter = target._call(target.fmu.enterInitializationMode)
exit_ = target._call(target.fmu.exitInitializationMode)
target.time = 0.1
print(json.dumps({"set": restored, "enter": enter, "exit": exit_, "kept": target.outputs() == source.outputs(),
                  "step": target.step(0.1), "errors": target.errors()}))
source.close()  # (freed while their Units' logger callbacks live)
target.close()
"""


def test_a_state_set_before_initialization_is_kept():
    """As the native unit: the restored unit is initialized; initializing it again is refused."""
    directory, _ = extracted_fmu()
    (record,), _ = run_child(CHILD_BEFORE_INIT, directory, Path(__file__).parent)
    assert record["set"] == 0 and record["kept"] and record["step"] == 0, record
    assert record["enter"] >= 3 and record["exit"] >= 3, record
    assert ("fmiEnterInitializationMode is not allowed in the initialized (stepping) state"
            in "\n".join(record["errors"]))
