"""``wetcloth blender-extension``: the Blender extension, ``wetcloth-VERSION.zip`` (Blender 4.2+ format).

The zip holds ``blender_manifest.toml`` (schema 1.0.0, id ``wetcloth``), a five-line ``__init__.py``
that registers the add-on, and ``wheels/``: wetcloth itself (the compiled core, this package and
the add-on, ``wetcloth.exporter.blender_extension``) built for the running Python and platform.
Blender installs the wheel into its own Python when the extension is installed; the bake needs
nothing else from outside (numpy and USD come with Blender).
"""

from __future__ import annotations

import platform
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import wetcloth

#: The extension's id (its module is ``bl_ext.<repository>.wetcloth``).
EXTENSION_ID = "wetcloth"
#: Oldest Blender with the extension format; Blender 4.2 to 5.0 ship Python 3.11, as the wheel is built for.
BLENDER_MIN = "4.2.0"
#: Blender's platform names of the machines a wheel can be built on here.
PLATFORMS = {("Linux", "x86_64"): "linux-x64", ("Linux", "aarch64"): "linux-arm64",
             ("Darwin", "arm64"): "macos-arm64", ("Darwin", "x86_64"): "macos-x64",
             ("Windows", "AMD64"): "windows-x64"}

INIT_SOURCE = '''"""Wet Cloth: bake a wetcloth simulation (cloth that soaks up water and sinks) in the scene.
The add-on's code is in the bundled wheel, module wetcloth.exporter.blender_extension."""


def register():
    from wetcloth.exporter import blender_extension
    blender_extension.register()


def unregister():
    from wetcloth.exporter import blender_extension
    blender_extension.unregister()
'''


def blender_platform() -> str:
    """Blender's name of this machine's platform (``linux-x64``); a ValueError where there is none."""
    key = (platform.system(), platform.machine())
    if key not in PLATFORMS:
        raise ValueError(f"no Blender platform for {key[0]} {key[1]}; wetcloth builds the extension on "
                         + ", ".join(f"{s} {m}" for s, m in PLATFORMS))
    return PLATFORMS[key]


def manifest(version: str, wheel_name: str, blender_platform_name: str) -> str:
    """The text of ``blender_manifest.toml``."""
    return f'''schema_version = "1.0.0"
id = "{EXTENSION_ID}"
version = "{version}"
name = "Wet Cloth"
tagline = "Bake cloth that soaks up water, floats and sinks"
maintainer = "wetcloth"
type = "add-on"
tags = ["Physics", "Animation"]
blender_version_min = "{BLENDER_MIN}"
license = ["SPDX:MIT"]
platforms = ["{blender_platform_name}"]
wheels = ["./wheels/{wheel_name}"]

[permissions]
files = "Writes the baked cloth (USD caches) beside the .blend file"
'''


def source_tree() -> Path:
    """The project folder this wetcloth runs from (an editable install), which pip can build a wheel of."""
    root = Path(wetcloth.__file__).resolve().parents[2]
    if not (root / "pyproject.toml").is_file() or not (root / "fmu_src" / "core").is_dir():
        raise ValueError(f"wetcloth is not running from its source tree (no pyproject.toml in {root}): "
                         "pass --wheel with a wetcloth wheel for Blender's Python")
    return root


def build_wheel(directory: Path) -> Path:
    """``pip wheel --no-deps`` of the source tree into ``directory``; the wheel's path."""
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", str(source_tree()),
                           "-w", str(directory)], capture_output=True, text=True)
    wheels = sorted(directory.glob("wetcloth-*.whl"))
    if done.returncode != 0 or len(wheels) != 1:
        raise ValueError(f"pip wheel of {source_tree()} failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
    return wheels[0]


def check_wheel(wheel: Path) -> None:
    """Refuse a wheel Blender's Python 3.11 cannot load: another project, version or Python."""
    parts = wheel.name[:-len(".whl")].split("-")
    if wheel.suffix != ".whl" or len(parts) != 5 or parts[0] != "wetcloth":
        raise ValueError(f"--wheel {wheel}: not a wetcloth wheel (wetcloth-VERSION-PYTHON-ABI-PLATFORM.whl)")
    if parts[1] != wetcloth.__version__:
        raise ValueError(f"--wheel {wheel}: version {parts[1]}, this wetcloth is {wetcloth.__version__}")
    if parts[2] != "cp311":
        raise ValueError(f"--wheel {wheel}: built for {parts[2]}; Blender 4.2 to 5.0 run Python 3.11 (cp311)")


def build_extension(out: Path | None = None, wheel: Path | None = None) -> Path:
    """Write ``wetcloth-VERSION.zip`` into the folder ``out`` (default: the current one); its path.

    ``wheel``: a wetcloth wheel to bundle (default: built now from the source tree, for this Python,
    which must be 3.11 like Blender's)."""
    if wheel is None and sys.version_info[:2] != (3, 11):
        raise ValueError(f"the wheel must be built by Python 3.11 (Blender's), this is "
                         f"{platform.python_version()}: run wetcloth from a Python 3.11 venv, or pass --wheel")
    out = Path(out or ".")
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"{EXTENSION_ID}-{wetcloth.__version__}.zip"
    with tempfile.TemporaryDirectory() as tmp:
        if wheel is None:
            wheel = build_wheel(Path(tmp))
        wheel = Path(wheel)
        check_wheel(wheel)
        partial = target.with_name(target.name + ".part")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("blender_manifest.toml", manifest(wetcloth.__version__, wheel.name, blender_platform()))
            archive.writestr("__init__.py", INIT_SOURCE)
            archive.write(wheel, f"wheels/{wheel.name}")
        partial.replace(target)
    return target
