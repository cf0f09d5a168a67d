"""What a fit evaluates: the scene's outputs at the measured times, for trial parameter values.

A ``CurveModel`` or ``SinkModel`` is a small picklable object (the scene, the parameter names, the
measurements): a global search sends it to Dask workers, which call it on their own.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.errors import BlowUpError, ParameterError
from wetcloth.scene import Scene
from wetcloth.simulation import OUTPUT_NAMES, Simulation

#: Finite-difference step of the fit's Jacobian (central differences), relative to each parameter's
#: size.  Two limits, both measured (2026-12-02, tolerance 5e-6, outputs at 1 Hz over 60 s):
#: - Noise.  The adaptive step control makes each run's depth noisy: 4e-7 m for the towel on a 9 x 13
#:   grid and the fit example's dishcloth, 3e-6 m on a 5 x 5 grid (the residual of a straight line
#:   through the depths of nine runs 1e-7 apart in absorption_rate; wet_mass is smooth to 1e-9 kg).
#:   A relative step of 1e-8 moves the depth by about that much (the derivative came out 10x too
#:   large); 1e-4 moves it by 1.7e-4 m, so the noise costs 0.1 % of a central difference (1 % on 5 x 5).
#: - Bends.  Where the cloth lands on the floor the depth's slope changes within a small change of a
#:   parameter.  On the example (docs/fit_example, rate and capacity correlated -0.96) forward steps
#:   of 1e-3 (the first value tried) stalled least squares at chi^2 37.5 and 62 against the optimum's
#:   31.24, the difference across the bend pointing it the wrong way along the valley; central
#:   differences of 1e-4 reached 31.24 from all of 8 starts (0.2..0.8 1/s, 3..6 kg/kg).
DIFF_STEP = 1e-4

#: Tightest ``tolerance`` a fit leaves as it is; a coarser one is tightened to it.  Measured as
#: above against tolerance 1e-9: at 5e-6 (the presets' value) the depth and wet mass lie within
#: 0.14 mm and 0.07 g of the converged ones, a seventh of a kitchen ruler's 1 mm and a fourteenth of
#: a kitchen scale's 1 g; at 1e-4 within 0.4 mm and 0.7 g, as large as the noise of good data, and
#: 20x noisier (8e-6 m).  Tighter than 5e-6 buys nothing: at 1e-7 the noise is no smaller (6e-6 m)
#: and a run takes 7x as long.  A scene with fixed steps (tolerance 0) has no step-control noise
#: and keeps them.
FIT_TOLERANCE = 5e-6

#: A value a failed run (a blow-up, parameters the scene refuses) did not reach is given the residual
#: PENALTY times its output's scale (``column_scale``), over its weight: far beyond any run's, so the
#: optimiser steps back from there.  (A weighted 1e4 was less than a real run's 1 cm off at a sigma of
#: 1 um, or at the sigma a fit estimates from noise-free data: a failed run looked the better fit.)
PENALTY = 1e4

#: Hz at which a sink-time run is sampled; the crossing is interpolated between samples.
SINK_RATE = 20.0


def fit_scene(scene: Scene) -> Scene:
    """``scene`` with its tolerance tightened to ``FIT_TOLERANCE`` if it was coarser (0 stays)."""
    if scene.tolerance > FIT_TOLERANCE:
        return scene.replace(tolerance=FIT_TOLERANCE)
    return scene


def column_scale(values: np.ndarray) -> float:
    """An output's scale in its unit (m, kg): its measured values' spread, else their largest magnitude, else 1."""
    v = values[np.isfinite(values)]
    spread = float(v.std()) if v.size > 1 else 0.0
    return spread if spread > 0 else (float(np.abs(v).max()) or 1.0)


class CurveModel:
    """The outputs ``names`` of ``scene`` with the fitted parameters set, at ``times``; and the
    residuals against measured ``values`` (NaN: not measured), each divided by its ``weights``."""

    def __init__(self, scene: Scene, parameters: tuple[str, ...], times: np.ndarray,
                 values: dict[str, np.ndarray], weights: dict[str, np.ndarray]):
        self.scene = scene
        self.parameters = tuple(parameters)
        self.times = np.asarray(times, float)
        self.names = tuple(values)
        self.columns = [OUTPUT_NAMES.index(n) for n in self.names]
        self.masks = [np.isfinite(values[n]) for n in self.names]
        self.observed = [values[n][m] for n, m in zip(self.names, self.masks)]
        self.weights = [np.broadcast_to(np.asarray(weights[n], float), values[n].shape)[m]
                        for n, m in zip(self.names, self.masks)]
        self.penalties = np.concatenate([PENALTY * column_scale(y) / w for y, w in zip(self.observed, self.weights)])

    def reweighted(self, weights: dict[str, np.ndarray]) -> "CurveModel":
        values = {n: np.where(m, 0.0, np.nan) for n, m in zip(self.names, self.masks)}
        for n, m, y in zip(self.names, self.masks, self.observed):
            values[n][m] = y
        return CurveModel(self.scene, self.parameters, self.times, values, weights)

    def with_values(self, x) -> Scene:
        return self.scene.replace(**dict(zip(self.parameters, (float(v) for v in x))))

    def outputs(self, x, times=None) -> np.ndarray:
        """All outputs (rows: ``times``, default the measured ones; columns: OUTPUT_NAMES) for
        parameter values ``x``, in one compiled call.  Raises BlowUpError or ParameterError."""
        times = self.times if times is None else times
        return Simulation(self.with_values(x)).sample(times)

    def residuals_of(self, outputs: np.ndarray) -> np.ndarray:
        """Weighted residuals of ``outputs`` (model minus measured, over the weights), output after
        output; its penalty where a failed run left NaN."""
        parts = [(outputs[m, c] - y) / w for c, m, y, w in zip(self.columns, self.masks, self.observed, self.weights)]
        r = np.concatenate(parts)
        return np.where(np.isfinite(r), r, self.penalties)

    def residuals(self, x) -> tuple[np.ndarray, BlowUpError | ParameterError | None]:
        """(weighted residuals at ``x``, why the run failed: its BlowUpError or ParameterError, None if it ran)."""
        try:
            return self.residuals_of(self.outputs(x)), None
        except (BlowUpError, ParameterError) as exc:
            partial = getattr(exc, "partial_outputs", np.empty((0, len(OUTPUT_NAMES))))
            out = np.full((self.times.size, len(OUTPUT_NAMES)), np.nan)
            out[:len(partial)] = partial
            return self.residuals_of(out), exc

    def __call__(self, x) -> float:
        """Half the sum of squared weighted residuals at ``x`` (least_squares' cost): a global search's objective."""
        r, _ = self.residuals(x)
        return 0.5 * float(r @ r)

    def split(self, r: np.ndarray) -> dict[str, np.ndarray]:
        """A residual vector cut into its outputs' parts."""
        sizes = np.cumsum([m.sum() for m in self.masks])[:-1]
        return dict(zip(self.names, np.split(r, sizes)))


class SinkModel:
    """The time (s) at which ``scene``, with the fitted parameter at a trial value, first goes more
    than ``sink_depth`` under (``batch`` metric ``time_to_sink``); ``inf`` if not within ``t_max``."""

    def __init__(self, scene: Scene, parameter: str, sink_depth: float, t_max: float):
        self.scene = scene
        self.parameters = (parameter,)
        self.sink_depth = sink_depth
        self.t_max = t_max

    def with_values(self, x) -> Scene:
        return self.scene.replace(**{self.parameters[0]: float(np.ravel(x)[0])})

    def sink_time(self, x) -> float:
        """Sampled at SINK_RATE in stretches of 5 s, stopping at the first stretch that crosses."""
        from wetcloth.batch.metrics import first_crossing  # the studies' definition of time_to_sink

        sim = Simulation(self.with_values(x))
        depth_col = OUTPUT_NAMES.index("depth")
        times = np.arange(0.0, self.t_max + 0.5 / SINK_RATE, 1.0 / SINK_RATE)
        last_t, last_d = None, None
        for chunk in np.array_split(times, max(1, math.ceil(self.t_max / 5.0))):
            depth = sim.sample(chunk)[:, depth_col]
            t = chunk if last_t is None else np.concatenate([[last_t], chunk])
            d = depth if last_d is None else np.concatenate([[last_d], depth])
            crossing = first_crossing(t, d, self.sink_depth, strict=True)
            if math.isfinite(crossing):
                return crossing
            last_t, last_d = chunk[-1], depth[-1]
        return math.inf

    def depth(self, x, times) -> np.ndarray:
        return Simulation(self.with_values(x)).sample(times)[:, OUTPUT_NAMES.index("depth")]
