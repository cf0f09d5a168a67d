"""``wetcloth blender-extension``: the Blender extension, ``wetcloth-VERSION.zip`` (Blender 4.2+ format).

The zip holds ``blender_manifest.toml`` (schema 1.0.0, id ``wetcloth``), a five-line ``__init__.py``
that registers the add-on, and ``wheels/``: wetcloth itself (the compiled core, this package and
the add-on, ``wetcloth.exporter.blender_extension``) built for the running Python and platform, and
for any other Python given, and for each of those Pythons a wheel of every ``DEPENDENCIES``.  Blender
installs the wheels of its own Python when the extension is installed; the bake needs nothing else
from outside (numpy and USD come with Blender).  The Blender versions the manifest allows are those
whose Python has a wetcloth wheel (``BLENDER_VERSIONS``).
"""

from __future__ import annotations

import os
import platform
import subprocess
from importlib import metadata
import sys
import tempfile
import zipfile
from pathlib import Path

import wetcloth

#: The extension's id (its module is ``bl_ext.<repository>.wetcloth``).
EXTENSION_ID = "wetcloth"
#: Blender versions (first, and first not) whose Python a wheel's tag is: 4.2 (the first with the
#: extension format) to 5.0 ship Python 3.11, 5.1 and later Python 3.13.
BLENDER_VERSIONS = {"cp311": ("4.2.0", "5.1.0"), "cp313": ("5.1.0", None)}
#: What the bake needs beyond Blender's own numpy and USD, bundled as wheels (the version this Python runs):
#: scipy, with which a mesh cloth's preconditioner orders its particles (reverse Cuthill-McKee), and
#: pyamg, whose aggregation gives the multigrid levels of a mesh of more than ALGEBRAIC_SIZE vertices.
DEPENDENCIES = ("scipy", "pyamg")
#: Where dependency wheels are kept once pip has downloaded them (as the Makefile keeps bpy's).
WHEEL_CACHE = Path(os.environ.get("WETCLOTH_WHEELS", Path.home() / ".cache" / "wetcloth" / "wheels"))
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


def blender_range(wheel_names) -> tuple[str, str | None]:
    """The first Blender the wheels serve and the first they do not (None: every later one); the
    table's ranges meet, so any set of its Pythons covers one stretch of versions."""
    ranges = sorted(BLENDER_VERSIONS[name.split("-")[2]] for name in wheel_names)
    return ranges[0][0], ranges[-1][1]


