"""Co-simulate a WetCloth unit through fmpy (the one fmpy wrapper of wetcloth), and the demo: the towel
with mesh frames, CSV and plot.

``simulate`` is what ``wetcloth demo`` and batch studies with ``engine = "fmu"`` run.  Unlike a bare
``fmpy.simulate_fmu``, it raises when the unit stops early (fmpy ends a run quietly at a step the
unit discards) and puts the unit's own message in the exception: a refused start value names the
parameter and its range, a blow-up is a ``BlowUpError`` as in the Python simulator.
"""

from __future__ import annotations

import atexit
import copy
import math
import os
import shutil
import threading
from pathlib import Path

import numpy as np

from wetcloth import run_settings
from wetcloth.errors import BlowUpError
from wetcloth.fmu import default_fmu_path
from wetcloth.progress import time_bar
from wetcloth.runner import ClothShape, RunResult, shape_frames
from wetcloth.scene import PARAMETERS, load_scene, read_scene_file
from wetcloth.simulation import OUTPUT_NAMES

DEFAULT_DEMO_DIR = Path("out") / "demo"
#: Cloth shapes in the demo plot, evenly spread over the run.
SHAPES = 4


class CoSimulationError(RuntimeError):
    """A co-simulation stopped before its end; the message is the unit's own."""


_extracted: dict[tuple[str, float], tuple[str, object]] = {}
_extract_lock = threading.Lock()


def unpacked(fmu: str | Path) -> tuple[str, object]:
    """The FMU extracted once per process (again if the file changes): (folder, fmpy model description).
    An extracted folder is used as it is."""
    import fmpy

    path = os.path.abspath(fmu)
    if not os.path.exists(path):
        raise FileNotFoundError(f"FMU {path!r} not found: build it with 'wetcloth build-fmu'")
    if os.path.isdir(path):
        return path, fmpy.read_model_description(path)
    stamp = (path, os.path.getmtime(path))
    with _extract_lock:
        if stamp not in _extracted:
            folder = fmpy.extract(path)
            atexit.register(shutil.rmtree, folder, ignore_errors=True)
            _extracted[stamp] = (folder, fmpy.read_model_description(folder))
        return _extracted[stamp]


def _sized(description, start_values: dict):
    """fmpy sizes array outputs by the start values in the model description: a copy whose grid
    parameters (FMI 3.0 structural parameters) and array shapes are those of ``start_values``."""
    arrays = [v for v in description.modelVariables if v.dimensions]
    if not arrays:
        return description
    description = copy.deepcopy(description)
    for variable in description.modelVariables:
        if variable.name in start_values and variable.causality == "structuralParameter":
            variable.start = str(start_values[variable.name])
    for variable in description.modelVariables:
        if variable.dimensions:
            variable.shape = tuple(int(d.start) if d.start is not None else int(d.variable.start)
                                   for d in variable.dimensions)
    return description


def simulate(fmu: str | Path, duration: float, fps: float, start_values: dict | None = None, input=None,
             output=OUTPUT_NAMES, progress: bool = False) -> np.ndarray:
    """Run the unit in fmpy from t = 0 to ``duration`` s, one communication step per 1/``fps`` s.

    Returns fmpy's structured array: ``time`` and the ``output`` variables (by default the six
    outputs; FMI 3.0 units also have ``positions`` and ``wetness`` arrays) at every communication
    point.  ``input`` is fmpy's input signal (a structured array with ``time`` first).  Raises
    CoSimulationError (BlowUpError for a blow-up) with the unit's message if the run does not reach
    ``duration``, ValueError for a variable the unit does not have.
    """
    import fmpy
    from fmpy.fmi1 import FMICallException

    start_values = dict(start_values or {})
    folder, description = unpacked(fmu)
    names = {v.name for v in description.modelVariables}
    unknown = [name for name in [*start_values, *output] if name not in names]
    if unknown:
        raise ValueError(f"the FMU {fmu} has no variable {unknown[0]!r}: rebuild it with 'wetcloth build-fmu'")
    errors: list[str] = []

    def logger(*args):  # FMI 2.0: (environment, instance, status, category, message); FMI 3.0: no instance
        status, message = int(args[-3]), args[-1]
        if status >= 2:
            errors.append(message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message))

    with time_bar(duration, desc=f"co-simulating {Path(fmu).name}", enabled=progress) as bar:

        def step_finished(time, recorder):
            bar.update(float(time) - bar.n)
            return True

        try:
            result = fmpy.simulate_fmu(
                folder, model_description=_sized(description, start_values), fmi_type="CoSimulation",
                start_time=0.0, stop_time=duration, output_interval=1.0 / fps, output=list(output),
                start_values=start_values, input=input, step_finished=step_finished, debug_logging=True,
                logger=logger)
        except FMICallException as exc:
            raise _stopped(errors, f"{exc}", None) from None
    end = float(result["time"][-1]) if len(result) else 0.0
    if not math.isclose(end, duration, rel_tol=1e-9, abs_tol=1e-12):
        raise _stopped(errors, f"the unit stopped at t = {end:g} s of {duration:g} s", end)
    return result


