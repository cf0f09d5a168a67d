"""How a spinning ball drags the towel it sweeps through: the analytic ball against the same ball as a mesh.

    .venv/bin/python bench/spinning_drag.py

The ``sweep`` preset with its ball turning 170 deg about the vertical as it sweeps (0.5 to 2 s, 1.98 rad/s;
``bench/collider_cost.py --part moving``'s spinning cases), the ball analytic and an icosphere of 1280 faces
(its friction in the implicit step through the supports, docs/model.md 6.3).  Over four windows of the spin:
the towel's centroid x at the window's end (mm; the spin drags it sideways), and of the particles within NEAR
of the ball's sphere (how many a sample) their mean velocity about the ball's vertical axis relative to the
ball (m/s) against the surface's own there, omega r (m/s).
"""
from __future__ import annotations

import os
import tempfile

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402

RADIUS, START, END, TURN = 0.12, 0.5, 2.0, np.radians(170.0)  # m, s, s, rad
NEAR = 5e-3  # m: a particle this near the ball's sphere touches it (a mesh ball holds the cloth off its faces)
WINDOWS = ((1.0, 1.25), (1.25, 1.5), (1.5, 1.75), (1.75, 2.0))  # s
SAMPLE = 0.01  # s between samples in a window


def ball_at(t: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The ball's centre (3, m), velocity (3, m/s) and angular velocity about z (rad/s) at t (s)."""
    moving = START < t < END
    along = min(max(t - START, 0.0), END - START)
    centre = np.array([0.0, -0.3 + 0.4 * along, 0.35])
    return centre, np.array([0.0, 0.4 if moving else 0.0, 0.0]), TURN / (END - START) if moving else 0.0


def turning(sim) -> tuple[float, float, int]:
    """The touching particles' summed speed about the ball's vertical axis relative to the ball (m/s), the
    surface's summed speed there (m/s) and their count, now."""
    pos, vel = sim.state.pos, sim.state.vel
    centre, velocity, spin = ball_at(sim.time)
    arm = pos - centre[:, None]
    near = np.linalg.norm(arm, axis=0) - RADIUS < NEAR
    across = np.hypot(arm[0], arm[1])
    about = np.array([-arm[1], arm[0]]) / np.maximum(across, 1e-12)  # the azimuthal direction about z
    speed = ((vel[:2] - velocity[:2, None]) * about).sum(axis=0)
    return speed[near].sum(), (spin * across[near]).sum(), int(near.sum())


def drag(scene) -> None:
    """Per window: the towel's centroid x at its end, the touching particles' mean speed about the axis and
    the surface's (sampled every SAMPLE s), and the touching particles a sample; the same over all windows;
    the centroid at 4 s."""
    sim = wetcloth.Simulation(scene)
    sim.advance(WINDOWS[0][0])
    total = np.zeros(3)
    for start, end in WINDOWS:
        speed = surface = 0.0
        count = 0
        for t in np.arange(start, end, SAMPLE) + SAMPLE:
            sim.advance(t - sim.time)
            s, u, c = turning(sim)
            speed, surface, count = speed + s, surface + u, count + c
        total += (speed, surface, count)
        mean = speed / count if count else float("nan")
        print(f"  {start:4.2f}-{end:4.2f} s  centroid x {sim.state.pos[0].mean() * 1000:7.2f} mm  touching "
              f"{count * SAMPLE / (end - start):5.1f}  speed about the axis {mean:6.3f} m/s, the surface's "
              f"{surface / count if count else float('nan'):5.3f} m/s", flush=True)
    print(f"  {WINDOWS[0][0]:4.2f}-{WINDOWS[-1][1]:4.2f} s  speed about the axis {total[0] / total[2]:6.3f} m/s, the "
          f"surface's {total[1] / total[2]:5.3f} m/s", flush=True)
    sim.advance(4.0 - sim.time)
    print(f"  4 s  centroid x {sim.state.pos[0].mean() * 1000:7.2f} mm", flush=True)


def main() -> None:
    import trimesh

    spinning = wetcloth.load_scene("sweep").replace(collider_key2_rz=170.0)
    with tempfile.TemporaryDirectory() as folder:
        ball = os.path.join(folder, "ball.stl")
        trimesh.creation.icosphere(subdivisions=3, radius=RADIUS).export(ball)
        mesh = spinning.replace(colliders=({"shape": "mesh", "file": ball, "y": -0.3, "z": 0.35, "friction": 0.4},))
        for name, scene in (("analytic ball", spinning), ("mesh ball", mesh)):
            print(name, flush=True)
            drag(scene)


if __name__ == "__main__":
    main()
