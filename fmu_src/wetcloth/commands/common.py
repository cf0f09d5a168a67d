"""What the subcommands share: argument types and exit statuses."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

#: Exit status of a command refused or failed for a reason it names (a bad option, a full disk).
FAILED = 2
#: Exit status of a command stopped by Ctrl-C (128 + SIGINT, as shells report it).
INTERRUPTED = 130
#: The largest random seed (numpy's seeds are 0..2**32 - 1).
SEED_MAX = 2**32 - 1


def path_argument(text: str) -> Path:
    """A file or folder path given on the command line; an empty one is refused (it would mean
    the current folder, which no option means)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("needs a path, got an empty string")
    return Path(text)


def csv_path(text: str) -> Path:
    """An output CSV file's path: one ending in ``.csv`` (any case), so that ``--csv x.parquet`` is
    refused rather than written as CSV under a name that says otherwise."""
    path = path_argument(text)
    if path.suffix.lower() != ".csv":
        raise argparse.ArgumentTypeError(f"{text}: a CSV file's name ends in .csv")
    return path


def seed_argument(text: str) -> int:
    """A random seed given on the command line: a whole number 0..2**32 - 1, as numpy takes."""
    try:
        seed = int(text)
    except ValueError:
        seed = None
    if seed is None or not 0 <= seed <= SEED_MAX:
        raise argparse.ArgumentTypeError(f"expected a whole number 0..2**32 - 1 ({SEED_MAX}), got {text!r}")
    return seed


def scheduler_argument(text: str) -> str:
    """A Dask scheduler's address given on the command line, checked without connecting
    (``wetcloth.batch.cluster.check_scheduler_address``)."""
    from wetcloth.batch.cluster import check_scheduler_address

    try:
        return check_scheduler_address(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def check_writable_folder(folder: Path, option: str, given: Path | None = None, make: bool = True) -> None:
    """Refuse an output folder that cannot be made or written, before any work: a ValueError naming
    ``option`` and its value ``given`` (default: ``folder``).  Makes the folder, as the output would; with
    ``make=False`` (a command with more to check before it writes anything) only looks at the folder or
    its nearest existing parent: a file there, or no permission to write, is refused."""
    if not make:
        existing = next(p for p in (folder.absolute(), *folder.absolute().parents) if p.exists() or p == p.parent)
        why = ("not a folder" if not existing.is_dir() else
               "Permission denied" if not os.access(existing, os.W_OK | os.X_OK) else None)
        if why is not None:
            raise ValueError(f"{option} {given or folder}: cannot write there ({why}: {existing})")
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".wetcloth-probe"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        where = f": {exc.filename}" if exc.filename else ""
        raise ValueError(f"{option} {given or folder}: cannot write there ({exc.strerror or exc}{where})") from None


def scene_with_overrides(scene: str | Path | None, overrides: list[tuple[str, str]]):
    """The scene of a file or preset with the command line's ``--set NAME=VALUE`` texts applied;
    every mistake of the ``--set`` options reported at once.  A parameter set twice is a ValueError."""
    from wetcloth.errors import Mistakes
    from wetcloth.scene import load_scene, parse_text

    names = [name for name, _ in overrides]
    for name in names:
        if names.count(name) > 1:
            values = ", ".join(value for n, value in overrides if n == name)
            raise ValueError(f"--set {name} is given {names.count(name)} times ({values}): give each parameter once")
    mistakes = Mistakes("--set")
    values = {}
    for name, text in overrides:
        with mistakes.collect():
            values[name] = parse_text(name, text)
    mistakes.raise_if_any()
    return load_scene(scene, **values)


def check_fmu_file(path: Path, option: str) -> None:
    """Refuse a unit to run that is not an FMU, before any work: a ValueError naming ``option`` unless
    ``path`` is a zip file holding a modelDescription.xml (an FMU) or a folder holding one (an FMU
    unpacked)."""
    import zipfile

    if path.is_dir():
        if not (path / "modelDescription.xml").is_file():
            raise ValueError(f"{option} {path}: a folder without a modelDescription.xml, so not an unpacked FMU")
        return
    if not path.exists():
        raise ValueError(f"{option} {path}: no such file (build one with 'wetcloth build-fmu')")
    try:
        with zipfile.ZipFile(path) as archive:
            archive.getinfo("modelDescription.xml")
    except (OSError, zipfile.BadZipFile, KeyError):
        raise ValueError(f"{option} {path}: not an FMU (a zip file holding a modelDescription.xml)") from None


def check_out_suffix(path: Path, suffix: str, option: str = "--out") -> None:
    """Refuse an output file's name that does not end in ``suffix`` (any case), so that an output never
    overwrites a file of another kind (a scene TOML, a mesh) given by mistake."""
    if path.suffix.lower() != suffix:
        raise ValueError(f"{option} {path}: the file's name must end in {suffix}")
