"""The kernels' compile cache: a warm start compiles nothing, and no edit of a kernel source, in any
file, leaves stale machine code in use (wetcloth/kernels/compilation.py)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

from wetcloth.kernels import compilation

# A kernel calling a kernel of another file and using a constant of that file: the two ways a
# caller's machine code depends on another file (numba checks only the caller's own file).
CALLEE = '''
from wetcloth.kernels import kernel

FACTOR = {factor}


@kernel
def inner(a):
    total = 0.0
    for i in range(a.shape[0]):
        total += {power} * a[i]
    return total
'''
CALLER = '''
from wetcloth.kernels import kernel
from kpkg.callee import FACTOR, inner


@kernel
def outer(a):
    return FACTOR * inner(a)
'''
CHILD = '''
import json, sys
import numpy as np
from numba.core import event
compiled = []
class Count(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)
    def on_end(self, ev):
        pass
event.register("numba:compile", Count())
sys.path.insert(0, sys.argv[1])
from kpkg.caller import outer
print(json.dumps({"value": outer(np.arange(4.0)), "compiled": compiled}))
'''


def _run(folder: Path) -> dict:
    done = subprocess.run([sys.executable, "-c", CHILD, str(folder)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def _write(package: Path, factor: float, power: float) -> None:
    (package / "callee.py").write_text(textwrap.dedent(CALLEE.format(factor=factor, power=power)))


def test_a_warm_start_compiles_nothing_and_an_edit_of_another_file_is_never_stale(tmp_path):
    """0 + 1 + 2 + 3 = 6: outer = FACTOR * power * 6.  The first run compiles the caller and its
    callee; the second loads both and compiles nothing; after the callee's file changes (both the
    constant the caller reads and the callee's code), the caller's cached code must not be used."""
    package = tmp_path / "kpkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "caller.py").write_text(CALLER)
    _write(package, factor=2.0, power=1.0)
    first = _run(tmp_path)
    assert first["value"] == 12.0 and {"outer", "inner"} <= set(first["compiled"])
    warm = _run(tmp_path)
    assert warm == {"value": 12.0, "compiled": []}
    _write(package, factor=3.0, power=5.0)
    edited = _run(tmp_path)
    assert edited["value"] == 90.0, "machine code compiled from the old sources was used"


def test_every_kernel_is_cached_against_the_whole_kernel_package():
    kernels = Path(compilation.__file__).parent
    assert compilation._scope(str(kernels / "water.py")) == kernels
    assert compilation._scope("/elsewhere/module.py") == Path("/elsewhere")
