"""What to plot from a study's results: a metric against one axis (a line) or over two (a heatmap)."""

from __future__ import annotations

from dataclasses import dataclass

from wetcloth.errors import StudyError


@dataclass(frozen=True)
class PlotSpec:
    """A plot of ``metric`` against axis ``x`` (a line), or over ``x`` and ``y`` (a heatmap)."""

    metric: str
    x: str
    y: str | None = None

    def filename(self, stem: str) -> str:
        """``<stem>_<metric>_vs_<x>.png`` or ``<stem>_<metric>_<x>_x_<y>.png``; ``wetcloth batch`` gives
        its results table's stem (``--out runs/a.parquet``: ``a_...``)."""
        if self.y is None:
            return f"{stem}_{self.metric}_vs_{self.x}.png"
        return f"{stem}_{self.metric}_{self.x}_x_{self.y}.png"


def parse_plot_spec(text: str) -> PlotSpec:
    """'METRIC:AXIS' (line) or 'METRIC:X,Y' (heatmap), as given to ``wetcloth batch --plot``."""
    metric, sep, rest = text.partition(":")
    axes = [a.strip() for a in rest.split(",") if a.strip()]
    if not sep or not metric.strip() or len(axes) not in (1, 2):
        raise StudyError("plot", f"expected METRIC:AXIS or METRIC:X,Y, got {text!r}")
    return PlotSpec(metric.strip(), axes[0], axes[1] if len(axes) == 2 else None)


def plot_specs(entries) -> tuple[PlotSpec, ...]:
    """The ``[[plot]]`` tables of a study file (metric, x, optional y)."""
    if not isinstance(entries, list) or not all(isinstance(p, dict) for p in entries):
        raise StudyError("plot", "must be an array of tables [[plot]] with metric, x and optional y")
    specs = []
    for p in entries:
        if set(p) - {"metric", "x", "y"} or not {"metric", "x"} <= set(p):
            raise StudyError("plot", f"each [[plot]] has metric, x and optional y; got {sorted(p)}")
        specs.append(PlotSpec(p["metric"], p["x"], p.get("y")))
    return tuple(specs)
