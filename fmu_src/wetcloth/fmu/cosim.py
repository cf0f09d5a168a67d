"""Co-simulate WetCloth.fmu through fmpy, and the demo: the towel with mesh frames, CSV and plot."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wetcloth.fmu.builder import DEFAULT_OUT, build_fmu, is_stale
from wetcloth.runner import RunResult, Snapshot
from wetcloth.scene import PARAMETERS, load_scene, read_scene_file
from wetcloth.simulation import OUTPUT_NAMES

DEFAULT_DEMO_DIR = Path("out") / "demo"
#: Cloth snapshots in the demo plot, evenly spread over the run.
SNAPSHOTS = 4


def simulate(fmu: str | Path, duration: float, fps: float, start_values: dict | None = None, input=None,
             progress: bool = False, debug_logging: bool = False) -> np.ndarray:
    """Run the unit in fmpy from t = 0 to ``duration`` s, one communication step per 1/``fps`` s.

    Returns fmpy's structured array: ``time`` and the six outputs at every communication point.
    ``input`` is fmpy's input signal (a structured array with ``time`` first).
    """
    import fmpy
    from tqdm.auto import tqdm

    with tqdm(total=float(duration), unit="sim s", disable=not progress, desc="co-simulating WetCloth.fmu",
              bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]") as bar:

        def step_finished(time, recorder):
            bar.update(float(time) - bar.n)
            return True

        return fmpy.simulate_fmu(
            str(fmu), start_time=0.0, stop_time=duration, output_interval=1.0 / fps, output=list(OUTPUT_NAMES),
            start_values=dict(start_values or {}), input=input, step_finished=step_finished,
            debug_logging=debug_logging,
        )


def read_frame(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (n, 3) m, wetness (n,) and triangles (m, 3) of an exported PLY frame."""
    import trimesh

    mesh = trimesh.load(str(path), process=False)
    wetness = np.asarray(mesh.metadata["_ply_raw"]["vertex"]["data"]["wetness"], dtype=float)
    return np.asarray(mesh.vertices, dtype=float), wetness, np.asarray(mesh.faces)


def run_result(outputs: np.ndarray, scene, fps: float, frames: Path | None = None,
               snapshots: int = SNAPSHOTS) -> RunResult:
    """A ``RunResult`` (as ``wetcloth.run`` makes) from fmpy outputs and, for snapshots, PLY frames."""
    rows = [{"time": float(row["time"]), **{name: float(row[name]) for name in OUTPUT_NAMES}} for row in outputs]
    result = RunResult(scene=scene, fps=fps, rows=rows)
    if frames is not None and snapshots:
        for index in sorted(set(np.linspace(0, len(rows) - 1, snapshots).round().astype(int).tolist())):
            positions, wetness, triangles = read_frame(frames / f"cloth_{index + 1:04d}.ply")
            result.snapshots.append(Snapshot(rows[index]["time"], positions, wetness))
            result.triangles = triangles
    return result


def demo(out: str | Path = DEFAULT_DEMO_DIR, fmu: str | Path = DEFAULT_OUT, duration: float | None = None,
         start_values: dict | None = None, progress: bool = True) -> dict[str, Path]:
    """Co-simulate the default towel through fmpy: PLY frames, ``outputs.csv`` and ``plot.png`` in ``out``.

    Builds ``fmu`` first if it is missing or older than wetcloth's sources.  The duration (s) and
    frame rate are the towel preset's ``[run]`` table unless ``duration`` is given.
    """
    out, fmu = Path(out), Path(fmu)
    if is_stale(fmu):
        build_fmu(fmu)
    preset = read_scene_file(None)
    run = preset.get("run", {})
    duration = float(run.get("duration", 90.0)) if duration is None else float(duration)
    fps = float(run.get("fps", 30.0))
    frames = out / "frames"
    values = {"mesh_output_dir": str(frames.resolve()), "mesh_format": "ply"} | dict(start_values or {})
    outputs = simulate(fmu, duration, fps, values, progress=progress)
    scene = load_scene(None, **{k: v for k, v in values.items() if k in PARAMETERS})
    result = run_result(outputs, scene, fps, frames)
    csv_path = result.write_csv(out / "outputs.csv")
    from wetcloth.plotting import plot_run

    plot_path = plot_run(result, out / "plot.png", title=f"towel through {fmu.name} (fmpy): {duration:g} s")
    return {"fmu": fmu, "frames": frames, "csv": csv_path, "plot": plot_path}
