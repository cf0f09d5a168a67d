"""The compiled core's builds (wetcloth/core_build.py): the one loaded is the fastest the CPU runs, a
build picked by ``WETCLOTH_CORE`` is checked, and the x86-64-v3 build steps every kind of scene to the
same bits as the baseline one (both in fresh processes on this machine: no stored reference)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from wetcloth import core_build
from support.hanging import HANGING

#: A scene of every kind of work the core does, each with overrides and seconds: water and absorption,
#: the grid's V-cycle and self-collision (41 across: past the band factors), the fixed-step mode with its
#: coarse space, a collider moved by keys, a mesh cloth (listed springs, algebraic multigrid) sliding on
#: a cylinder, a mesh collider with water, wind.
SCENES = [
    ("towel", {}, 2.0),
    ("towel", dict(nx=41, ny=41, self_collision="on", **HANGING), 0.3),
    ("towel", dict(nx=41, ny=41, integrator="implicit_euler", tolerance=0.0, max_step=1 / 30, **HANGING), 0.2),
    ("sweep", {}, 0.5),
    ("tablecloth", {}, 0.1),
    ("bucket", {}, 0.3),
    ("flag", {}, 0.3),
]

CHILD = """
import hashlib, json, sys
import wetcloth
from wetcloth import core_build
digests = []
for preset, overrides, duration in json.loads(sys.argv[1]):
    sim = wetcloth.Simulation(wetcloth.load_scene(preset, **overrides))
    sim.advance(duration)
    state = b"".join(a.tobytes() for a in (sim.state.pos, sim.state.vel, sim.state.water))
    digests.append([sim.steps, sim.rejected_steps, sim.solver_counts, hashlib.sha256(state).hexdigest()])
print(json.dumps({"build": core_build.running(), "digests": digests}))
"""


def run_child(build: str | None) -> dict:
    """The child's report, run with WETCLOTH_CORE=build (None: unset)."""
    env = {k: v for k, v in os.environ.items() if k != core_build.ENVIRONMENT}
    if build is not None:
        env[core_build.ENVIRONMENT] = build
    done = subprocess.run([sys.executable, "-c", CHILD, json.dumps(SCENES)], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.skipif(not core_build.runnable("x86-64-v3"), reason="the x86-64-v3 build is not installed or this CPU does not run it")
def test_both_builds_step_every_kind_of_scene_to_the_same_bits():
    """Without fast-math or fused multiply-adds, wider vectors change no result: the same steps, the same
    Newton and CG counts and the same bytes of positions, velocities and water in every scene."""
    baseline, v3 = run_child("baseline"), run_child("x86-64-v3")
    assert (baseline["build"], v3["build"]) == ("baseline", "x86-64-v3")
    for (preset, _, _), ours, theirs in zip(SCENES, baseline["digests"], v3["digests"]):
        assert ours == theirs, preset


def test_import_loads_the_fastest_build_this_cpu_runs():
    assert run_child(None)["build"] == ("x86-64-v3" if core_build.runnable("x86-64-v3") else "baseline")


V3_CPU = {"X86_V3": True}
OLD_CPU = {"AVX": True, "AVX2": False, "FMA3": False}


def everything(build):
    return True


def test_the_choice_falls_back_to_the_baseline_where_the_cpu_or_the_install_lacks_x86_64_v3():
    assert core_build.choose(None, V3_CPU, everything) == "x86-64-v3"
    assert core_build.choose(None, OLD_CPU, everything) == "baseline"
    assert core_build.choose(None, {}, everything) == "baseline"  # (not x86, or numpy hides the features)
    assert core_build.choose(None, V3_CPU, lambda build: build == "baseline") == "baseline"
    # numpy before 2.3 names no X86_V3: its parts decide.
    assert core_build.choose(None, {"AVX": True, "AVX2": True, "FMA3": True, "F16C": True}, everything) == "x86-64-v3"
    assert core_build.choose("baseline", V3_CPU, everything) == "baseline"


@pytest.mark.parametrize(("requested", "features", "available", "message"), [
    ("avx2", V3_CPU, everything, "WETCLOTH_CORE must be one of 'baseline', 'x86-64-v3'"),
    ("x86-64-v3", OLD_CPU, everything, "this CPU lacks x86-64-v3"),
    ("x86-64-v3", V3_CPU, lambda build: build == "baseline", "this install has no such build"),
])
def test_a_build_the_environment_cannot_have_is_refused_by_name(requested, features, available, message):
    with pytest.raises(ImportError, match=message):
        core_build.choose(requested, features, available)


def test_the_loaded_build_is_wetcloth_core_by_every_way_of_naming_it():
    import wetcloth
    from wetcloth import _core

    assert wetcloth._core is _core is sys.modules["wetcloth._core"]
    assert _core.__spec__.name == core_build.MODULES[core_build.running()]
