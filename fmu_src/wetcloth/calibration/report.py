"""A fit's report: a text summary, ``fit.json``, the fitted scene as TOML and a plot of the curves."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.calibration.data import SinkTimes
from wetcloth.calibration.fitting import FitResult
from wetcloth.calibration.parameters import TABLES
from wetcloth.calibration.problem import DIFF_STEP
from wetcloth.files import write_text
from wetcloth.simulation import OUTPUT_NAMES, OUTPUTS, Simulation

JSON_NAME = "fit.json"
TOML_NAME = "fitted_scene.toml"
PLOT_NAME = "fit.png"
#: Points of each curve in the plot.
PLOT_POINTS = 400


def _number(value):
    """A float for JSON: None for NaN and infinities (which JSON has not)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _g(value, digits: int = 5) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def _correlation(value: float) -> str:
    """A correlation as the summary prints it: '-0.995', or why it is undefined (NaN: no covariance)."""
    if math.isfinite(value):
        return f"{value:+.3f}"
    return "undefined (no standard errors: the data do not identify these parameters together)"


def distribution(result: FitResult) -> str:
    return "normal" if result.dof is None else f"Student t, {result.dof} degrees of freedom"


def summary(result: FitResult, data_name: str = "the data", warnings: bool = True) -> str:
    """The estimates, their standard errors and 95 % intervals, correlations, residuals and (with
    ``warnings``) the warnings, as text."""
    names = result.names
    if result.kind == "sink":
        s = result.sink
        head = (f"fitted {names[0]} to the sink time {s['measured']:.5g} s (depth > {s['sink_depth']:g} m; "
                f"{result.observations} timing{'s' if result.observations > 1 else ''} in {data_name}) in "
                f"{result.runs} runs, {result.seconds:.1f} s")
    else:
        counts = ", ".join(f"{k} {v['count']}" for k, v in result.sigma.items())
        head = (f"fitted {', '.join(names)} to {result.observations} values of {data_name} ({counts}) in "
                f"{result.runs} runs, {result.seconds:.1f} s")
        if result.global_search:
            g = result.global_search
            head += f" ({g['runs']} of them in the global search, {g['seconds']:.1f} s)"
    lines = [head]
    rows = [("parameter", "start", "estimate", "std. error", "95 % interval", "unit")]
    for j, q in enumerate(result.parameters):
        lo, hi = result.intervals[j]
        rows.append((q.name, _g(q.start), _g(result.estimates[j], 6), _g(result.standard_errors[j], 3),
                     f"{_g(lo, 6)} .. {_g(hi, 6)}" if math.isfinite(lo) else "-", q.unit))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    if len(names) > 1:
        pairs = [f"{names[i]} ~ {names[j]} {_correlation(result.correlation[i, j])}"
                 for i in range(len(names)) for j in range(i + 1, len(names))]
        lines.append("  correlation: " + "; ".join(pairs))
    if result.kind == "sink":
        s = result.sink
        se = f" +- {s['standard_error']:.3g} s (standard error)" if s["standard_error"] is not None else ""
        lines.append(f"  sink time: measured {s['measured']:.5g} s{se}; fitted {s['fitted']:.5g} s")
    else:
        parts = []
        for k, v in result.sigma.items():
            unit = OUTPUTS[k][0]
            noise = (f"sigma given" if v["given"] else f"sigma estimated from the fit: {v['value']:.3g} {unit}")
            parts.append(f"{k} rms residual {v['rms']:.3g} {unit} ({noise})")
        lines.append("  " + "; ".join(parts))
        if result.chi2 is not None:
            lines.append(f"  chi^2 = {result.chi2:.4g} for {result.observations - len(names)} degrees of freedom "
                         f"(probability {result.chi2_probability:.2g})")
    lines.append(f"  intervals: estimate +- {result.quantile:.3f} standard errors ({distribution(result)})")
    if warnings:
        lines += [f"warning: {w}" for w in result.warnings]
    return "\n".join(lines)


