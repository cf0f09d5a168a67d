"""Run a script in a child process whose folder ``DISK`` is a disk of a few kilobytes.

Two ways, each a test parameter (``DISKS``):
- ``tmpfs``: a real filesystem of that size, mounted in a private mount namespace (``unshare -rm``,
  as root or where unprivileged user namespaces are allowed; skipped elsewhere).  Writes past its
  size fail with ENOSPC in the kernel, whatever library writes.
- ``budget``: anywhere: the child's ``open`` (builtins, io, pathlib) hands out files under ``DISK``
  that share a budget of that many bytes; the write that exceeds it writes what fits and raises
  ``OSError(ENOSPC)``, as a full disk does.  Deleting a file gives nothing back (harsher than a disk).
The script runs with ``DISK`` (a ``pathlib.Path``) defined, inspects what it left there (a tmpfs
vanishes with its namespace) and prints its findings as one JSON line, which ``run`` returns.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import pytest

DISKS = ["tmpfs", "budget"]

_BUDGET = '''
import builtins, errno, io, pathlib
_open = io.open
_free = [{size}]

class _Full:
    def __init__(self, fh):
        self._fh = fh
    def write(self, data):
        size = len(memoryview(data).cast("B")) if not isinstance(data, str) else len(data.encode())
        if size > _free[0]:
            fit = _free[0]
            _free[0] = 0
            if fit:
                self._fh.write(data[:fit])
            raise OSError(errno.ENOSPC, "No space left on device")
        _free[0] -= size
        return self._fh.write(data)
    def writelines(self, lines):
        for line in lines:
            self.write(line)
    def __enter__(self):
        return self
    def __exit__(self, *exc):
        self._fh.close()
    def __iter__(self):
        return iter(self._fh)
    def __getattr__(self, name):
        return getattr(self._fh, name)

def _limited(file, mode="r", *args, **kwargs):
    fh = _open(file, mode, *args, **kwargs)
    inside = isinstance(file, (str, bytes, pathlib.PurePath)) and str(pathlib.Path(file).absolute()).startswith(str(DISK))
    return _Full(fh) if inside and any(c in mode for c in "wax+") else fh

builtins.open = io.open = _limited
'''


def run(kind: str, tmp_path, size: int, script: str, timeout: float = 120) -> dict:
    """Run ``script`` with ``DISK`` = ``tmp_path / 'disk'`` a disk of ``size`` bytes; its JSON line."""
    disk = tmp_path / "disk"
    disk.mkdir()
    prelude = f"import pathlib\nDISK = pathlib.Path({str(disk)!r})\n"
    if kind == "budget":
        prelude += _BUDGET.format(size=size)
    source = prelude + textwrap.dedent(script)
    command = [sys.executable, "-c", source]
    if kind == "tmpfs":
        unshare = shutil.which("unshare")
        probe = unshare and subprocess.run([unshare, "-rm", "true"], capture_output=True).returncode == 0
        if not probe:
            pytest.skip("no private mount namespace here (unshare -rm): the 'budget' disk covers this case")
        command = [unshare, "-rm", "sh", "-c", f'mount -t tmpfs -o size={size} none "$0" && exec "$@"', str(disk),
                   *command]
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, cwd=tmp_path)
    lines = done.stdout.strip().splitlines()
    assert done.returncode == 0 and lines, (done.returncode, done.stdout, done.stderr)
    return json.loads(lines[-1])
