"""Plots of a run: depth and masses against time, and shapes of the cloth coloured by wetness."""

from __future__ import annotations

import contextlib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.backend_bases import FigureCanvasBase  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from wetcloth.files import whole_file  # noqa: E402

WETNESS_CMAP = "YlGnBu"


def image_format(path: str | Path) -> str:
    """The image format of a plot written to ``path``: its suffix (PNG without one); a ValueError naming
    the formats matplotlib writes for a suffix it does not."""
    suffix = Path(path).suffix.lstrip(".").lower()
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix and suffix not in formats:
        raise ValueError(f"{path}: '.{suffix}' is not an image format; allowed: a file name ending in "
                         f"{', '.join('.' + f for f in sorted(formats))}, or no suffix (PNG)")
    return suffix or "png"


@contextlib.contextmanager
def figure_file(path: str | Path, dpi: int, **options):
    """``with figure_file(path, dpi, **options) as fig``: a figure (``plt.figure(**options)``), written to ``path`` (format from its suffix, PNG without one) whole or not at all when the block
    ends without error, and closed in any case."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(**options)
    try:
        yield fig
        with whole_file(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=image_format(path))
    finally:
        plt.close(fig)


def plot_run(result, path: str | Path, title: str | None = None, label: str | None = None,
             compare: dict | None = None) -> Path:
    """Write a figure (whole or not at all): depth, wet mass and water mass against time, and the
    run's cloth shapes.  ``compare`` maps a label to other runs' outputs (columns ``time``, ``depth``,
    ``wet_mass``, ``water_mass``), drawn dashed over the run's curves (``label`` names the run's)."""
    shots = result.shapes
    with figure_file(path, 90, figsize=(4 * max(len(shots), 3), 8), constrained_layout=True) as fig:
        _draw_run(fig, result, title, label, compare or {})
    return Path(path)


def _draw_run(fig, result, title: str | None, label: str | None, compare: dict) -> None:
    shots = result.shapes
    grid = fig.add_gridspec(2, max(len(shots), 3))
    t = result.column("time")

    ax = fig.add_subplot(grid[0, : max(len(shots), 3) // 2 + 1])
    ax.plot(t, 100 * result.column("depth"), color="tab:blue", label=label)
    for name, other in compare.items():
        ax.plot(other["time"], 100 * other["depth"], color="black", ls="--", lw=1.0, label=name)
    if compare:
        ax.legend(loc="lower right")
    ax.axhline(0.0, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("depth of the centroid below the surface (cm)")
    ax.invert_yaxis()
    ax.set_title("depth")

    ax = fig.add_subplot(grid[0, max(len(shots), 3) // 2 + 1 :])
    ax.plot(t, 1000 * result.column("wet_mass"), label="wet mass", color="tab:purple")
    ax.plot(t, 1000 * result.column("water_mass"), label="absorbed water", color="tab:cyan")
    for name, other in compare.items():
        for column in ("wet_mass", "water_mass"):
            ax.plot(other["time"], 1000 * other[column], color="black", ls="--", lw=1.0,
                    label=f"{name}" if column == "wet_mass" else None)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("mass (g)")
    ax.legend(loc="upper left")
    ax.set_title("mass")

    level = result.scene.water_level
    lows = [s.positions[:, 2].min() for s in shots] + [level]
    highs = [s.positions[:, 2].max() for s in shots] + [level]
    zlim = (min(lows) - 0.02, max(highs) + 0.02)
    for k, shot in enumerate(shots):
        ax = fig.add_subplot(grid[1, k], projection="3d")
        _draw_cloth(ax, shot, result.triangles, level, zlim)
    sm = plt.cm.ScalarMappable(cmap=WETNESS_CMAP, norm=plt.Normalize(0, 1))
    if shots:
        fig.colorbar(sm, ax=fig.axes[-1], shrink=0.6, label="wetness (saturation)")
    fig.suptitle(title or "wetcloth run")


def _draw_cloth(ax, shot, triangles, water_level, zlim):
    """The cloth's triangles coloured by mean wetness, over a translucent water surface."""
    p = shot.positions
    face_wetness = shot.wetness[triangles].mean(axis=1)
    colours = plt.get_cmap(WETNESS_CMAP)(face_wetness)
    ax.add_collection3d(Poly3DCollection(p[triangles], facecolors=colours, edgecolors="none"))
    lo, hi = p[:, :2].min(axis=0), p[:, :2].max(axis=0)
    span = max(hi - lo) * 0.6 + 1e-3
    cx, cy = (lo + hi) / 2
    xs = np.array([[cx - span, cx + span], [cx - span, cx + span]])
    ys = np.array([[cy - span, cy - span], [cy + span, cy + span]])
    ax.plot_surface(xs, ys, np.full_like(xs, water_level), color="tab:blue", alpha=0.15)
    ax.set_xlim(cx - span, cx + span)
    ax.set_ylim(cy - span, cy + span)
    ax.set_zlim(*zlim)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.set_title(f"t = {shot.time:.1f} s")
    ax.view_init(elev=20, azim=-60)
