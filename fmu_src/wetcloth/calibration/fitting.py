"""The fit: nonlinear least squares over scene parameters, optionally after a global search on Dask;
or, for measured sink times, a root search on the sink time.

    from wetcloth.calibration import fit, read_measurements
    result = fit(wetcloth.load_scene("towel", nx=9, ny=13), read_measurements("towel.csv"),
                 ["absorption_rate", "absorption_capacity"])
    result.estimates, result.standard_errors, result.intervals, result.scene
"""

from __future__ import annotations

import math
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy import optimize, stats

from wetcloth.calibration.data import Curves, SinkTimes, check_against_scene
from wetcloth.calibration.parameters import FitParameter, fit_parameters
from wetcloth.calibration.problem import DIFF_STEP, CurveModel, SinkModel, column_scale, fit_scene
from wetcloth.calibration.statistics import chi2_check, estimate_sigma, leverage, uncertainty
from wetcloth.errors import BlowUpError, ParameterError
from wetcloth.scene import Scene, parameter_field

#: Differential evolution's population per fitted parameter, and its generations at most: at most
#: POPULATION * p * (GENERATIONS + 1) runs (330 for two parameters).
POPULATION = 15
GENERATIONS = 10
#: Function evaluations of least squares at most (each Jacobian adds 2 runs per parameter).
MAX_EVALUATIONS = 60
#: Outputs without sigma: fits with re-estimated sigma at most, and the relative change of the
#: estimates at which they count as settled.
REWEIGHTS = 6
SETTLED = 0.01
#: Sink-time fits: m the cloth must go under to count as sunk (as studies' ``sink_depth``), and
#: how far past the measured time a run goes before it counts as not sinking.
SINK_DEPTH = 0.05
SINK_HORIZON = 2.0


class FitError(ValueError):
    """The fit cannot be done as asked (too few data, no sink time within the bounds ...)."""


@dataclass
class FitResult:
    """What a fit found.  ``estimates``, ``standard_errors`` and ``intervals`` (p x 2, 95 %) are in
    the parameters' units, in the order of ``parameters``; ``scene`` is the start scene with the
    estimates set (and the fit's tolerance)."""

    kind: str  # "curves" or "sink"
    parameters: list[FitParameter]
    start_scene: Scene
    scene: Scene
    estimates: np.ndarray
    standard_errors: np.ndarray
    intervals: np.ndarray
    correlation: np.ndarray
    quantile: float
    dof: int | None
    warnings: list[str]
    runs: int
    failed_runs: int
    seconds: float
    converged: bool
    message: str
    observations: int
    sigma: dict[str, dict] = field(default_factory=dict)  # output -> {"given": bool, "value": float | None, "rms": float}
    chi2: float | None = None
    chi2_probability: float | None = None
    global_search: dict | None = None
    sink: dict | None = None  # sink-time fits: measured, its standard error, fitted, sink_depth, t_max
    data: Curves | SinkTimes | None = None

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def estimate(self, name: str) -> float:
        return float(self.estimates[self.names.index(name)])


class _Runs:
    """Counts the fit's runs (from several threads) on a tqdm bar."""

    def __init__(self, bar):
        self.bar = bar
        self.count = 0
        self.failed = 0
        self._lock = threading.Lock()

    def add(self, ok: bool = True) -> None:
        with self._lock:
            self.count += 1
            self.failed += not ok
            if self.bar is not None:
                self.bar.update(1)


def _bar(desc: str, total: int | None, progress: bool):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=" runs", disable=not progress, dynamic_ncols=True, leave=False, delay=1.0)


