"""Work against precision: error against run time for every integrator, fixed steps and adaptive.

    .venv/bin/python bench/work_precision.py [--quick]

Reference scenes (a 15 x 21 towel, and a sheet):
  landing       the tilted towel dropped from 10 cm lands and floats (3 s)
  sinking       a towel soaking up water almost at once sinks (4 s)
  rising_water  a floating towel carried up by a water level rising 3 cm in 1 s (3 s)
  hanging_sheet a 41 x 41 sheet, 1 m square, released horizontal from one edge in air (1 s)

Each run is compared with a converged reference (BDF2, fixed 0.25 ms steps; its own error is
shown by halving that step).  Errors: centroid (max over the 30 Hz samples, m), vertex positions
(RMS over vertices and samples, m), wet mass (max relative).  Writes ``docs/work_precision.csv``
and ``docs/work_precision.png``.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402
import numpy as np  # noqa: E402

import _paths  # noqa: E402,F401  (tests/ on sys.path for the oracles)
from support.accuracy import REFERENCE_STEP, cases, errors, reference, simulate  # noqa: E402
from wetcloth.errors import BlowUpError  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "docs"
INTEGRATORS = ("explicit_euler", "symplectic_euler", "implicit_euler", "bdf2")


def settings_grid(quick: bool) -> list[dict]:
    tolerances = [1e-3, 1e-4, 1e-5, 5e-6] if quick else [3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 5e-6, 3e-6]
    implicit_steps = [1 / 30, 1e-2, 3e-3, 1e-3] if quick else [1 / 30, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
    explicit_steps = [1e-4, 5e-5] if quick else [1.5e-4, 1e-4, 5e-5, 2e-5]
    bdf2_steps = [1 / 30, 1e-2] if quick else [1 / 30, 1e-2, 3e-3, 1e-3]
    grid = []
    for integrator in INTEGRATORS:
        steps = {"implicit_euler": implicit_steps, "bdf2": bdf2_steps}.get(integrator, explicit_steps)
        grid += [dict(integrator=integrator, tolerance=0.0, max_step=h) for h in steps]
        grid += [dict(integrator=integrator, tolerance=tol, max_step=0.1 if integrator == "bdf2" else 0.01)
                 for tol in tolerances]
    return grid


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer settings (a smoke run)")
    args = parser.parse_args()
    OUT.mkdir(exist_ok=True)
    rows = []
    for case in cases():
        ref = reference(case)
        half = reference(case, REFERENCE_STEP / 2)
        check = errors(ref, half)
        print(f"{case.name}: reference ({ref.seconds:.1f} s) against half its step: centroid "
              f"{check['centroid_error']:.2e} m, vertices {check['vertex_rms_error']:.2e} m, "
              f"wet mass {check['wet_mass_error']:.2e}", flush=True)
        rows.append(dict(case=case.name, integrator="reference (halved step)", mode="fixed",
                         setting=REFERENCE_STEP / 2, seconds=half.seconds, steps=half.steps, **check))
        for settings in settings_grid(args.quick):
            mode = "adaptive" if settings["tolerance"] > 0 else "fixed"
            value = settings["tolerance"] if mode == "adaptive" else settings["max_step"]
            try:
                run = simulate(case, **settings)
                row = dict(seconds=run.seconds, steps=run.steps, **errors(run, ref))
            except BlowUpError:
                row = dict(seconds=float("nan"), steps=0, centroid_error=float("inf"),
                           vertex_rms_error=float("inf"), wet_mass_error=float("inf"))
            rows.append(dict(case=case.name, integrator=settings["integrator"], mode=mode, setting=value, **row))
            print(f"  {settings['integrator']:17s} {mode:8s} {value:8.1e}: {row['seconds']:7.2f} s "
                  f"{row['steps']:7d} steps  centroid {row['centroid_error']:.2e} m  "
                  f"vertices {row['vertex_rms_error']:.2e} m  wet mass {row['wet_mass_error']:.1e}", flush=True)
    write_csv(rows, OUT / "work_precision.csv")
    plot(rows, OUT / "work_precision.png")
    print(f"wrote {OUT / 'work_precision.csv'} and {OUT / 'work_precision.png'}")


def write_csv(rows, path: Path) -> None:
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def plot(rows, path: Path) -> None:
    names = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, len(names), figsize=(5.5 * len(names), 4.5), constrained_layout=True)
    colours = {"explicit_euler": "tab:red", "symplectic_euler": "tab:green", "implicit_euler": "tab:blue",
               "bdf2": "tab:purple"}
    for ax, name in zip(np.atleast_1d(axes), names):
        for integrator, colour in colours.items():
            for mode, style in (("fixed", "o--"), ("adaptive", "s-")):
                pts = sorted((r["seconds"], r["centroid_error"]) for r in rows
                             if r["case"] == name and r["integrator"] == integrator and r["mode"] == mode
                             and np.isfinite(r["centroid_error"]) and r["centroid_error"] > 0)
                if pts:
                    ax.loglog(*zip(*pts), style, color=colour, label=f"{integrator} ({mode})", ms=4)
        ax.axhline(1e-3, color="0.5", lw=0.8, ls=":")
        ax.set_title(name)
        ax.set_xlabel("run time (s)")
        ax.set_ylabel("centroid error, max over time (m)")
        ax.grid(True, which="both", alpha=0.3)
        ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels of a short log axis overlap
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    main()
