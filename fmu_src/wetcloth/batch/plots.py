"""Plots of a results table: a metric against one axis, and a heatmap of a metric over two axes; and
of a study's kept curves: every run's, overlaid against time and coloured by an axis.

Only runs with status 'ok' are plotted (only they have curves).  When other axes vary too, each point of the plot is the
mean over them (the line plot also shows every run as a dot).  A run whose metric is NaN (for
``time_to_sink``: it never sank) is drawn as 'never' rather than dropped silently.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from wetcloth.batch.metrics import METRICS
from wetcloth.batch.plot_spec import PlotSpec, SeriesPlotSpec
from wetcloth.scene import is_parameter, parameter_field
from wetcloth.simulation import OUTPUTS


def _label(name: str) -> str:
    if name in METRICS:
        unit = METRICS[name].unit
    elif name in OUTPUTS:
        unit = OUTPUTS[name][0]
    elif is_parameter(name):
        unit = parameter_field(name).metadata["unit"]
    else:
        unit = "-"
    return name.replace("_", " ") + ("" if unit == "-" else f" ({unit})")


def _ok(table: pd.DataFrame, spec: PlotSpec) -> pd.DataFrame:
    for column in (spec.metric, spec.x, spec.y):
        if column is not None and column not in table:
            raise ValueError(f"cannot plot: the results table has no column {column!r}")
    return table[table["status"] == "ok"]


def line_data(table: pd.DataFrame, metric: str, x: str) -> pd.DataFrame:
    """Per value of axis ``x``: ``mean`` of the metric over the finite values, ``count`` of ok runs,
    ``never`` the number of ok runs whose metric is NaN."""
    ok = _ok(table, PlotSpec(metric, x))
    grouped = ok.groupby(x)[metric]
    return pd.DataFrame({"mean": grouped.mean(), "count": grouped.size(), "never": grouped.apply(lambda s: int(s.isna().sum()))})


def heatmap_data(table: pd.DataFrame, metric: str, x: str, y: str) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(values, ok, runs): per (y row, x column) cell, the mean metric over its ok runs' finite
    values (NaN if none), the number of ok runs, and the number of runs of any status."""
    ok = _ok(table, PlotSpec(metric, x, y))
    xs = sorted(table[x].dropna().unique())
    ys = sorted(table[y].dropna().unique())

    def grid(frame: pd.DataFrame, values: str, aggfunc: str) -> pd.DataFrame:
        if not len(frame):
            return pd.DataFrame(np.nan, index=ys, columns=xs)
        return frame.pivot_table(index=y, columns=x, values=values, aggfunc=aggfunc).reindex(index=ys, columns=xs)

    counts = [grid(f, "run_key", "count").fillna(0).astype(int) for f in (ok, table)]
    return grid(ok, metric, "mean"), counts[0], counts[1]


def plot(table: pd.DataFrame, spec: PlotSpec | SeriesPlotSpec, path: str | Path, study=None, series=None) -> Path:
    """Draw ``spec`` (a line if ``spec.y`` is None, else a heatmap) from ``table`` to a PNG at ``path``;
    a :class:`SeriesPlotSpec` from the curves ``series`` (the study's Dataset: ``StudyReport.series``)."""
    from wetcloth.plotting import figure_file

    if isinstance(spec, SeriesPlotSpec):
        if series is None:
            raise ValueError("cannot plot the curves: none were kept (the study needs series = [...] and a results "
                             "table to keep them beside)")
        return plot_series(series, spec, path, study=study)

    title = f"{study.name}: " if study is not None else ""
    with figure_file(path, 110, figsize=(6.4, 4.8), constrained_layout=True) as fig:
        ax = fig.subplots()
        if spec.y is None:
            _line(ax, table, spec)
            ax.set_title(f"{title}{spec.metric} vs {spec.x}")
        else:
            _heatmap(fig, ax, table, spec)
            ax.set_title(f"{title}{spec.metric} over {spec.x} x {spec.y}")
    return Path(path)


def _line(ax, table: pd.DataFrame, spec: PlotSpec) -> None:
    ok = _ok(table, spec)
    data = line_data(table, spec.metric, spec.x)
    finite = ok[np.isfinite(ok[spec.metric])]
    ax.plot(finite[spec.x], finite[spec.metric], "o", color="0.6", ms=4, label="runs")
    ax.plot(data.index, data["mean"], "-o", color="C0", label="mean" if len(ok) > len(data) else spec.metric)
    never = data[data["never"] > 0]
    if len(never):
        top = np.nanmax(ok[spec.metric]) if np.isfinite(ok[spec.metric]).any() else 1.0
        ax.plot(never.index, np.full(len(never), top), "^", color="C3", label="never (NaN) in some runs")
    ax.set_xlabel(_label(spec.x))
    ax.set_ylabel(_label(spec.metric))
    ax.grid(alpha=0.3)
    ax.legend()


