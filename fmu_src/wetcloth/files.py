"""Whole files or none: every output wetcloth writes goes through :func:`whole_file`.

The data is written under a temporary name beside the target and renamed over it only once it
is complete (``os.replace``, atomic on one filesystem), so a reader, a crash, Ctrl-C or a full
disk never leaves half a file; on any failure the temporary file is removed and the target is
left as it was (absent, or its previous contents).
"""

from __future__ import annotations

import os
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Iterator


def temporary_name(path: Path, suffix: str | None = None) -> Path:
    """Where ``path`` is written before it is complete: ``path`` + ``suffix`` if given, else a hidden
    ``.<name>.<pid>.tmp`` beside it (two processes writing the same file never share one)."""
    if suffix is not None:
        return path.with_name(path.name + suffix)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


@contextmanager
def whole_file(path: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """Yield the temporary path to write; on leaving the block it replaces ``path``.

        with whole_file("out/table.parquet") as tmp:
            table.to_parquet(tmp)

    Any exception (OSError of a full disk, KeyboardInterrupt) removes the temporary file and
    propagates.  ``suffix`` names the temporary file ``<name><suffix>`` (see ``temporary_name``).
    """
    path = Path(path)
    tmp = temporary_name(path, suffix)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with suppress(OSError):
            tmp.unlink()
        raise


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all."""
    path = Path(path)
    with whole_file(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