def manifest(version: str, wheel_names, blender_platform_name: str, dependencies=()) -> str:
    """The text of ``blender_manifest.toml``: wetcloth's wheels ``wheel_names`` and ``dependencies``' wheels."""
    first, last = blender_range(wheel_names)
    upper = f'blender_version_max = "{last}"\n' if last else ""
    wheels = ", ".join(f'"./wheels/{name}"' for name in [*wheel_names, *dependencies])
    return f'''schema_version = "1.0.0"
id = "{EXTENSION_ID}"
version = "{version}"
name = "Wet Cloth"
tagline = "Bake cloth that soaks up water, floats and sinks"
maintainer = "wetcloth"
type = "add-on"
tags = ["Physics", "Animation"]
blender_version_min = "{first}"
{upper}license = ["SPDX:MIT"]
platforms = ["{blender_platform_name}"]
wheels = [{wheels}]

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


def run_python(python: str | Path, *arguments: str) -> subprocess.CompletedProcess:
    """Interpreter ``python`` run with ``arguments``, its output captured; a ValueError where it cannot run."""
    try:
        return subprocess.run([str(python), *arguments], capture_output=True, text=True)
    except OSError as exc:  # no such file, not executable
        raise ValueError(f"Python interpreter {python} cannot be run: {exc.strerror or exc}; give the path of "
                         "a Python (Blender 4.2 to 5.0 run 3.11, 5.1 and later 3.13)") from None


def python_tag(python: str | Path) -> str:
    """The wheel tag (``cp311``) of interpreter ``python``; a ValueError for one no Blender ships."""
    done = run_python(python, "-c", "import sys; print(f'cp{sys.version_info[0]}{sys.version_info[1]}')")
    tag = done.stdout.strip()
    if done.returncode != 0 or tag not in BLENDER_VERSIONS:
        raise ValueError(f"--python {python}: {'Python ' + tag[2] + '.' + tag[3:] if tag else 'not a Python'}; "
                         "Blender ships Python 3.11 (4.2 to 5.0) or 3.13 (5.1 and later)")
    return tag


def build_wheel(directory: Path, python: str | Path = sys.executable) -> Path:
    """``pip wheel --no-deps`` of the source tree by interpreter ``python`` into ``directory``; the wheel.  Where
    ``python`` has the build's requirements (as ``make`` installs them), without an isolated build environment:
    the build then reuses build/ (pyproject.toml's ``build-dir``), compiled by the editable install."""
    before = set(directory.glob("wetcloth-*.whl"))
    has_backend = run_python(python, "-c", "import scikit_build_core, nanobind").returncode == 0
    isolation = ["--no-build-isolation"] if has_backend else []
    done = run_python(python, "-m", "pip", "wheel", "--no-deps", "--quiet", *isolation, str(source_tree()),
                      "-w", str(directory))
    wheels = sorted(set(directory.glob("wetcloth-*.whl")) - before)
    if done.returncode != 0 or len(wheels) != 1:
        raise ValueError(f"pip wheel of {source_tree()} by {python} failed (exit {done.returncode}):\n"
                         f"{done.stderr[-2000:]}")
    return wheels[0]


def check_wheel(wheel: Path) -> None:
    """Refuse a wheel no Blender can load: another project or version, or a Python no Blender ships."""
    parts = wheel.name[:-len(".whl")].split("-")
    if wheel.suffix != ".whl" or len(parts) != 5 or parts[0] != "wetcloth":
        raise ValueError(f"wheel {wheel}: not a wetcloth wheel (wetcloth-VERSION-PYTHON-ABI-PLATFORM.whl)")
    if parts[1] != wetcloth.__version__:
        raise ValueError(f"wheel {wheel}: version {parts[1]}, this wetcloth is {wetcloth.__version__}")
    if parts[2] not in BLENDER_VERSIONS:
        raise ValueError(f"wheel {wheel}: built for {parts[2]}; Blender ships Python 3.11 (4.2 to 5.0, cp311) "
                         "or 3.13 (5.1 and later, cp313)")


def dependency_wheel(name: str, tag: str) -> Path:
    """The wheel of package ``name`` (the version this Python runs) for Python ``tag`` (cp311) on this
    platform: from WHEEL_CACHE, where pip downloads it the first time."""
    version = metadata.version(name)
    pattern = f"{name}-{version}-{tag}-{tag}-*.whl"
    if not any(WHEEL_CACHE.glob(pattern)):
        done = subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:",
                               "--python-version", f"{tag[2]}.{tag[3:]}", "--dest", str(WHEEL_CACHE),
                               f"{name}=={version}"], capture_output=True, text=True)
        if done.returncode != 0 or not any(WHEEL_CACHE.glob(pattern)):
            raise ValueError(f"no wheel of {name} {version} for {tag} in {WHEEL_CACHE}, and pip could not download "
                             f"one (exit {done.returncode}):\n{done.stderr[-2000:]}")
    return sorted(WHEEL_CACHE.glob(pattern))[-1]


def build_extension(out: Path | None = None, wheels=(), pythons=()) -> Path:
    """Write ``wetcloth-VERSION.zip`` into the folder ``out`` (default: the current one); its path.

    ``wheels``: wetcloth wheels to bundle as they are; ``pythons``: interpreters to build one with
    each.  With neither, the wheel is built now from the source tree by this Python."""
    out = Path(out or ".")
    wheels = [Path(w) for w in wheels]
    for wheel in wheels:
        check_wheel(wheel)
    pythons = list(pythons or ([] if wheels else [sys.executable]))
    sources = [*(w.name for w in wheels), *(f"--python {p}" for p in pythons)]
    tags = [w.name.split("-")[2] for w in wheels] + [python_tag(p) for p in pythons]  # before any building
    if len(set(tags)) != len(tags):
        raise ValueError(f"two wheels for one Python ({', '.join(f'{s}: {t}' for s, t in zip(sources, tags))}); "
                         "give one per Python")
    with tempfile.TemporaryDirectory() as tmp:
        for python in pythons:
            wheels.append(build_wheel(Path(tmp), python))
            check_wheel(wheels[-1])
        names = [w.name for w in wheels]
        wheels += [dependency_wheel(name, tag) for tag in tags for name in DEPENDENCIES]
        text = manifest(wetcloth.__version__, names, blender_platform(), [w.name for w in wheels[len(names):]])
        out.mkdir(parents=True, exist_ok=True)
        target = out / f"{EXTENSION_ID}-{wetcloth.__version__}.zip"
        partial = target.with_name(target.name + ".part")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("blender_manifest.toml", text)
            archive.writestr("__init__.py", INIT_SOURCE)
            for wheel in wheels:
                archive.write(wheel, f"wheels/{wheel.name}")
        partial.replace(target)
    return target
