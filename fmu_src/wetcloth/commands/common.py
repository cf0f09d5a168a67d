"""What the subcommands share: argument types and exit statuses."""

from __future__ import annotations

import argparse
from pathlib import Path

#: Exit status of a command refused or failed for a reason it names (a bad option, a full disk).
FAILED = 2
#: Exit status of a command stopped by Ctrl-C (128 + SIGINT, as shells report it).
INTERRUPTED = 130


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


def scene_with_overrides(scene: str | Path | None, overrides: list[tuple[str, str]]):
    """The scene of a file or preset with the command line's ``--set NAME=VALUE`` texts applied;
    every mistake of the ``--set`` options reported at once."""
    from wetcloth.errors import Mistakes
    from wetcloth.scene import load_scene, parse_text

    mistakes = Mistakes("--set")
    values = {}
    for name, text in overrides:
        with mistakes.collect():
            values[name] = parse_text(name, text)
    mistakes.raise_if_any()
    return load_scene(scene, **values)