def _heatmap(fig, ax, table: pd.DataFrame, spec: PlotSpec) -> None:
    values, ok_counts, run_counts = heatmap_data(table, spec.metric, spec.x, spec.y)
    grid = values.to_numpy(float)
    import matplotlib

    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="0.85")  # grey: no finite value
    image = ax.imshow(np.ma.masked_invalid(grid), origin="lower", aspect="auto", cmap=cmap)
    fig.colorbar(image, ax=ax, label=_label(spec.metric))
    ax.set_xticks(range(len(values.columns)), [f"{v:g}" if isinstance(v, (int, float)) else str(v) for v in values.columns])
    ax.set_yticks(range(len(values.index)), [f"{v:g}" if isinstance(v, (int, float)) else str(v) for v in values.index])
    ax.set_xlabel(_label(spec.x))
    ax.set_ylabel(_label(spec.y))
    small = grid.size <= 150
    for (i, j), v in np.ndenumerate(grid):
        if run_counts.iat[i, j] == 0:
            continue
        if ok_counts.iat[i, j] == 0:
            ax.text(j, i, "error", ha="center", va="center", fontsize=7, color="C3")
        elif not np.isfinite(v):
            ax.text(j, i, "never", ha="center", va="center", fontsize=7, color="0.3")
        elif small:
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=7, color="k" if image.norm(v) > 0.6 else "w")


