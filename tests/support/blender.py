"""The Blender interpreter of the Blender tests: bpy 5.0.1 from PyPI in .venv-blender (made by the Makefile)."""

import os
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
