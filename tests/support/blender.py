"""The Blender interpreter of the Blender tests: bpy 5.0.1 from PyPI in .venv-blender (made by the Makefile)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"
#: Another bpy interpreter can be tried with WETCLOTH_BLENDER_PYTHON (e.g. a venv with bpy 4.2).
BLENDER_PYTHON = Path(os.environ.get("WETCLOTH_BLENDER_PYTHON", DEFAULT_BLENDER_PYTHON))


def require_blender_python() -> Path:
    """The interpreter; without it the test fails under WETCLOTH_REQUIRE_BLENDER=1 (``make test``) and
    is skipped, with the reason, otherwise (the 1.3 GB environment is then the developer's choice)."""
    if BLENDER_PYTHON.exists():
        return BLENDER_PYTHON
    message = (f"{BLENDER_PYTHON} is missing; `make .venv-blender/.installed` builds it "
               "(Python 3.11 venv with bpy 5.0.1, ~1 GB; `make test` does it first)")
    if os.environ.get("WETCLOTH_REQUIRE_BLENDER") == "1":
        pytest.fail(message)
    pytest.skip(message)


def probe_extension(root: Path, probe: Path, spec: dict) -> dict:
    """Build the extension's zip into ``root`` (with a wheel for the Blender Python's version too, as a release
    has), then run ``probe`` in that Python, its user folder in ``root``, given ``spec`` plus the zip and a work
    folder (root/spec.json; it writes root/result.json): the probe's report, or the test fails."""
    from wetcloth.cli import main as cli_main

    python = require_blender_python()
    version = subprocess.run([str(python), "-c", "import sys; print(*sys.version_info[:2])"], capture_output=True,
                             text=True, check=True).stdout.split()
    # another Blender's Python (5.1 and later run 3.13) gets its own wheel beside this Python's, as a release has
    other = [] if tuple(map(int, version)) == sys.version_info[:2] else ["--python", sys.executable, "--python", str(python)]
    assert cli_main(["blender-extension", "--out", str(root), *other]) == 0
    (root / "work").mkdir()
    (root / "user").mkdir()
    spec = spec | {"zip": str(next(root.glob("wetcloth-*.zip"))), "work": str(root / "work")}
    (root / "spec.json").write_text(json.dumps(spec))
    env = os.environ | {"BLENDER_USER_RESOURCES": str(root / "user")}  # not the developer's Blender folder
    done = subprocess.run([str(python), str(probe), str(root / "spec.json"), str(root / "result.json")],
                          capture_output=True, text=True, timeout=600, env=env, cwd=root)
    if done.returncode != 0 or not (root / "result.json").exists():
        pytest.fail(f"the Blender probe failed (exit {done.returncode}):\n{done.stderr[-4000:]}")
    report = json.loads((root / "result.json").read_text())
    if "error" in report:
        pytest.fail(f"the Blender probe stopped:\n{report['error']}")
    return report
