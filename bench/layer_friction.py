"""Friction between the cloth's own layers: a 0.1 m sheet lying on a 0.3 m sheet on a slope, against Coulomb.

    .venv/bin/python bench/layer_friction.py [--angle 15] [--duration 0.2] [--factors 1.001 0.9 0]

One mesh cloth of two square quad sheets (2 cm spacing, the small one 2.001 mm, a thickness, above the large
one and turned off its grid lines), tilted by ``--angle`` about x; its UVs lay the two side by side, so that
self-collision takes the stack (docs/model.md section 2.4).  The large sheet is held either by pins (every
vertex) or by a plane under it of friction 5 (its vertices 1 um above their contact distance); the small one
has ``self_friction`` = each of ``--factors`` times tan(angle).  Coulomb: at or above tan(angle) the small
sheet stays; below, it slides (1 - factor) g sin(angle) t^2 / 2 down the slope.  Printed for the default
(BDF2, adaptive) and the fixed-step mode (``implicit_euler`` at 1/30 s): the small sheet's mean slide
against that (mm, and their ratio), the large sheet's, steps and steps taken again.  Backward Euler's frame
steps slide n (n + 1) / 2 where the exact slide is n^2 / 2 steps' worth (7/6 at 6 steps): more, not less.
"""

from __future__ import annotations

import argparse
import math
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import wetcloth  # noqa: E402
from wetcloth._core import GRAVITY  # noqa: E402
import _paths  # noqa: E402,F401  (tests/ on sys.path)
from support.layers import stack_scene  # noqa: E402

MODES = {"default (bdf2, adaptive)": {},
         "fixed-step mode (implicit_euler, 1/30 s)": dict(integrator="implicit_euler", tolerance=0.0, max_step=1 / 30)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--angle", type=float, default=15.0, help="slope (deg)")
    parser.add_argument("--duration", type=float, default=0.2, help="simulated s")
    parser.add_argument("--factors", type=float, nargs="+", default=[1.001, 0.9, 0.0],
                        help="self_friction as multiples of tan(angle)")
    args = parser.parse_args()
    tangent = math.tan(math.radians(args.angle))
    for held_by in ("pins", "plane"):
        for mode, settings in MODES.items():
            for factor in args.factors:
                scene, large, downhill = stack_scene(args.angle, factor * tangent, held_by, **settings)
                sim = wetcloth.Simulation(scene)
                start = sim.positions.copy()
                sim.advance(args.duration)
                slide = (sim.positions - start) @ downhill
                expected = 0.5 * max(0.0, 1.0 - factor) * GRAVITY * math.sin(math.radians(args.angle)) * args.duration ** 2
                ratio = f"{slide[large:].mean() / expected:5.3f}" if expected > 0.0 else "  -  "
                print(f"held by {held_by:5s}  {mode:40s}  self_friction {factor:5.3f} tan a: small sheet slid "
                      f"{1e3 * slide[large:].mean():7.3f} mm, Coulomb {1e3 * expected:7.3f} mm, ratio {ratio}; "
                      f"large sheet {1e3 * slide[:large].mean():6.3f} mm; steps {sim.steps:4d}, taken again "
                      f"{sim.rejected_steps:3d}", flush=True)


if __name__ == "__main__":
    main()
