"""Mesh frames from the FMU (one per communication point, through wetcloth.exporter), the folder that belongs
to the unit, and the demo."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from test_fmu_support import SMALL, Unit, built_fmu, extracted_fmu, run_child

import wetcloth
from wetcloth.exporter import ExportError, check_directory, open_sequence, sequence_files
from wetcloth.fmu.cosim import read_frame
from wetcloth.simulation import OUTPUT_NAMES

#: PLY frames store positions as float32: ~6e-8 relative, under a micrometre for a cloth within 1 m.
FLOAT32_M = 1e-6


@pytest.fixture(scope="module")
def fmu():
    return str(built_fmu())


def test_one_ply_frame_per_communication_point_matching_the_direct_run(fmu, tmp_path):
    frames = tmp_path / "frames"
    result = fmpy.simulate_fmu(fmu, stop_time=0.5, output_interval=0.1,
                               start_values=SMALL | {"mesh_output_dir": str(frames)})
    files = sorted(frames.glob("cloth_*.ply"))
    assert [f.name for f in files] == [f"cloth_{k:04d}.ply" for k in range(1, len(result) + 1)]
    sim = wetcloth.Simulation(wetcloth.Scene(**SMALL))
    for k, path in enumerate(files):
        if k:
            sim.advance(result["time"][k] - sim.time)
        positions, wetness, triangles = read_frame(path)
        np.testing.assert_allclose(positions, sim.positions, atol=FLOAT32_M)
        np.testing.assert_allclose(wetness, sim.wetness, atol=1e-6)
        # the frames hold quads (the export default), which trimesh triangulates on loading: the
        # simulation's triangles, some starting at another corner (orientation: tests/test_export.py)
        assert np.array_equal(np.sort(triangles, axis=1), np.sort(sim.triangles, axis=1))
    manifest = json.loads((frames / "frames.json").read_text())  # written when the unit terminates
    assert manifest["frame_count"] == len(result) and manifest["fps"] == pytest.approx(10.0)


def test_obj_frames_and_a_rerun_replaces_the_old_frames(fmu, tmp_path):
    frames = tmp_path / "frames"
    values = SMALL | {"mesh_output_dir": str(frames), "mesh_format": "obj"}
    fmpy.simulate_fmu(fmu, stop_time=0.3, output_interval=0.1, start_values=values)
    fmpy.simulate_fmu(fmu, stop_time=0.1, output_interval=0.1, start_values=values)
    assert sorted(f.name for f in frames.glob("cloth_*")) == ["cloth_0001.obj", "cloth_0002.obj"]


def test_a_rolled_back_run_rewrites_its_frames_and_drops_the_abandoned_ones(tmp_path):
    frames = tmp_path / "frames"
    unit = Unit(SMALL | {"mesh_output_dir": str(frames)})
    try:
        unit.step(0.1)
        state = unit.fmu.getFMUstate()
        saved_time = unit.time
        unit.set(water_level=0.05)  # a path the master then abandons
        unit.step(0.1)
        unit.step(0.1)
        unit.fmu.setFMUstate(state)
        unit.fmu.freeFMUstate(state)
        unit.time = saved_time
        unit.step(0.1)
    finally:
        unit.close()
    assert sorted(f.name for f in frames.glob("cloth_*")) == [f"cloth_{k:04d}.ply" for k in (1, 2, 3)]
    sim = wetcloth.Simulation(wetcloth.Scene(**SMALL))
    sim.advance(0.1)
    sim.advance(0.1)
    positions, _, _ = read_frame(frames / "cloth_0003.ply")
    np.testing.assert_allclose(positions, sim.positions, atol=FLOAT32_M)  # the rolled-back path's frame
    assert json.loads((frames / "frames.json").read_text())["frame_count"] == 3


def test_a_state_restored_in_a_new_instance_continues_the_frames(tmp_path):
    """fmi2DeSerializeFMUstate in a fresh instance: its frames go on after the state's frame count."""
    frames = tmp_path / "frames"
    first = Unit(SMALL | {"mesh_output_dir": str(frames)}, name="first")
    try:
        first.step(0.1)  # frames 1 (t = 0) and 2
        saved = first.fmu.serializeFMUstate(first.fmu.getFMUstate())
        first.step(0.1)
        first.step(0.1)  # frames 3 and 4: a branch the master abandons
    finally:
        first.close()
    second = Unit(SMALL | {"mesh_output_dir": str(frames)}, name="second")
    try:
        state = second.fmu.deSerializeFMUstate(saved)
        second.fmu.setFMUstate(state)
        second.fmu.freeFMUstate(state)
        second.time = 0.1
        assert second.step(0.1) == 0
    finally:
        second.close()
    assert sorted(f.name for f in frames.glob("cloth_*")) == [f"cloth_{k:04d}.ply" for k in (1, 2, 3)]
    assert json.loads((frames / "frames.json").read_text())["frame_count"] == 3