# ----------------------------------------------------------------------------- curves
def fit(scene: Scene, data: Curves | SinkTimes, names: list[str], bounds: dict | None = None, *,
        global_search: bool = False, client=None, scheduler: str | None = None, workers: int | None = None,
        seed: int = 0, sink_depth: float = SINK_DEPTH, progress: bool = False,
        announce: Callable[[str], None] | None = None) -> FitResult:
    """Fit the parameters ``names`` of ``scene`` to ``data`` (``read_measurements``), within
    ``bounds`` (name -> (lo, hi); default: each parameter's allowed range).

    ``global_search``: first a differential evolution over the bounds (needed for every parameter),
    its runs on Dask: ``client``, or a cluster at ``scheduler``, or a local cluster of ``workers``
    processes (``wetcloth.batch.dask_client``); ``announce`` gets its dashboard's address.  Sink
    times (``SinkTimes``) fit one parameter by a root search.  ``progress``: a bar of the runs."""
    started = time.perf_counter()
    # a global search starts from its own samples, a sink-time search from the bounds: neither needs the
    # start inside them
    params = fit_parameters(scene, list(names), bounds,
                            need_start_inside=not (global_search or isinstance(data, SinkTimes)))
    if isinstance(data, Curves):
        check_against_scene(data, scene, {q.name: (q.lo, q.hi) for q in params})
    if isinstance(data, SinkTimes):
        if global_search:
            raise FitError("--global is for curves: a sink time is fitted by a root search within --bounds")
        result = _fit_sink(scene, data, params, sink_depth, progress)
    else:
        result = _fit_curves(scene, data, params, global_search, client, scheduler, workers, seed, progress, announce)
    result.seconds = time.perf_counter() - started
    result.data = data
    return result


def _fit_curves(scene, data: Curves, params: list[FitParameter], global_search, client, scheduler, workers, seed,
                progress, announce) -> FitResult:
    p = len(params)
    n = data.observations
    estimated = [name for name in data.names if data.sigma[name] is None]
    if n < p or (estimated and n <= p):
        raise FitError(f"{n} measured values cannot determine {p} parameters" +
                       (" and the noise (no sigma_NAME given): more values than parameters are needed" if estimated else ""))
    if global_search:
        missing = [q.name for q in params if not q.given]
        if missing:
            raise FitError(f"--global searches within the bounds: give --bounds for {', '.join(missing)} "
                           f"(the allowed ranges are far wider than any cloth's values)")
    start_scene = fit_scene(scene)
    weights = {name: data.sigma[name] if data.sigma[name] is not None else column_scale(data.values[name])
               for name in data.names}
    model = CurveModel(start_scene, tuple(q.name for q in params), data.times, data.values, weights)
    scales = np.array([q.scale for q in params])
    lo = np.array([q.lo for q in params])
    hi = np.array([q.hi for q in params])
    start = np.array([q.start for q in params])
    runs = _Runs(None)
    search = None
    if global_search:
        start, search = _global_search(model, params, client, scheduler, workers, seed, progress, announce, runs)
    with _bar("fitting", None, progress) as bar, ThreadPoolExecutor(max(1, min(2 * p, os.cpu_count() or 1))) as pool:
        runs.bar = bar
        solution = _least_squares(model, start, lo, hi, scales, pool, runs)
        solved_with, sigma = model, {}  # the model whose weights the solution's residuals carry
        for round_ in range(REWEIGHTS if estimated else 0):
            # Outputs without sigma: estimate it from the residuals, fit again with it as the weight,
            # until it settles (the first weights, the outputs' spreads, are not their noise: a fit
            # with them lets one output's residuals shrink and its sigma come out low).
            sigma = estimate_sigma(_raw_residuals(solved_with, solution.fun),
                                   solved_with.split(leverage(solution.jac)))
            change = max(abs(sigma[k] / float(w[0]) - 1.0) for k, w in zip(solved_with.names, solved_with.weights)
                         if k in estimated)
            model = solved_with.reweighted({k: (sigma[k] if k in estimated else data.sigma[k]) for k in data.names})
            if len(data.names) == 1 or change < SETTLED or round_ == REWEIGHTS - 1:
                break  # one output: its weight does not move the fit
            solution = _least_squares(model, solution.x * scales, lo, hi, scales, pool, runs)
            solved_with = model
        runs.bar = None
    x = solution.x * scales
    jac = solution.jac / scales  # per unit of each parameter
    residuals = solution.fun
    if estimated:  # the fit's residuals and Jacobian, weighted by the last sigma (rows rescale)
        factor = np.concatenate([then / now for then, now in zip(solved_with.weights, model.weights)])
        residuals, jac = residuals * factor, jac * factor[:, None]
    raw = _raw_residuals(model, residuals)
    sigma_info = {}
    for k in data.names:
        rms = float(np.sqrt(np.mean(raw[k] ** 2)))
        sigma_info[k] = {"given": k not in estimated, "rms": rms,
                         "value": float(sigma[k]) if k in estimated else None, "count": data.count(k)}
    dof = n - p
    stats_ = uncertainty(jac, x, [q.name for q in params], scales, dof if estimated else None)
    warnings = list(stats_.warnings)
    chi2 = prob = None
    if not estimated:
        chi2 = float(residuals @ residuals)
        prob, warning = chi2_check(chi2, dof)
        if warning:
            warnings.append(warning)
    warnings += _bound_warnings(params, x)
    if solution.status <= 0:
        warnings.append(f"least squares stopped before converging ({solution.message}); the estimates may be off")
    if runs.failed:
        warnings.append(f"{runs.failed} of {runs.count} runs failed (a blow-up, or values the scene refuses) and "
                        f"counted as far off: narrower --bounds keep the fit where the scene runs")
    return FitResult(
        kind="curves", parameters=params, start_scene=start_scene, scene=model.with_values(x), estimates=x,
        standard_errors=stats_.standard_error, intervals=stats_.interval, correlation=stats_.correlation,
        quantile=stats_.quantile, dof=stats_.dof, warnings=warnings, runs=runs.count, failed_runs=runs.failed,
        seconds=0.0, converged=bool(solution.status > 0), message=str(solution.message),
        observations=n, sigma=sigma_info, chi2=chi2, chi2_probability=prob, global_search=search)