def to_json(result: FitResult, data_path: str | None = None, scene: str | None = None) -> dict:
    """The report as a JSON-ready dict (NaN and infinities as null)."""
    names = result.names
    out = {
        "kind": result.kind,
        "data": data_path,
        "scene": scene,
        "parameters": [
            {"name": q.name, "unit": q.unit, "start": q.start, "estimate": _number(result.estimates[j]),
             "standard_error": _number(result.standard_errors[j]),
             "interval_95": [_number(v) for v in result.intervals[j]], "bounds": [_number(q.lo), _number(q.hi)],
             "bounds_given": q.given}
            for j, q in enumerate(result.parameters)],
        "correlation": {"names": names, "matrix": [[_number(v) for v in row] for row in result.correlation]},
        "interval_distribution": distribution(result),
        "quantile": result.quantile,
        "warnings": result.warnings,
        "observations": result.observations,
        "runs": result.runs,
        "failed_runs": result.failed_runs,
        "seconds": result.seconds,
        "converged": result.converged,
        "message": result.message,
        "tolerance": result.scene.tolerance,
        "diff_step": DIFF_STEP,
        "wetcloth": wetcloth.__version__,
    }
    if result.kind == "curves":
        out["outputs"] = {k: {"count": v["count"], "sigma_given": v["given"], "sigma_estimated": _number(v["value"]),
                              "rms_residual": v["rms"], "unit": OUTPUTS[k][0]} for k, v in result.sigma.items()}
        out["chi2"] = _number(result.chi2)
        out["chi2_probability"] = _number(result.chi2_probability)
        out["global_search"] = result.global_search
    else:
        out["sink"] = {k: _number(v) for k, v in result.sink.items()}
    return out


def _toml_value(value) -> str:
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string: the same escapes as JSON for these texts
    return repr(value)


def _table_of(name: str) -> tuple[str, int, str] | None:
    """(table, k, field) of a flattened table field such as 'collider2_z' ('collider', 2, 'z'); None for a
    scene parameter."""
    for table, parse, _ in TABLES:
        where = parse(name)
        if where is not None:
            return table, *where
    return None


def scene_toml(result: FitResult, description: str = "", duration: float | None = None, fps: float | None = None) -> str:
    """The fitted scene as a scene file (``wetcloth.load_scene`` reads it): every parameter and every
    [[collider]], [[grip_key]] and [[collider_key]] table, the fitted values marked with their standard
    error; ``[run]`` with ``duration`` and ``fps`` if given."""
    scene = result.scene
    fitted = dict(zip(result.names, range(len(result.names))))
    lines = ["# Fitted by 'wetcloth fit' (wetcloth " + wetcloth.__version__ + "): the fitted parameters are marked.",
             f"description = {_toml_value(description)}", ""]
    table = None
    for name, value in scene.to_dict().items():
        where = _table_of(name)
        if where is not None and where[:2] != table:
            table = where[:2]
            lines += ["", f"[[{table[0]}]]"]
        line = f"{name if where is None else where[2]} = {_toml_value(value)}"
        if name in fitted:
            j = fitted[name]
            line += (f"    # fitted: +- {_g(result.standard_errors[j], 3)} {result.parameters[j].unit} (standard "
                     f"error), start {result.parameters[j].start:g}")
        elif name == "tolerance" and result.start_scene.tolerance != scene.tolerance:
            line += "    # the fit's"
        lines.append(line)
    if duration is not None or fps is not None:
        lines += ["", "[run]"]
        if duration is not None:
            lines.append(f"duration = {float(duration)!r}")
        if fps is not None:
            lines.append(f"fps = {float(fps)!r}")
    return "\n".join(lines) + "\n"


