"""The cloth's mechanical energy: kinetic, gravitational and the springs' elastic energy (J).

What the fixed-step mode promises not to grow (docs/model.md section 7) and what the hanging-sheet
benchmark reports.  Water's forces (buoyancy, drag) and its uptake are not counted: it is the energy
of a cloth in air.
"""

from __future__ import annotations

import numpy as np

from wetcloth._core import BUCKLING_STRAIN, GRAVITY, TENSION_ROUNDING


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


def buckling_energy(stretch: np.ndarray, stiffness: np.ndarray, width: np.ndarray) -> float:
    """Energy (J) of buckling springs (spring_law.hpp's buckled_stretch) of ``stiffness`` (N/m) stretched by
    ``stretch`` (m), their push rounded off over ``width`` (m, BUCKLING_STRAIN times the rest length):
    ``k s^2 / 2`` while pulling; compressed by x, ``k (x^2 / 2 - x^3 / (12 w))`` up to x = 2 w, then
    ``k (4 w^2 / 3 + w (x - 2 w))``."""
    x = np.maximum(-stretch, 0.0)
    pulling = 0.5 * np.maximum(stretch, 0.0) ** 2
    rounded = x**2 / 2 - x**3 / (12 * width)
    beyond = 4 / 3 * width**2 + width * (x - 2 * width)
    return float(np.sum(stiffness * (pulling + np.where(x < 2 * width, rounded, beyond))))


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
    energy += buckling_energy(stretch[t:b], cloth.pair_stiffness[t:b], BUCKLING_STRAIN * cloth.pair_rest[t:b])
    energy += elastic_energy(stretch[b:], cloth.pair_stiffness[b:], None)
    return float(energy)