def _raw_residuals(model: CurveModel, weighted: np.ndarray) -> dict[str, np.ndarray]:
    """Weighted residuals back in each output's unit, output by output."""
    return {k: r * w for (k, r), w in zip(model.split(weighted).items(), model.weights)}


def _least_squares(model: CurveModel, start, lo, hi, scales, pool, runs: _Runs):
    """scipy's trust-region least squares in the parameters over their scales (each near 1), with a
    central-difference Jacobian of steps DIFF_STEP times each parameter's size (see problem.py), its
    runs side by side in ``pool``'s threads (a run releases the GIL)."""
    cache: dict[bytes, np.ndarray] = {}

    def residuals(u):
        key = np.asarray(u, float).tobytes()
        if key not in cache:
            r, failure = model.residuals(u * scales)
            runs.add(failure is None)
            if failure is not None and not cache:  # the start (nothing evaluated yet): nothing to go from
                raise FitError(_start_failed(model, u * scales, failure))
            cache.clear()
            cache[key] = r
        return cache[key]

    def jacobian(u):
        u = np.asarray(u, float)
        base = residuals(u)
        steps = DIFF_STEP * np.where(u != 0, np.abs(u), 1.0)
        ends = [(min(u[j] + steps[j], hi[j] / scales[j]), max(u[j] - steps[j], lo[j] / scales[j]))
                for j in range(u.size)]  # one side only at a bound

        def run(task):
            j, value = task
            if value == u[j]:
                return base
            v = u.copy()
            v[j] = value
            r, failure = model.residuals(v * scales)
            runs.add(failure is None)
            return r

        tasks = [(j, e) for j in range(u.size) for e in ends[j]]
        results = iter(pool.map(run, tasks))
        columns = [(next(results) - next(results)) / (up - down) for up, down in ends]
        return np.column_stack(columns)

    u0 = np.clip(np.asarray(start, float) / scales, lo / scales, hi / scales)
    # Tolerances above the runs' noise (4e-7 m against data of mm: relative changes of 1e-6 in the
    # cost are noise), so that the search stops there rather than at MAX_EVALUATIONS.
    return optimize.least_squares(residuals, u0, jac=jacobian, bounds=(lo / scales, hi / scales), method="trf",
                                  x_scale=1.0, ftol=1e-6, xtol=1e-6, gtol=1e-8,
                                  max_nfev=MAX_EVALUATIONS)


