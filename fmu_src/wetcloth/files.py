"""Whole files or none: every output wetcloth writes goes through :func:`whole_file`.

The data is written to a temporary file beside the target and renamed over it only once it is
complete (``os.replace``, atomic on one filesystem), so a reader, a crash, Ctrl-C or a full disk
never leaves half a file; on any failure the temporary file is removed and the target is left as it
was (absent, or its previous contents).

The temporary file is created new (``tempfile.mkstemp``: a random name, ``O_EXCL``), never opened
if something is there already: a symbolic link planted at a predictable temporary name would
otherwise have the data written wherever it points.  It gets the permissions a new file gets
(0666 less the umask), as the target would.
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Iterator


def _umask() -> int:
    """The process's umask, read without changing it where Linux tells it (/proc), else by setting it back."""
    with suppress(OSError, ValueError, StopIteration):
        status = Path("/proc/self/status").read_text()
        return int(next(line for line in status.splitlines() if line.startswith("Umask:")).split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def new_temporary(path: Path, suffix: str | None = None) -> Path:
    """A new, empty file beside ``path`` to write it in, created exclusively: hidden
    ``.<name>.<random>.tmp``, or ``<name>.<random><suffix>`` if ``suffix`` is given."""
    prefix = f"{path.name}." if suffix is not None else f".{path.name}."
    fd, name = tempfile.mkstemp(suffix=suffix if suffix is not None else ".tmp", prefix=prefix, dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_umask())
    finally:
        os.close(fd)
    return Path(name)


@contextmanager
def whole_file(path: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """Yield the temporary path to write; on leaving the block it replaces ``path``.

        with whole_file("out/table.parquet") as tmp:
            table.to_parquet(tmp)

    Any exception (OSError of a full disk, KeyboardInterrupt) removes the temporary file and
    propagates.  ``suffix`` names the temporary file ``<name>.<random><suffix>`` (see ``new_temporary``).
    """
    path = Path(path)
    tmp = new_temporary(path, suffix)
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
