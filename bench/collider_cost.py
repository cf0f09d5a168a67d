"""What colliders cost: those the cloth never touches (issue 26: under 5 %), and a cloth lying on a mesh.

    .venv/bin/python bench/collider_cost.py [--repeat 5] [--duration 5] [--part far|lying|both|moving]
                                            [--frame-steps]

Far (``--part far``): the default towel at 41 x 57 lands on the water for ``--duration`` s: without
colliders, with a far analytic sphere, with the bucket mesh collider (models/meshes/bucket.ply, 1200
triangles) far away, and with the bucket right under the floating towel, its rim 2 cm under the water (the
box test skips it too while the cloth floats above).  Each run's CPU seconds, best and median of
``--repeat`` rounds taken in turn, and the ratio to the run without colliders; the step counts show the
runs are the same.

Lying (``--part lying``): a cloth that lies on a mesh collider, where the edges' pass (docs/model.md
section 6.3) works in every step: the ``bucket`` preset for 6 s, and a 15 x 15 sheet (0.4 m) dropped onto
an icosphere of 5120 faces (radius 0.15 m, tests/test_mesh_colliders.py) for 2 s.  CPU seconds (best and
median), accepted and rejected steps, ms per step, CG iterations per Newton iteration.

Moving (``--part moving``, docs/model.md section 6.3 "Moving colliders"): the ``sweep`` preset (a ball
sweeping through a hanging towel) for 4 s, with its collider keys and without them (the ball never
reaches the towel), and with the ball also turning 170 deg about the vertical as it sweeps (a turning
collider: friction against its surface's velocity), and the same two with the ball a mesh (an icosphere of
1280 faces: the edges' pass runs in its moving frame), as the lying part prints them.  ``--frame-steps``:
the same cases at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step = 1/30``).
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import wetcloth  # noqa: E402
from wetcloth.scene import preset_dir  # noqa: E402

BUCKET = str(preset_dir() / "meshes" / "bucket.ply")
CASES = {
    "none": (),
    "far sphere": ({"shape": "sphere", "x": 5.0, "radius": 0.3},),
    "far bucket mesh": ({"shape": "mesh", "file": BUCKET, "x": 5.0},),
    "bucket mesh under": ({"shape": "mesh", "file": BUCKET, "z": -0.32},),
}


def lying_cases(folder: str) -> dict:
    """The scenes of a cloth lying on a mesh collider, with their durations (s)."""
    import trimesh

    ball = os.path.join(folder, "ball.stl")
    trimesh.creation.icosphere(subdivisions=4, radius=0.15).export(ball)
    sheet = wetcloth.load_scene(nx=15, ny=15, width=0.4, length=0.4, initial_tilt=0.0, water_level=-0.5,
                                initial_height=0.16, colliders=({"shape": "mesh", "file": ball, "friction": 0.5},))
    return {"bucket preset": (wetcloth.load_scene("bucket"), 6.0), "sheet on icosphere": (sheet, 2.0)}


def timed_cases(cases: dict, repeat: int) -> None:
    """Run each case (name -> (scene, duration s)) ``repeat`` times in turn; print CPU seconds (best, median),
    accepted and rejected steps, ms per step, CG iterations per Newton iteration."""
    times = {name: [] for name in cases}
    counts = {}
    for _ in range(repeat):
        for name, (scene, duration) in cases.items():
            sim = wetcloth.Simulation(scene)
            start = time.process_time()
            sim.advance(duration)
            times[name].append(time.process_time() - start)
            solves = sim.solver_counts
            counts[name] = (duration, sim.steps, sim.rejected_steps,
                            solves["cg_iterations"] / solves["newton_iterations"])
    for name, t in times.items():
        duration, steps, rejected, cg = counts[name]
        print(f"{name:<18} {duration:3.0f} s  best {min(t):6.2f} s  median {statistics.median(t):6.2f} s  "
              f"steps {steps:5d}  rejected {rejected:5d}  {1000 * min(t) / steps:.2f} ms a step  "
              f"CG a Newton iteration {cg:.2f}", flush=True)


def lying(repeat: int) -> None:
    with tempfile.TemporaryDirectory() as folder:
        timed_cases(lying_cases(folder), repeat)


def moving(repeat: int, frame_steps: bool) -> None:
    import trimesh

    sweep = wetcloth.load_scene("sweep")
    if frame_steps:
        sweep = sweep.replace(integrator="implicit_euler", tolerance=0.0, max_step=1.0 / 30.0)
    spinning = sweep.replace(collider_key2_rz=170.0)  # the ball turns 170 deg about the vertical as it sweeps
    with tempfile.TemporaryDirectory() as folder:
        ball = os.path.join(folder, "ball.stl")  # the ball as a mesh (1280 faces): its edges' pass in its frame
        trimesh.creation.icosphere(subdivisions=3, radius=0.12).export(ball)
        mesh = sweep.replace(colliders=({"shape": "mesh", "file": ball, "y": -0.3, "z": 0.35, "friction": 0.4},))
        timed_cases({"sweep": (sweep, 4.0), "sweep, no keys": (sweep.replace(collider_keys=()), 4.0),
                     "sweep, spinning": (spinning, 4.0), "sweep, mesh ball": (mesh, 4.0),
                     "mesh ball spinning": (mesh.replace(collider_key2_rz=170.0), 4.0)}, repeat)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--duration", type=float, default=5.0)
    parser.add_argument("--part", choices=("far", "lying", "both", "moving"), default="both")
    parser.add_argument("--frame-steps", action="store_true", help="moving part: at fixed frame steps")
    args = parser.parse_args()
    if args.part == "moving":
        moving(args.repeat, args.frame_steps)
        return
    if args.part != "far":
        lying(args.repeat)
    if args.part == "lying":
        return
    times = {name: [] for name in CASES}
    steps = {}
    for _ in range(args.repeat):
        for name, colliders in CASES.items():
            sim = wetcloth.Simulation(wetcloth.load_scene(nx=41, ny=57, colliders=colliders))
            start = time.process_time()
            sim.advance(args.duration)
            times[name].append(time.process_time() - start)
            steps[name] = sim.steps
    base = min(times["none"])
    for name, t in times.items():
        print(f"{name:<18} best {min(t):6.2f} s  median {statistics.median(t):6.2f} s  steps {steps[name]:5d}  "
              f"{min(t) / base:.3f}x of none", flush=True)


if __name__ == "__main__":
    main()