def _start_failed(model: CurveModel, x: np.ndarray, failure: Exception) -> str:
    """Why a fit cannot start: the run at the start values ``x`` (in the parameters' units) failed."""
    values = ", ".join(f"{name} = {v:g} {parameter_field(name).metadata['unit']}"
                       for name, v in zip(model.parameters, x))
    return (f"the run at the start ({values}) failed, so the fit has no curve to go from (start where the scene "
            f"runs: --set NAME=VALUE): {failure}")


def _bound_warnings(params: list[FitParameter], x: np.ndarray) -> list[str]:
    out = []
    for q, v in zip(params, x):
        tol = 1e-6 * (q.hi - q.lo if q.finite else max(abs(v), 1.0))
        for side, bound in (("lower", q.lo), ("upper", q.hi)):
            if abs(v - bound) <= tol:
                out.append(f"{q.name} ended at its {side} bound {bound:g}: the best fit may lie beyond it and the "
                           f"interval, which assumes an optimum inside, does not hold; widen --bounds if the range allows")
    return out


class _DaskMap:
    """``map(func, population)`` for differential evolution: the population's runs as Dask tasks."""

    def __init__(self, client, runs: _Runs):
        self.client = client
        self.runs = runs

    def __call__(self, func, population):
        from distributed import as_completed

        futures = self.client.map(func, list(population), pure=False)
        for _ in as_completed(futures, loop=self.client.loop):
            self.runs.add()
        return self.client.gather(futures)


def _global_search(model: CurveModel, params, client, scheduler, workers, seed, progress, announce, runs: _Runs):
    """Differential evolution over the bounds, every population's runs on Dask; the best point."""
    from wetcloth.batch.cluster import dask_client

    bounds = [(q.lo, q.hi) for q in params]
    total = POPULATION * len(params) * (GENERATIONS + 1)
    started = time.perf_counter()
    before = runs.count
    with dask_client(client, scheduler, workers, announce=announce) as c, _bar("global search", total, progress) as bar:
        runs.bar = bar
        result = optimize.differential_evolution(
            model, bounds, popsize=POPULATION, maxiter=GENERATIONS, init="latinhypercube", tol=0.01, seed=seed,
            polish=False, updating="deferred", workers=_DaskMap(c, runs))
        runs.bar = None
    return result.x, {"runs": runs.count - before, "best_cost": float(result.fun), "best": result.x.tolist(),
                      "generations": int(result.nit), "seconds": time.perf_counter() - started,
                      "population": POPULATION * len(params)}


