"""The cloth's mechanical energy: kinetic, gravitational and the springs' elastic energy (J).

What the fixed-step mode promises not to grow (docs/model.md section 7) and what the hanging-sheet
benchmark reports.  Water's forces (buoyancy, drag) and its uptake are not counted: it is the energy
of a cloth in air.
"""

from __future__ import annotations

import numpy as np

from wetcloth._core import BUCKLING_ROUNDING, BUCKLING_STRAIN, GRAVITY, TENSION_ROUNDING


def elastic_energy(stretch: np.ndarray, stiffness: np.ndarray, width: float | None) -> float:
    """Energy (J) of springs of ``stiffness`` (N/m) stretched by ``stretch`` (m): ``k s^2 / 2`` both
    ways (``width`` None), or the integral of the tension-only law (docs/model.md section 3), rounded
    over its first ``width`` (m) of stretch and zero when compressed."""
    if width is None:
        return float(np.sum(0.5 * stiffness * stretch**2))
    s = np.maximum(stretch, 0.0)
    rounded = stiffness * (2 * s**3 / (3 * width) - s**4 / (4 * width**2))
    beyond = stiffness * (5 / 12 * width**2 + (s**2 - width**2) / 2)
    return float(np.sum(np.where(s < width, rounded, beyond)))


def buckling_energy(stretch: np.ndarray, stiffness: np.ndarray, rest: np.ndarray) -> float:
    """Energy (J) of buckling springs (spring_law.hpp's buckled_stretch) of ``stiffness`` (N/m) and ``rest``
    length (m) stretched by ``stretch`` (m): pulling, the tension-only law's rounded over c =
    BUCKLING_ROUNDING l; compressed by x, the integral of the push b r (2 - r), r = min(R(x) / (2 b), 1),
    b = BUCKLING_STRAIN l, R(x) the same onset: 2 x^2 / c - x^3 / c^2 below c, there the push R - R^2 / (4 b)
    (c < 2 b); then R(x) = x up to x = 2 b, and the push b beyond."""
    c, b = BUCKLING_ROUNDING * rest, BUCKLING_STRAIN * rest
    x = np.maximum(-stretch, 0.0)
    onset = np.minimum(x, c)
    ramp = np.clip(x, c, 2 * b)
    pushing = (2 * onset**3 / (3 * c) - onset**4 / (4 * c**2)
               - (4 * onset**5 / (5 * c**2) - 2 * onset**6 / (3 * c**3) + onset**7 / (7 * c**4)) / (4 * b)
               + (ramp**2 - c**2) / 2 - (ramp**3 - c**3) / (12 * b) + b * np.maximum(x - 2 * b, 0.0))
    return elastic_energy(stretch, stiffness, c) + float(np.sum(stiffness * pushing))


def mechanical_energy(sim) -> float:
    """Kinetic + gravitational (zero at z = 0) + elastic energy (J) of a Simulation's cloth, each spring
    (a grid's families, a mesh's listed springs: the first ``pair_tension_count`` tension-only, the next
    ``pair_buckling_count`` buckling) with its
    dry stiffness."""
    cloth, state = sim.model.cloth, sim.state
    mass = np.asarray(cloth.dry_mass) + state.water
    energy = 0.5 * np.sum(mass * state.vel**2) + GRAVITY * np.sum(mass * state.pos[2])
    for offset, rest, tension_only, stiffness in zip(cloth.offsets, cloth.rest, cloth.tension_only, cloth.stiffness):
        i = np.flatnonzero(stiffness)
        stretch = np.linalg.norm(state.pos[:, i] - state.pos[:, i + offset], axis=0) - rest
        energy += elastic_energy(stretch, stiffness[i], TENSION_ROUNDING * rest if tension_only else None)
    first, second = cloth.pairs
    stretch = np.linalg.norm(state.pos[:, first] - state.pos[:, second], axis=0) - cloth.pair_rest
    t = int(cloth.pair_tension_count)
    b = t + int(cloth.pair_buckling_count)
    energy += elastic_energy(stretch[:t], cloth.pair_stiffness[:t], TENSION_ROUNDING * cloth.pair_rest[:t])
    energy += buckling_energy(stretch[t:b], cloth.pair_stiffness[t:b], cloth.pair_rest[t:b])
    energy += elastic_energy(stretch[b:], cloth.pair_stiffness[b:], None)
    return float(energy)