def series_colours(values: np.ndarray, axis=None):
    """(colours, legend): one RGBA colour per value of the colouring axis, and how to explain them: a
    ``ScalarMappable`` for numbers (viridis; a logarithmic scale for a log-uniform axis or a geometric
    grid), a {value: colour} dict for text."""
    import matplotlib
    from matplotlib.colors import LogNorm, Normalize

    values = np.asarray(values)
    if values.dtype.kind in "OUST" or values.dtype.kind == "b":
        names = list(dict.fromkeys(str(v) for v in values))
        palette = {name: matplotlib.colormaps["tab10"](i % 10) for i, name in enumerate(names)}
        return [palette[str(v)] for v in values], palette
    numbers = values.astype(float)
    finite = numbers[np.isfinite(numbers)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    norm = LogNorm(lo, hi) if _log_scaled(finite, axis) else Normalize(lo, hi if hi > lo else lo + 1.0)
    mappable = matplotlib.cm.ScalarMappable(norm=norm, cmap=matplotlib.colormaps["viridis"])
    return [mappable.to_rgba(v) for v in numbers], mappable


def _log_scaled(values: np.ndarray, axis) -> bool:
    """Whether an axis is best coloured on a log scale: sampled log-uniform, or a grid of three or more
    positive values in geometric progression."""
    if values.size == 0 or values.min() <= 0:
        return False
    if axis is not None and axis.distribution is not None:
        return axis.distribution.get("random") == "loguniform"
    grid = np.unique(values)
    if grid.size < 3:
        return False
    ratios = grid[1:] / grid[:-1]
    return bool(np.allclose(ratios, ratios[0], rtol=1e-6) and ratios[0] > 1.0 + 1e-9)


def plot_series(series, spec: SeriesPlotSpec, path: str | Path, study=None) -> Path:
    """The kept curves (an xarray Dataset: ``StudyReport.series`` or ``xarray.open_zarr`` of
    ``NAME.series.zarr``) to a PNG at ``path``: one panel per output of ``spec`` (all of the Dataset's if
    it names none), one line per run, coloured by its value on the axis ``spec.color`` (default: the
    study's first axis, else the Dataset's first coordinate along ``run``), with a colour bar or legend."""
    from wetcloth.plotting import figure_file

    names = list(spec.series or [n for n in series.data_vars if series[n].dims == ("run", "time")])
    missing = [n for n in names if n not in series.data_vars]
    if missing or not names:
        raise ValueError(f"cannot plot the curves of {', '.join(missing) or 'no output'}: the kept curves are "
                         f"{', '.join(series.data_vars) or 'none'}")
    along_run = [c for c in series.coords if series[c].dims == ("run",) and c != "run"]
    color = spec.color or (study.axis_names[0] if study is not None and study.axis_names else
                           (along_run[0] if along_run else None))
    if color is not None and color not in series.coords:
        raise ValueError(f"cannot colour the curves by {color!r}: it is not a coordinate of the kept curves; "
                         f"they have {', '.join(along_run) or 'none'}")
    axis = next((a for a in study.axes if a.name == color), None) if study is not None else None
    runs = series.sizes["run"]
    time = np.asarray(series["time"].values, float)
    if color is not None:
        colours, legend = series_colours(np.asarray(series[color].values), axis)
    else:
        colours, legend = ["C0"] * runs, None
    width = 0.6 if runs > 100 else 1.0 if runs > 20 else 1.4
    alpha = 0.45 if runs > 100 else 0.8
    title = f"{study.name}: " if study is not None else ""
    with figure_file(path, 110, figsize=(7.2, 0.6 + 2.6 * len(names)), constrained_layout=True) as fig:
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        for ax, name in zip(axes, names):
            values = np.asarray(series[name].values, float)
            for i in range(runs):
                ax.plot(time, values[i], color=colours[i], lw=width, alpha=alpha)
            ax.set_ylabel(_label(name))
            ax.grid(alpha=0.3)
            if name == "depth":
                ax.invert_yaxis()  # down is deeper, as the cloth goes
            if runs == 0:
                ax.text(0.5, 0.5, "no curves (no run finished ok)", ha="center", va="center",
                        transform=ax.transAxes, color="0.4")
        axes[-1].set_xlabel("time (s)")
        if isinstance(legend, dict):
            from matplotlib.lines import Line2D

            handles = [Line2D([], [], color=c, lw=2, label=v) for v, c in legend.items()]
            axes[0].legend(handles=handles, title=color.replace("_", " "), fontsize=8)
        elif legend is not None:
            bar = fig.colorbar(legend, ax=list(axes), label=_label(color))
            ticks = np.unique(np.asarray(series[color].values, float))
            if 0 < ticks.size <= 12:  # a grid's values, as they are
                bar.minorticks_off()
                bar.set_ticks(ticks, labels=[f"{v:g}" for v in ticks])
        fig.suptitle(f"{title}{', '.join(names)} of {runs} runs" + (f", coloured by {color}" if color else ""),
                     fontsize=10)
    return Path(path)


def plot_sensitivity(result, path: str | Path, study=None) -> Path:
    """A bar chart of a :class:`~wetcloth.batch.sensitivity.SensitivityResult` to a PNG at ``path``:
    one panel per analysed metric, its factors from most to least influential; Sobol: S1 and ST
    side by side, Morris: mu* and sigma, with the confidence intervals as error bars.  A metric
    without indices gets a panel that says why."""
    from wetcloth.plotting import figure_file

    sobol = result.spec.method == "sobol"
    width = max(6.4, 1.8 + 0.9 * len(result.factors))
    with figure_file(path, 110, figsize=(width, 0.4 + 2.9 * len(result.metrics)), constrained_layout=True) as fig:
        axes = fig.subplots(len(result.metrics), 1, squeeze=False)
        for ax, metric in zip(axes[:, 0], result.metrics):
            ax.set_title(f"{_label(metric)}", fontsize=10)
            if metric in result.problems:
                _no_indices(ax, result.problems[metric])
                continue
            frame = result.indices[result.indices["metric"] == metric].sort_values("rank")
            bars = (("S1", "S1_conf", "first order S1"), ("ST", "ST_conf", "total ST")) if sobol else \
                (("mu_star", "mu_star_conf", "mu*"), ("sigma", None, "sigma"))
            x = np.arange(len(frame))
            for i, (column, conf, label) in enumerate(bars):
                ax.bar(x + (i - 0.5) * 0.38, frame[column], 0.38, label=label, color=f"C{i}",
                       yerr=None if conf is None else frame[conf], capsize=3, error_kw=dict(lw=1))
            ax.set_xticks(x, [n.replace("_", " ") for n in frame["parameter"]], fontsize=8)
            ax.axhline(0.0, color="0.3", lw=0.6)
            ax.set_ylabel("share of variance" if sobol else f"{METRICS[metric].unit} over the range")
            ax.grid(axis="y", alpha=0.3)
            ax.legend(fontsize=8)
        level = f"{100 * result.spec.conf_level:g}%"
        title = f"{study.name}\n" if study is not None else ""
        fig.suptitle(f"{title}{result.spec.describe(len(result.factors))}; error bars: {level} confidence", fontsize=10)
    return Path(path)


def _no_indices(ax, problem: str) -> None:
    import textwrap

    short = problem if len(problem) <= 450 else problem[:450] + " ... (the rest: the command's output)"
    ax.text(0.5, 0.5, textwrap.fill(short, 110), ha="center", va="center", fontsize=7, color="C3",
            transform=ax.transAxes)
    ax.set_axis_off()