def plot(result: FitResult, path: str | Path, title: str | None = None) -> Path:
    """The data against the fitted curves and the starting curves (PNG), one panel per measured output;
    for a sink time, the depth of both runs against the measured time."""
    from wetcloth.plotting import figure_file

    data = result.data
    if isinstance(data, SinkTimes):
        t_end = result.sink["t_max"]
        names = ["depth"]
    else:
        t_end = float(np.nanmax(data.times))
        names = list(data.names)
    times = np.linspace(0.0, t_end, PLOT_POINTS)
    curves = {}
    for label, scene in (("start", result.start_scene), ("fitted", result.scene)):
        try:
            curves[label] = Simulation(scene).sample(times)
        except wetcloth.BlowUpError as exc:  # the start may blow up where the fit does not: draw what it reached
            curves[label] = np.vstack([getattr(exc, "partial_outputs", np.empty((0, len(OUTPUT_NAMES)))),
                                       np.full((times.size, len(OUTPUT_NAMES)), np.nan)])[:times.size]
    with figure_file(path, 100, figsize=(6.5, 3.2 * len(names)), constrained_layout=True) as fig:
        axes = fig.subplots(len(names), 1, squeeze=False)[:, 0]
        for ax, name in zip(axes, names):
            c = OUTPUT_NAMES.index(name)
            unit = OUTPUTS[name][0]
            ax.plot(times, curves["start"][:, c], color="0.55", ls="--", lw=1.2, label="start")
            ax.plot(times, curves["fitted"][:, c], color="tab:blue", lw=1.6, label="fitted")
            if isinstance(data, SinkTimes):
                s = result.sink
                ax.axhline(s["sink_depth"], color="0.3", lw=0.8, ls=":", label=f"sink depth {s['sink_depth']:g} m")
                ax.axvline(s["measured"], color="tab:red", lw=1.2, label=f"measured sink time {s['measured']:.4g} s")
                if data.times.size > 1:
                    ax.plot(data.times, np.full(data.times.size, s["sink_depth"]), "|", color="tab:red", ms=12,
                            mew=1.2, label="each timed drop")
                if s["standard_error"]:
                    half = result.quantile * s["standard_error"]
                    ax.axvspan(s["measured"] - half, s["measured"] + half, color="tab:red", alpha=0.15, lw=0)
            else:
                y = data.values[name]
                ok = np.isfinite(y)
                sigma = data.sigma[name]
                ax.errorbar(data.times[ok], y[ok], yerr=None if sigma is None else sigma[ok], fmt="o", ms=3.5,
                            color="tab:red", elinewidth=0.8, capsize=0, label="measured", zorder=3)
            ax.set_ylabel(f"{name} ({unit})")
            ax.grid(alpha=0.3)
            ax.legend(loc="best", fontsize=8)
        axes[-1].set_xlabel("time (s)")
        estimates = ", ".join(f"{q.name} = {_g(result.estimates[j], 4)} {q.unit}" for j, q in enumerate(result.parameters))
        fig.suptitle((title + "\n" if title else "") + estimates, fontsize=9)
    return Path(path)


def write_report(result: FitResult, out_dir: str | Path, data_path: str | None = None, scene: str | None = None,
                 fps: float | None = None) -> list[Path]:
    """Write ``fit.json``, ``fitted_scene.toml`` and ``fit.png`` into ``out_dir`` (each whole or not at
    all); their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    report = to_json(result, data_path, scene)
    json_path = write_text(out_dir / JSON_NAME, json.dumps(report, indent=1) + "\n")
    duration = result.sink["t_max"] if result.kind == "sink" else float(np.nanmax(result.data.times))
    described = f"{scene or 'scene'} fitted to {data_path or 'measurements'}: " + ", ".join(
        f"{q.name} = {_g(result.estimates[j], 6)} {q.unit}" for j, q in enumerate(result.parameters))
    toml_path = write_text(out_dir / TOML_NAME, scene_toml(result, described, duration if duration > 0 else None, fps))
    plot_path = plot(result, out_dir / PLOT_NAME, title=f"{scene or 'scene'} fitted to {data_path or 'measurements'}")
    return [json_path, toml_path, plot_path]
