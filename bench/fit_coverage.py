"""Coverage of the fit's 95 % intervals: synthetic data from known parameters plus seeded noise.

    .venv/bin/python bench/fit_coverage.py [--trials 20] [--nx 9 --ny 13] [--noise 1]

The towel preset on an ``nx`` x ``ny`` grid with absorption_rate 0.3 1/s and absorption_capacity
3.8 kg/kg: depth and wet mass at 1 Hz over 60 s plus Gaussian noise (``--noise`` times 1 mm and
1 g; seeds ``--first-seed``, + 1, ...).  Each trial fits both from 0.27 1/s and 4.2 kg/kg twice: with the sigma
given (sigma columns) and with the sigma estimated from the residuals.  Printed: how often each
true value lies within its 95 % interval, and the mean and spread of the errors in standard errors
(z = (estimate - truth) / standard error: mean 0 and spread 1 when the intervals are right).
Issue 28 asks for at least 17 of 20; tests/test_fit.py runs 20 trials on a 5 x 5 grid with sigma given.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy import stats

import wetcloth
from wetcloth.calibration import Curves, fit

TRUTH = {"absorption_rate": 0.3, "absorption_capacity": 3.8}
START = {"absorption_rate": 0.27, "absorption_capacity": 4.2}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--nx", type=int, default=9)
    parser.add_argument("--ny", type=int, default=13)
    parser.add_argument("--noise", type=float, default=1.0, help="noise in mm and g (default 1)")
    parser.add_argument("--first-seed", type=int, default=0, help="seeds first-seed, first-seed + 1, ... (default 0)")
    args = parser.parse_args()
    scene = wetcloth.load_scene("towel", nx=args.nx, ny=args.ny, **TRUTH)
    times = np.arange(0.0, 60.01, 1.0)
    clean = wetcloth.Simulation(scene).sample(times)
    columns = {n: wetcloth.OUTPUT_NAMES.index(n) for n in ("depth", "wet_mass")}
    truth = np.array(list(TRUTH.values()))
    sigma = 1e-3 * args.noise
    for given in (True, False):
        inside, z, runs, started = np.zeros(2, int), [], 0, time.perf_counter()
        for seed in range(args.first_seed, args.first_seed + args.trials):
            rng = np.random.default_rng(seed)
            values = {n: clean[:, c] + rng.normal(0.0, sigma, times.size) for n, c in columns.items()}
            data = Curves(times=times, values=values,
                          sigma={n: np.full(times.size, sigma) if given else None for n in columns})
            result = fit(scene.replace(**START), data, list(TRUTH))
            inside += (result.intervals[:, 0] <= truth) & (truth <= result.intervals[:, 1])
            z.append((result.estimates - truth) / result.standard_errors)
            runs += result.runs
        z = np.array(z)
        # how likely this count or fewer is if the intervals hold 95 %
        chance = stats.binom.cdf(inside, args.trials, 0.95)
        print(f"towel {args.nx} x {args.ny}, noise {args.noise:g} mm / {args.noise:g} g, sigma "
              f"{'given' if given else 'estimated'}: {args.trials} trials, {runs} runs, {time.perf_counter() - started:.1f} s")
        for j, name in enumerate(TRUTH):
            print(f"  {name:20s} truth inside the 95 % interval in {inside[j]} of {args.trials} "
                  f"(P(<= that | 95 %) = {chance[j]:.2f}); z mean {z[:, j].mean():+.2f}, spread {z[:, j].std(ddof=1):.2f}")


if __name__ == "__main__":
    main()