def _stopped(errors: list[str], what: str, last_good_time: float | None) -> Exception:
    """The exception for a run that stopped: the unit's last message, as a BlowUpError if it was one."""
    reason = next((m for m in reversed(errors) if "Fatal py exception" not in m), "no message from the unit")
    if "BlowUpError: " in reason:
        blow_up = reason[reason.index("BlowUpError: ") + len("BlowUpError: "):]
        return BlowUpError(f"{blow_up} (through the FMU: {what})", last_good_time=last_good_time or 0.0)
    return CoSimulationError(f"{what}: {reason}")


def read_frame(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (n, 3) m, wetness (n,) and triangles (m, 3) of an exported PLY frame."""
    import trimesh

    mesh = trimesh.load(str(path), process=False)
    wetness = np.asarray(mesh.metadata["_ply_raw"]["vertex"]["data"]["wetness"], dtype=float)
    return np.asarray(mesh.vertices, dtype=float), wetness, np.asarray(mesh.faces)


def run_result(outputs: np.ndarray, scene, fps: float, frames: Path | None = None,
               shapes: int = SHAPES) -> RunResult:
    """A ``RunResult`` (as ``wetcloth.run`` makes) from fmpy outputs and, for its cloth shapes, PLY frames."""
    from wetcloth.exporter import frame_file_name

    rows = [{"time": float(row["time"]), **{name: float(row[name]) for name in OUTPUT_NAMES}} for row in outputs]
    result = RunResult(scene=scene, fps=fps, rows=rows)
    if frames is not None:
        for index in shape_frames(len(rows), shapes):
            positions, wetness, triangles = read_frame(frames / frame_file_name("cloth", index + 1, "ply"))
            result.shapes.append(ClothShape(rows[index]["time"], positions, wetness))
            result.triangles = triangles
    return result


def demo(out: str | Path = DEFAULT_DEMO_DIR, fmu: str | Path | None = None, duration: float | None = None,
         start_values: dict | None = None, progress: bool = True, native: bool = True) -> dict:
    """Co-simulate the default towel through fmpy: PLY frames, ``outputs.csv`` and ``plot.png`` in ``out``.

    Builds ``fmu`` (default ``default_fmu_path()``) first if it is missing or older than wetcloth's
    sources.  The duration (s) and frame rate are the towel preset's ``[run]`` table unless
    ``duration`` is given.  With ``native``, also builds the native unit (``build-fmu --native``, beside
    ``fmu``, its objects kept in ``build/native``) and co-simulates the same towel through it; the plot shows
    both curves, and the result holds the largest difference of their outputs (``native_difference``:
    zero, the same core) or, where no C++ compiler is found, why there is no native run
    (``native_skipped``).
    """
    from wetcloth.fmu.builder import build_fmu, is_stale

    out, fmu = Path(out), Path(default_fmu_path() if fmu is None else fmu)
    if is_stale(fmu):
        build_fmu(fmu)
    run = run_settings.resolve(read_scene_file(None).get("run"), duration=duration)
    duration, fps = run.duration, run.fps
    frames = out / "frames"
    values = {"mesh_output_dir": str(frames.resolve()), "mesh_format": "ply"} | dict(start_values or {})
    outputs = simulate(fmu, duration, fps, values, progress=progress)
    scene_values = {k: v for k, v in values.items() if k in PARAMETERS}
    scene = load_scene(None, **scene_values)
    result = run_result(outputs, scene, fps, frames)
    csv_path = result.write_csv(out / "outputs.csv")
    paths = {"fmu": fmu, "frames": frames, "csv": csv_path}
    compare = {}
    if native:
        from wetcloth.fmu.native import NativeBuildError, build_native_fmu, native_fmu_path

        try:
            native_fmu = build_native_fmu(fmu.parent / native_fmu_path().name, build_dir=Path("build") / "native")
        except NativeBuildError as exc:
            paths["native_skipped"] = str(exc)
        else:
            native_outputs = simulate(native_fmu, duration, fps, scene_values, progress=progress)
            compare[native_fmu.name] = native_outputs
            paths["native"] = native_fmu
            paths["native_difference"] = max(float(np.max(np.abs(native_outputs[name] - outputs[name])))
                                             for name in OUTPUT_NAMES)
    from wetcloth.plotting import plot_run

    title = f"towel through {' and '.join([fmu.name, *compare])} (fmpy): {duration:g} s"
    paths["plot"] = plot_run(result, out / "plot.png", title=title, label=fmu.name, compare=compare)
    return paths
