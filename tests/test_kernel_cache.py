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


BUNDLES = '''
from wetcloth.kernels import {decorator}


@{decorator}
def first(a):
    return a[0]


@{decorator}
def bundle_sum(bundle, out):
    out[0] = first(bundle.a) + first(bundle.b)
'''


def test_kernels_count_no_references_unless_counted(tmp_path, monkeypatch):
    """``kernel`` compiles with numba's reference counting off: a kernel passing a bundle of arrays
    on to another kernel, as the step loop does, takes and releases no references (no NRT_incref
    or NRT_decref in its code); compiled by ``counted_kernel`` the same kernel does."""
    import importlib
    from collections import namedtuple

    import numpy as np

    monkeypatch.syspath_prepend(str(tmp_path))
    bundle = namedtuple("Bundle", "a b")(np.ones(3), np.full(3, 2.0))
    codes = {}
    for decorator in ("kernel", "counted_kernel"):
        (tmp_path / f"bundles_{decorator}.py").write_text(BUNDLES.format(decorator=decorator))
        module = importlib.import_module(f"bundles_{decorator}")
        out = np.zeros(1)
        module.bundle_sum(bundle, out)
        assert out[0] == 3.0
        (result,) = module.bundle_sum.overloads.values()
        codes[decorator] = result.library.get_llvm_str()
    assert "NRT_incref" not in codes["kernel"] and "NRT_decref" not in codes["kernel"]
    assert "NRT_decref" in codes["counted_kernel"]
