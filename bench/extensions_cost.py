"""What the effects beyond the thesis cost: off, against the core before they existed; on, each alone.

    .venv/bin/python bench/extensions_cost.py [--core-commit cfdb766] [--repeat 5]

The core is checked out at ``--core-commit`` (the last commit before wicking, drying, wet
stiffness and currents) into a temporary git worktree and timed in a child process, alternating
with the current code, on the towel landing (21 x 29, 3 s, every effect off).  Each effect is then
switched on alone in the current code.  The current code runs the compiled core and
``--core-commit`` numba's kernels: "every effect off" against the core measures that change too.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIMER = """
import json, sys, time
import wetcloth
overrides = json.loads(sys.argv[1])
scene = wetcloth.Scene(nx=21, ny=29, **overrides)
wetcloth.Simulation(scene).advance(0.05)  # untimed warm-up (at --core-commit: numba compiles or loads the kernels)
best = float("inf")
for _ in range({repeat}):
    sim = wetcloth.Simulation(scene)
    start = time.perf_counter()
    sim.advance(3.0)
    best = min(best, time.perf_counter() - start)
print(json.dumps(dict(seconds=best, steps=sim.steps)))
"""
EFFECTS = {
    "every effect off": {},
    "wicking_rate = 1e-4 m2/s": {"wicking_rate": 1e-4},
    "drying_rate = 0.01 1/s": {"drying_rate": 0.01},
    "wet_stiffness_factor = -0.3": {"wet_stiffness_factor": -0.3},
    "current_x = 0.1 m/s": {"current_x": 0.1},
}


def time_run(source: Path, overrides: dict, repeat: int) -> dict:
    env_path = str(source / "fmu_src")
    out = subprocess.run([sys.executable, "-c", TIMER.format(repeat=repeat), json.dumps(overrides)],
                         env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"}, capture_output=True, text=True,
                         check=True, cwd=source)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--core-commit", default="cfdb766")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        core = Path(tmp) / "core"
        subprocess.run(["git", "worktree", "add", "--detach", str(core), args.core_commit], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            core_run = time_run(core, {}, args.repeat)
            now_run = time_run(ROOT, {}, args.repeat)
            core_again = time_run(core, {}, args.repeat)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(core)], cwd=ROOT, check=True)
    core_best = min(core_run["seconds"], core_again["seconds"])
    print("Towel landing, 21 x 29, 3 s simulated, best of", args.repeat)
    print("| code | effects | run time | steps | against the core |")
    print("|---|---|---|---|---|")
    print(f"| core ({args.core_commit}) | - | {core_best:.3f} s | {core_run['steps']} | 1.00x |")
    for name, overrides in EFFECTS.items():
        run = now_run if not overrides else time_run(ROOT, overrides, args.repeat)
        print(f"| current | {name} | {run['seconds']:.3f} s | {run['steps']} | {run['seconds'] / core_best:.2f}x |",
              flush=True)


if __name__ == "__main__":
    main()
