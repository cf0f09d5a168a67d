"""A Blender mesh as the cloth and its frames back on it (docs/blender.md section 9), in headless bpy:
the probe (tests/blender/roundtrip_probe.py) runs the docs' snippets.  Skipped without .venv-blender,
failing under WETCLOTH_REQUIRE_BLENDER=1 (as tests/test_blender.py)."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from support.blender import require_blender_python

import wetcloth
from wetcloth.exporter import open_sequence

PROBE = Path(__file__).with_name("blender") / "roundtrip_probe.py"
FPS, FRAMES = 24, 13
#: Blender plays float32 positions (USD points): within 6e-8 m of wetcloth's below 2 m.
POSITION_TOL = 1e-6


def probe(python, stage: str, spec: dict, root: Path) -> dict:
    (root / "spec.json").write_text(json.dumps(spec))
    done = subprocess.run([str(python), str(PROBE), stage, str(root / "spec.json"), str(root / "result.json")],
                          capture_output=True, text=True, timeout=600, cwd=root)
    report = json.loads((root / "result.json").read_text()) if (root / "result.json").exists() else {}
    if done.returncode != 0 or "error" in report or not report:
        pytest.fail(f"the Blender probe ({stage}) failed (exit {done.returncode}):\n{report.get('error', '')}"
                    f"\n{done.stderr[-3000:]}")
    return report


def test_a_blender_mesh_with_a_pin_group_simulates_and_its_frames_play_back_on_it(tmp_path):
    """The plane (9 x 9 vertices, its top edge pinned by the vertex group) goes out as PLY with the group as
    the point attribute 'pinned'; wetcloth runs it (cloth_mesh, pinned_vertices = 'pinned') as the particles in
    Blender's vertex order, at Blender's coordinates; its USD frames played on the same object by a
    MeshSequenceCache modifier put every vertex where wetcloth has it (float32), the pinned edge still, and
    leave the object's UV map as it was exported (the PLY carries none: the object keeps its own)."""
    python = require_blender_python()
    spec = {"size": 0.5, "height": 1.0, "cuts": 7, "ply": str(tmp_path / "cloth.ply"), "blend": str(tmp_path / "shot.blend"),
            "usd": str(tmp_path / "frames" / "cloth.usd"), "frames": [1, 7, FRAMES]}
    exported = probe(python, "export", spec, tmp_path)
    scene = wetcloth.load_scene(cloth_mesh=spec["ply"], pinned_vertices="pinned", water_level=0.0, floor_level=-1.0)
    sim = wetcloth.Simulation(scene)
    assert sim.model.topology.n == exported["vertices"] == 81
    np.testing.assert_allclose(sim.positions, exported["world"], rtol=0, atol=1e-6)  # Blender's order, its place
    assert sorted(np.flatnonzero(sim.model.topology.pinned)) == sorted(exported["pinned"])
    expected = [sim.positions.copy()]
    with open_sequence(tmp_path / "frames", fmt="usd", fps=FPS, scene=scene) as frames:
        frames.on_frame(0, sim)
        for index in range(1, FRAMES):
            sim.advance(1 / FPS)
            expected.append(sim.positions.copy())
            frames.on_frame(index, sim)
    played = probe(python, "play", spec, tmp_path)
    for frame in spec["frames"]:
        np.testing.assert_allclose(played["frames"][str(frame)], expected[frame - 1], rtol=0, atol=POSITION_TOL)
    moved = np.abs(expected[-1] - expected[0]).max(axis=1)
    assert moved[exported["pinned"]].max() == 0.0 and moved.max() > 0.05
    assert list(exported["uv"]) == ["UVMap"] and np.ptp(exported["uv"]["UVMap"]) == 1.0  # the plane's 0..1 map
    for frame in spec["frames"]:  # the evaluated mesh's, as played: Blender's own values, exactly
        assert played["uv"][str(frame)] == exported["uv"], frame


def test_the_docs_show_the_snippets_the_probe_runs():
    """docs/blender.md section 9 shows, line for line, the code the probe runs in Blender."""
    docs = (Path(__file__).resolve().parents[1] / "docs" / "blender.md").read_text()
    section = docs[docs.index("## 9. Your own mesh"):]
    source = PROBE.read_text()
    for name in ("EXPORT_SNIPPET", "PLAY_SNIPPET"):
        snippet = source.split(f"{name} = '''", 1)[1].split("'''", 1)[0]
        for line in filter(None, snippet.splitlines()):
            assert line in section, (name, line)
