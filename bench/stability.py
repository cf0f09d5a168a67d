"""Numerical stability under stress: the largest stable fixed step of each integrator against the
stretch stiffness, and a sweep showing that the default adaptive mode never blows up.

    .venv/bin/python bench/stability.py [--quick]

"Stable" is defined in ``tests/support/stress.py``: no blow-up and kinetic energy within what the scene
could release.  Scene: a 9 x 9 towel dropped 10 cm onto water, 0.3 s.  Writes
``docs/stability.csv`` and the stability map ``docs/stability.png``.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import wetcloth  # noqa: E402
import _paths  # noqa: E402,F401  (tests/ on sys.path for the oracles)
from support.stress import stress_run  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "docs"
BASE = dict(nx=9, ny=9)
DURATION = 0.3  # s
STIFFNESSES = [1e1, 1e2, 1e3, 1e4, 1e5, 1e6]  # N/m
INTEGRATORS = ["explicit_euler", "symplectic_euler", "implicit_euler", "bdf2"]


def largest_stable_step(integrator: str, stiffness: float, lo=1e-6, hi=0.05, rounds=8) -> float:
    """Bisection in log h between a stable ``lo`` and an unstable ``hi`` (s); 0 if even ``lo`` fails
    (shorter steps are not searched: 0.3 s at 1 us is already 300 000 steps)."""
    scene = wetcloth.load_scene(**BASE, stretch_stiffness=stiffness, integrator=integrator, tolerance=0.0)
    if stress_run(scene.replace(max_step=hi), DURATION).stable:
        return hi
    if not stress_run(scene.replace(max_step=lo), DURATION).stable:
        return 0.0
    for _ in range(rounds):
        mid = math.sqrt(lo * hi)
        if stress_run(scene.replace(max_step=mid), DURATION).stable:
            lo = mid
        else:
            hi = mid
    return lo


def adaptive_sweep(quick: bool) -> list[dict]:
    """Every integrator in adaptive mode over stiffness, areal density, absorption rate and water jumps."""
    densities = [0.05, 0.45, 5.0]
    rates = [0.0, 0.15, 1000.0]  # 1/s; 1000 saturates on contact
    jumps = {"none": None, "up 5 cm": {0.15: 0.05}, "down 5 cm": {0.15: -0.05}}
    stiffnesses = [1e1, 1e3, 1e6] if quick else STIFFNESSES
    rows = []
    for integrator, k, density, rate, (jump, levels) in itertools.product(
            INTEGRATORS, stiffnesses, densities, rates, jumps.items()):
        scene = wetcloth.load_scene(**BASE, integrator=integrator, stretch_stiffness=k, areal_density=density,
                                    absorption_rate=rate)
        start = time.perf_counter()
        result = stress_run(scene, DURATION, water_levels=levels)
        rows.append(dict(integrator=integrator, stretch_stiffness=k, areal_density=density, absorption_rate=rate,
                         water_jump=jump, stable=result.stable, steps=result.steps,
                         wet_mass_decreased=result.wet_mass_decreased, seconds=time.perf_counter() - start,
                         reason=result.reason))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    OUT.mkdir(exist_ok=True)
    stiffnesses = [1e1, 1e3, 1e6] if args.quick else STIFFNESSES
    table = {integ: [largest_stable_step(integ, k) for k in stiffnesses] for integ in INTEGRATORS}
    print("Largest stable fixed step (s) against stretch stiffness:")
    print("| integrator | " + " | ".join(f"{k:g} N/m" for k in stiffnesses) + " |")
    print("|---|" + "---|" * len(stiffnesses))
    for integ, steps in table.items():
        print(f"| {integ} | " + " | ".join(f"{h:.2g}" if h else "< 1e-6" for h in steps) + " |", flush=True)
    rows = adaptive_sweep(args.quick)
    failures = [r for r in rows if not r["stable"] or r["wet_mass_decreased"]]
    print(f"\nAdaptive mode: {len(rows) - len(failures)} of {len(rows)} stressed runs stable, with non-decreasing "
          f"wet mass ({sum(r['seconds'] for r in rows):.0f} s).")
    for r in failures:
        print("  FAILED:", r)
    with open(OUT / "stability.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig, ax = plt.subplots(figsize=(6, 4.5), constrained_layout=True)
    for integ, steps in table.items():
        ax.loglog(stiffnesses, [max(h, 1e-8) for h in steps], "o-", label=integ)
    ax.set_xlabel("stretch_stiffness (N/m)")
    ax.set_ylabel("largest stable fixed step (s)")
    ax.set_title("stability map: 9 x 9 towel landing on water (capped at 0.05 s)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.savefig(OUT / "stability.png", dpi=100)
    print(f"wrote {OUT / 'stability.csv'} and {OUT / 'stability.png'}")


if __name__ == "__main__":
    main()
