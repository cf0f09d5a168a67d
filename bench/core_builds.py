"""The compiled core's two builds against each other: the x86-64-v3 build (AVX2) and the baseline one,
on the same scenes (docs/core.md, "How it builds").

    .venv/bin/python bench/core_builds.py [--repeat 3] [--cases hanging fixed landing tablecloth study]

Each case runs in a fresh process with ``WETCLOTH_CORE`` set, the two builds in turn, ``--repeat``
rounds; prints the best CPU time of each, their ratio, and whether both ended the same (steps, counts and
positions to the bit; they should).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

from wetcloth import core_build  # noqa: E402

HANGING = ("nx=81, ny=81, width=1.0, length=1.0, pinned_edge='y_max', initial_tilt=0.0, initial_height=2.0, "
           "water_level=-10.0, floor_level=-20.0, self_collision='on'")


def advanced(scene: str, duration: float) -> str:
    """A case's source: a Simulation of `scene` (load_scene's arguments) advanced `duration` s."""
    return (f"sim = wetcloth.Simulation(wetcloth.load_scene({scene}))\nsim.advance({duration})\n"
            "result = [sim.steps, sim.solver_counts, sim.state.pos.tobytes().hex()]")


#: What each case runs (Python source leaving its deterministic result in `result`), with what it is.
CASES = {
    "hanging": ("hanging sheet 81 x 81, default, self-collision on, 1 s", advanced(HANGING, 1.0)),
    "fixed": ("the same, implicit_euler at frame steps, 3 s",
              advanced(HANGING + ", integrator='implicit_euler', tolerance=0.0, max_step=1 / 30", 3.0)),
    "landing": ("towel 64 x 64 landing on water, 3 s", advanced("'towel', nx=64, ny=64", 3.0)),
    "tablecloth": ("round tablecloth (2k-vertex mesh) on its table, 0.5 s", advanced("'tablecloth'", 0.5)),
    "study": ("towel_sink_sensitivity.toml, every 16th run",
              "from wetcloth.batch.engines import python_series\nfrom wetcloth.batch.spec import load_study\n"
              "from wetcloth.scene import preset_dir\n"
              "study = load_study(preset_dir() / 'studies' / 'towel_sink_sensitivity.toml')\n"
              "result = [{k: v.tobytes().hex() for k, v in python_series(run.params, study.duration, "
              "study.sample_rate).items()} for run in study.runs()[::16]]"),
}

CHILD = """
import json, time
import wetcloth
start = time.process_time()
{case}
print(json.dumps({{"cpu": time.process_time() - start, "result": result}}))
"""


def run(case: str, build: str) -> dict:
    """The case's CPU time (s) and deterministic result with the given build."""
    env = dict(os.environ, **{core_build.ENVIRONMENT: build})
    done = subprocess.run([sys.executable, "-c", CHILD.format(case=CASES[case][1])], env=env, capture_output=True,
                          text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    args = parser.parse_args()
    if not core_build.runnable("x86-64-v3"):
        parser.exit(1, "the x86-64-v3 build is not installed or this CPU does not run it: nothing to compare\n")
    print("| case | baseline (s) | x86-64-v3 (s) | ratio | same result |\n|---|---|---|---|---|")
    for case in args.cases:
        best = {"baseline": None, "x86-64-v3": None}
        for _ in range(args.repeat):
            for build in best:
                result = run(case, build)
                if best[build] is None or result["cpu"] < best[build]["cpu"]:
                    best[build] = result
        base, v3 = best["baseline"], best["x86-64-v3"]
        same = base["result"] == v3["result"]
        print(f"| {CASES[case][0]} | {base['cpu']:.2f} | {v3['cpu']:.2f} | {v3['cpu'] / base['cpu']:.2f}x | "
              f"{'yes' if same else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