# ----------------------------------------------------------------------------- sink time
def _fit_sink(scene: Scene, data: SinkTimes, params: list[FitParameter], sink_depth: float, progress) -> FitResult:
    if len(params) != 1:
        raise FitError(f"a sink time determines one parameter; --params names {len(params)}: "
                       f"{', '.join(q.name for q in params)} (fix the others in the scene, or measure curves)")
    if not (sink_depth > 0 and math.isfinite(sink_depth)):
        raise FitError(f"sink depth must be a finite number > 0 m, got {sink_depth!r}")
    q = params[0]
    measured, se_t, dof = data.mean()
    t_max = SINK_HORIZON * float(data.times.max()) + 10.0
    start_scene = fit_scene(scene)
    model = SinkModel(start_scene, q.name, sink_depth, t_max)
    runs = _Runs(None)
    values: dict[float, float] = {}

    def sink_time(v: float) -> float:
        if v not in values:
            try:
                values[v] = model.sink_time([v])
            except BlowUpError as exc:
                raise FitError(f"the run with {q.name} = {v:g} {q.unit} blew up ({exc}); give --bounds that keep "
                               f"the scene stable") from None
            except ParameterError as exc:
                raise FitError(f"{q.name} = {v:g}: {exc}; give --bounds within which the scene is valid") from None
            runs.add()
        return values[v]

    def gap(v: float) -> float:  # > 0: sinks later than measured (or not within t_max)
        t = sink_time(v)
        return (t if math.isfinite(t) else t_max) - measured

    with _bar("fitting", None, progress) as bar:
        runs.bar = bar
        a, b = _bracket(q, gap, sink_time, t_max)
        root = optimize.brentq(gap, a, b, xtol=1e-7 * q.scale, rtol=1e-7, maxiter=60)
        # the slope of the sink time at the root, for the standard error: central differences
        h = DIFF_STEP * (abs(root) if root != 0 else q.scale)
        lo_v, hi_v = max(root - h, q.lo), min(root + h, q.hi)
        t_lo, t_hi = sink_time(lo_v), sink_time(hi_v)
        runs.bar = None
    fitted = sink_time(root)
    warnings = []
    slope = (t_hi - t_lo) / (hi_v - lo_v) if math.isfinite(t_lo) and math.isfinite(t_hi) else math.nan
    if se_t is None:
        se = math.nan
        warnings.append("one sink time without sigma_time_to_sink: its uncertainty, and so the parameter's, is "
                        "unknown; time several drops (one row each) or give sigma_time_to_sink")
    elif not (math.isfinite(slope) and slope != 0):
        se = math.inf
        warnings.append(f"{q.name} is not identifiable from the sink time: it does not change with it here")
    else:
        se = se_t / abs(slope)
    quantile = float(stats.norm.ppf(0.975) if dof is None else stats.t.ppf(0.975, dof))
    warnings += _bound_warnings([q], np.array([root]))
    interval = np.array([[root - quantile * se, root + quantile * se]])
    return FitResult(
        kind="sink", parameters=params, start_scene=start_scene, scene=model.with_values([root]),
        estimates=np.array([root]), standard_errors=np.array([se]), intervals=interval, correlation=np.ones((1, 1)),
        quantile=quantile, dof=dof, warnings=warnings, runs=runs.count, failed_runs=0, seconds=0.0,
        converged=True, message=f"sink time {fitted:.6g} s against {measured:.6g} s measured", observations=data.observations,
        sink={"measured": measured, "standard_error": se_t, "fitted": fitted, "start": sink_time(q.start) if q.lo <= q.start <= q.hi else None,
              "sink_depth": sink_depth, "t_max": t_max, "slope": slope})


def _bracket(q: FitParameter, gap: Callable[[float], float], sink_time: Callable[[float], float],
             t_max: float) -> tuple[float, float]:
    """Two values of the parameter between which the measured sink time lies: the bounds if given,
    else the start and values 2, 4, ... 64 times larger and smaller (within the allowed range)."""

    def describe(v: float) -> str:
        t = sink_time(v)
        return f"sinks at {t:.4g} s" if math.isfinite(t) else f"does not sink within {t_max:g} s"

    if q.given:
        g_lo, g_hi = gap(q.lo), gap(q.hi)
        if g_lo * g_hi > 0:
            raise FitError(f"the measured sink time is not reached within --bounds {q.name}={q.lo:g}:{q.hi:g}: "
                           f"the cloth {describe(q.lo)} at {q.lo:g} and {describe(q.hi)} at {q.hi:g}; widen the bounds")
        return q.lo, q.hi
    g0 = gap(q.start)
    if g0 == 0.0:
        return q.start, q.start
    if q.start <= 0:
        raise FitError(f"{q.name} starts at {q.start:g}: give --bounds {q.name}=LO:HI to search between")
    tried = [q.start]
    for k in range(1, 7):
        for v in (q.start * 2 ** k, q.start / 2 ** k):
            if not q.lo <= v <= q.hi:
                continue
            tried.append(v)
            if gap(v) * g0 <= 0:
                return (v, q.start) if v < q.start else (q.start, v)
    seen = "; ".join(f"{describe(v)} at {v:g}" for v in sorted(tried))
    raise FitError(f"no value of {q.name} from {min(tried):g} to {max(tried):g} gives the measured sink time: the cloth "
                   f"{seen}; give --bounds {q.name}=LO:HI around the value, or fit another parameter")


__all__ = ["FitError", "FitResult", "fit"]
