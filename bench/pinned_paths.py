"""What checking keys against the pinned particles costs (wetcloth/pinned_paths.py), when a scene is loaded.

    .venv/bin/python bench/pinned_paths.py [--repeat 5]

The ``sweep`` preset's towel (pinned by its top row) with its ball keyed back and forth 1.2 m along x 50 times
(60 m), far from the towel and grazing the pinned row 3 mm above it; and the hostile trial's half-space keyed
through the pinned row (refused; it used to run for 290 s of CPU).  Seconds of CPU per ``Scene.replace``, the best
of ``--repeat``, and the same replace without keys, in the same process.
"""

from __future__ import annotations

import argparse
import time

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.scene import Collider, ColliderKey

TOP = 0.85  # m: the sweep towel's pinned row


def timed(base: wetcloth.Scene, repeat: int, **changes) -> tuple[float, str]:
    """The least CPU time (s) of base.replace(**changes), and 'refused' or 'accepted'."""
    best, outcome = float("inf"), ""
    for _ in range(repeat):
        start = time.process_time()
        try:
            base.replace(**changes)
            outcome = "accepted"
        except ParameterError:
            outcome = "refused"
        best = min(best, time.process_time() - start)
    return best, outcome


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    repeat = parser.parse_args().repeat
    base = wetcloth.load_scene("sweep")
    back_and_forth = tuple(ColliderKey(collider=1, time=1.0 + j, x=1.2 if j % 2 == 0 else 0.0) for j in range(50))
    plane = Collider(shape="plane", x=0.0, y=-0.3, z=0.135, normal_x=0.0, normal_y=1.0, normal_z=0.0, friction=0.41)
    half_space = (ColliderKey(collider=1, time=0.936, x=0.197, y=0.192, z=-0.281, rx=-57.5),
                  ColliderKey(collider=1, time=1.233, x=0.284, y=0.149, z=-0.116, rz=-21.7))
    cases = {
        "ball without keys": dict(colliders=(Collider(shape="sphere", x=-0.6, y=-2.0, z=0.35, radius=0.12),),
                                  collider_keys=()),
        "ball 2 m away, 50 keys": dict(colliders=(Collider(shape="sphere", x=-0.6, y=-2.0, z=0.35, radius=0.12),),
                                       collider_keys=back_and_forth),
        "ball grazing the pins, 50 keys": dict(
            colliders=(Collider(shape="sphere", x=-0.6, y=0.0, z=TOP + 0.123, radius=0.12),),
            collider_keys=back_and_forth),
        "half-space through the pins": dict(colliders=(plane,), collider_keys=half_space),
    }
    for label, changes in cases.items():
        seconds, outcome = timed(base, repeat, **changes)
        print(f"{label:32s} {seconds:.4f} s CPU, {outcome}")


if __name__ == "__main__":
    main()
