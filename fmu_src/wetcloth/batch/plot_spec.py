"""What to plot from a study's results: a metric against one axis (a line) or over two (a heatmap),
and the curves a study keeps, overlaid and coloured by an axis (kind ``series``)."""

from __future__ import annotations

from dataclasses import dataclass

from wetcloth.errors import StudyError

#: The kinds of [[plot]]: without ``kind``, a plot with ``y`` is a heatmap, else a line.
KINDS = ("line", "heatmap", "series")


@dataclass(frozen=True)
class PlotSpec:
    """A plot of ``metric`` against axis ``x`` (a line), or over ``x`` and ``y`` (a heatmap)."""

    metric: str
    x: str
    y: str | None = None

    @property
    def kind(self) -> str:
        return "line" if self.y is None else "heatmap"

    def filename(self, stem: str) -> str:
        """``<stem>_<metric>_vs_<x>.png`` or ``<stem>_<metric>_<x>_x_<y>.png``; ``wetcloth batch`` gives
        its results table's stem (``--out runs/a.parquet``: ``a_...``)."""
        if self.y is None:
            return f"{stem}_{self.metric}_vs_{self.x}.png"
        return f"{stem}_{self.metric}_{self.x}_x_{self.y}.png"


@dataclass(frozen=True)
class SeriesPlotSpec:
    """The kept curves of ``series`` (outputs; empty: every kept one), one panel each against time, one
    line per run, coloured by its value on axis ``color`` (None: the study's first axis)."""

    series: tuple[str, ...] = ()
    color: str | None = None
    kind = "series"

    def filename(self, stem: str, series: tuple[str, ...] = (), color: str | None = None) -> str:
        """``<stem>_series_<output>[_<output>...]_by_<axis>.png``; ``series`` and ``color`` fill in what
        the spec leaves to the study (all kept outputs, the first axis)."""
        names = "_".join(self.series or series) or "curves"
        axis = self.color or color
        return f"{stem}_series_{names}" + (f"_by_{axis}" if axis else "") + ".png"


def parse_plot_spec(text: str) -> PlotSpec | SeriesPlotSpec:
    """'METRIC:AXIS' (line), 'METRIC:X,Y' (heatmap) or 'series:AXIS' (the kept curves coloured by
    AXIS), as given to ``wetcloth batch --plot``."""
    metric, sep, rest = text.partition(":")
    axes = [a.strip() for a in rest.split(",") if a.strip()]
    if metric.strip() == "series" and sep and len(axes) == 1:
        return SeriesPlotSpec(color=axes[0])
    if not sep or not metric.strip() or len(axes) not in (1, 2):
        raise StudyError("plot", f"expected METRIC:AXIS, METRIC:X,Y or series:AXIS, got {text!r}")
    return PlotSpec(metric.strip(), axes[0], axes[1] if len(axes) == 2 else None)


def _text(value, what: str) -> str:
    if not isinstance(value, str):
        raise StudyError("plot", f"{what} must be a name (text), got {value!r}")
    return value


def _series_spec(p: dict) -> SeriesPlotSpec:
    if set(p) - {"kind", "series", "color"}:
        raise StudyError("plot", f"a [[plot]] of kind 'series' has series (an output or a list of them; default: "
                                 f"every kept one) and color (an axis); got {sorted(p)}")
    series = p.get("series", [])
    series = [series] if isinstance(series, str) else series
    if not isinstance(series, list):
        raise StudyError("plot", f"series must be an output name or a list of them, got {series!r}")
    if len(set(series)) != len(series):
        raise StudyError("plot", f"repeated output in series = {series}")
    color = p.get("color")
    return SeriesPlotSpec(tuple(_text(s, "each of series") for s in series),
                          None if color is None else _text(color, "color"))


def plot_specs(entries) -> tuple[PlotSpec | SeriesPlotSpec, ...]:
    """The ``[[plot]]`` tables of a study file: metric, x and optional y; or kind = "series" with
    optional series and color."""
    if not isinstance(entries, list) or not all(isinstance(p, dict) for p in entries):
        raise StudyError("plot", "must be an array of tables [[plot]] with metric, x and optional y "
                                 "(or kind = \"series\")")
    specs = []
    for p in entries:
        kind = p.get("kind")
        if kind is not None and kind not in KINDS:
            raise StudyError("plot", f"kind {kind!r} is not a kind of plot; kinds: {', '.join(KINDS)}")
        if kind == "series":
            specs.append(_series_spec(p))
            continue
        if set(p) - {"kind", "metric", "x", "y"} or not {"metric", "x"} <= set(p):
            raise StudyError("plot", f"each [[plot]] has metric, x and optional y; got {sorted(p)}")
        if kind == "heatmap" and "y" not in p:
            raise StudyError("plot", f"a heatmap has metric, x and y; got {sorted(p)}")
        if kind == "line" and "y" in p:
            raise StudyError("plot", "a line plot has metric and x (a plot with y is a heatmap)")
        specs.append(PlotSpec(p["metric"], p["x"], p.get("y")))
    return tuple(specs)