CHILD_TERMINATE = r"""
import json, sys
from pathlib import Path
sys.path.insert(0, sys.argv[2])
import fmpy, test_fmu_support as support
support._BUILT["dir2"], support._BUILT["md2"] = Path(sys.argv[3]), fmpy.read_model_description(sys.argv[3])
frames = Path(sys.argv[1])
unit = support.Unit(support.SMALL | {"mesh_output_dir": str(frames)})
unit.step(0.1)
unit._call(unit.fmu.terminate)
manifest = (frames / "frames.json").read_text()
statuses = [unit.step(0.1), unit._call(unit.fmu.terminate)]
print(json.dumps({"statuses": statuses, "same_manifest": (frames / "frames.json").read_text() == manifest,
                  "files": sorted(p.name for p in frames.iterdir())}))
unit.fmu.freeInstance()  # (while its Unit's logger callback lives)
"""


def test_after_terminate_no_frame_is_written_and_frames_json_stays(tmp_path):
    records, _ = run_child(CHILD_TERMINATE, tmp_path / "frames", Path(__file__).parent, extracted_fmu()[0])
    record = records[-1]
    assert record["statuses"] == [4, 0]  # doStep refused (pythonfmu: Fatal), the second terminate does nothing
    assert record["same_manifest"]
    assert record["files"] == ["cloth_0001.ply", "cloth_0002.ply", "frames.json", "load_in_blender.py"]


def snapshot_of(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_a_folder_with_files_the_unit_did_not_write_is_refused_and_left_alone(fmu, tmp_path):
    """The folder of the issue: another tool's USD, PLY and OBJ frames.  Initialization fails (fmpy
    raises) naming mesh_output_dir; not one file is touched."""
    folder = tmp_path / "assets"
    folder.mkdir()
    for name in ("hero_asset.usd", "render_0001.ply", "scan_00042.obj", "notes.txt"):
        (folder / name).write_bytes(f"{name}: not mine".encode())
    before = snapshot_of(folder)
    with pytest.raises(Exception, match="fmi2ExitInitializationMode"):
        fmpy.simulate_fmu(fmu, stop_time=0.1, output_interval=0.1, start_values=SMALL | {"mesh_output_dir": str(folder)})
    assert snapshot_of(folder) == before
    # An unrelated file alone is refused as well: the folder must belong to the unit.
    (other := tmp_path / "other").mkdir()
    (other / "notes.txt").write_text("keep me")
    with pytest.raises(Exception, match="fmi2ExitInitializationMode"):
        fmpy.simulate_fmu(fmu, stop_time=0.1, output_interval=0.1, start_values=SMALL | {"mesh_output_dir": str(other)})
    assert snapshot_of(other) == {"notes.txt": b"keep me"}


def test_a_sequence_the_unit_wrote_is_replaced_and_the_replacement_logged(tmp_path):
    frames = tmp_path / "frames"
    values = SMALL | {"mesh_output_dir": str(frames)}
    for steps in (3, 1):
        unit = Unit(values)
        try:
            for _ in range(steps):
                assert unit.step(0.1) == 0
        finally:
            unit.close()
    warnings = [text for status, text in unit.messages if status == 1]
    assert len(warnings) == 1 and "replaced the earlier frame sequence" in warnings[0]
    for name in ("cloth_0001.ply", "cloth_0004.ply", "frames.json", "load_in_blender.py"):
        assert name in warnings[0]
    assert sorted(p.name for p in frames.iterdir()) == ["cloth_0001.ply", "cloth_0002.ply", "frames.json",
                                                         "load_in_blender.py"]


# ------------------------------------------------------------------ the exporter's rule behind it
def test_overwrite_replaces_only_the_sequence_its_frames_json_describes(tmp_path):
    """``overwrite`` (the CLI's too) replaces an earlier sequence of this exporter, never other files:
    a folder that also holds another tool's frame-like files is refused untouched; unrelated files
    stay unless ``exclusive``."""
    scene = wetcloth.Scene(nx=3, ny=3)
    sim = wetcloth.Simulation(scene)
    with open_sequence(tmp_path, fps=10, scene=scene) as sequence:
        sequence.write_frame(sim.positions, sim.wetness)
    assert [p.name for p in sequence_files(tmp_path)] == ["cloth_0001.ply", "frames.json", "load_in_blender.py"]
    (tmp_path / "notes.txt").write_text("keep me")
    assert [p.name for p in check_directory(tmp_path, overwrite=True)] == [
        "cloth_0001.ply", "frames.json", "load_in_blender.py"]
    with pytest.raises(ExportError, match=r"not part of the frame sequence .*notes\.txt"):
        check_directory(tmp_path, overwrite=True, exclusive=True)
    (tmp_path / "render_0001.ply").write_bytes(b"another tool's")
    before = snapshot_of(tmp_path)
    with pytest.raises(ExportError, match=r"render_0001\.ply"):
        open_sequence(tmp_path, fps=10, scene=scene, overwrite=True)
    assert snapshot_of(tmp_path) == before
    (tmp_path / "render_0001.ply").unlink()
    (tmp_path / "frames.json").write_text('{"generator": "someone else"}')
    with pytest.raises(ExportError, match="did not write"):
        open_sequence(tmp_path, fps=10, scene=scene, overwrite=True)


def test_demo_command_writes_frames_csv_and_plot(fmu, tmp_path, native_objects):
    out = tmp_path / "demo"
    # The demo keeps the native unit's objects in ./build/native: here the session's shared folder.
    native_objects.mkdir(parents=True, exist_ok=True)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "native").symlink_to(native_objects, target_is_directory=True)
    done = subprocess.run([sys.executable, "-m", "wetcloth.cli", "demo", "--out", str(out), "--fmu", fmu,
                           "--duration", "0.2", "--no-progress"], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    header, *rows = (out / "outputs.csv").read_text().splitlines()
    assert header.split(",") == ["time", *OUTPUT_NAMES]
    fps = wetcloth.scene.read_scene_file(None)["run"]["fps"]
    assert len(rows) == round(0.2 * fps) + 1 == len(list((out / "frames").glob("cloth_*.ply")))
    assert (out / "plot.png").read_bytes().startswith(b"\x89PNG")
    # The native unit, run beside it, gives the same outputs to the bit: the same compiled core.
    assert "WetClothNative.fmu: outputs differ by 0 at most" in done.stdout, done.stdout
    # The default towel, through the FMU, equals a direct run of the towel preset.
    sim = wetcloth.Simulation(wetcloth.load_scene())
    last = [float(v) for v in rows[-1].split(",")]
    for _ in range(len(rows) - 1):
        sim.advance(1.0 / fps)
    np.testing.assert_allclose(last[1:], [sim.outputs()[n] for n in OUTPUT_NAMES], rtol=1e-9, atol=1e-12)


def test_demo_builds_a_missing_fmu(tmp_path):
    from wetcloth.fmu import demo

    paths = demo(tmp_path / "demo", fmu=tmp_path / "models" / "WetCloth.fmu", duration=0.1, progress=False,
                 native=False)
    assert paths["fmu"].exists() and paths["csv"].exists()
