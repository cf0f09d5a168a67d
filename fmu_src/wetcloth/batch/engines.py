"""One run of a study, as a Dask task: simulate a scene, compute its metrics, never raise.

Two engines give the output time series: ``python`` (``Simulation.sample``, the default) and
``fmu`` (``models/WetCloth.fmu`` co-simulated through fmpy by ``wetcloth.fmu.cosim.simulate``).  An exception in a
run becomes a result with status ``error`` and the exception's text, so the study goes on.  A study
that keeps curves (``series``) gets them back with the result, under ``series``.
"""

from __future__ import annotations

import os
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np

from wetcloth.batch.metrics import compute_metrics
from wetcloth.simulation import OUTPUT_NAMES

#: Every output series a run gives: time (s), then the outputs (``wetcloth.simulation.OUTPUTS``).
RUN_SERIES = ("time", *OUTPUT_NAMES)

#: The engines a study may run on.
ENGINES = ("python", "fmu")
OK = "ok"
ERROR = "error"


def python_series(params: dict[str, Any], duration: float, sample_rate: float) -> dict[str, np.ndarray]:
    """Outputs of the Python simulator sampled at ``sample_rate`` Hz from 0 to ``duration`` s: the frames
    and values of ``wetcloth.runner.run`` with no shapes, sampled in one compiled call and kept as arrays
    (a run's table of rows, one dict per frame, cost as much as building its scene)."""
    from wetcloth.runner import frame_times
    from wetcloth.scene import from_dict
    from wetcloth.simulation import Simulation

    times = frame_times(duration, sample_rate)
    outputs = Simulation(from_dict(params)).sample(times)
    return {"time": times, **{name: outputs[:, k].copy() for k, name in enumerate(OUTPUT_NAMES)}}


def is_fmu_variable(name: str) -> bool:
    """Whether study parameter ``name`` is a variable of a unit built from the study's scene: a scene parameter,
    or a number field of one of its colliders (collider1_radius; ``vocabulary.COLLIDER_VARIABLES``)."""
    from wetcloth.fmu.vocabulary import COLLIDER_VARIABLES
    from wetcloth.scene import PARAMETERS, collider_name

    where = collider_name(name)
    return name in PARAMETERS or (where is not None and where[1] in COLLIDER_VARIABLES)


def fmu_series(params: dict[str, Any], duration: float, sample_rate: float, fmu: str) -> dict[str, np.ndarray]:
    """Outputs of the FMU (fmpy co-simulation, communication step 1/``sample_rate`` s); a run the unit
    stops early raises (a blow-up as BlowUpError), as the Python engine does.  The scene's colliders (their
    number, shapes and files), grip keys and collider keys must be those built into the unit (ValueError
    otherwise); the other parameters, the colliders' number fields among them, are its start values."""
    from wetcloth.fmu.cosim import simulate, unpacked
    from wetcloth.fmu.packed_scene import check_carries
    from wetcloth.scene import from_dict

    folder, _ = unpacked(fmu)
    check_carries(fmu, Path(folder) / "resources", from_dict(params))
    variables = {name: value for name, value in params.items() if is_fmu_variable(name)}
    result = simulate(fmu, duration, sample_rate, variables, output=OUTPUT_NAMES)
    return {name: np.asarray(result[name], float) for name in RUN_SERIES}


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"


def execute(task: dict[str, Any]) -> dict[str, Any]:
    """Run one study run; ``task`` has key, params, duration, sample_rate, sink_depth, metrics,
    engine, fmu, and optionally series (outputs whose curves to return).  Returns run_key, status
    ('ok' or 'error'), error, the metrics, run_time (s of wall-clock time), cpu_time (s of CPU time of
    the thread that ran it; well below run_time = cores shared), worker; with series, an ok run also
    ``series``: {'time': its sample times, output: values} (float64 arrays)."""
    start = time.perf_counter()
    cpu_start = time.thread_time()
    row: dict[str, Any] = {"run_key": task["key"]}
    try:
        if task["engine"] == "fmu":
            series = fmu_series(task["params"], task["duration"], task["sample_rate"], task["fmu"])
        else:
            series = python_series(task["params"], task["duration"], task["sample_rate"])
        row.update(compute_metrics(series, task["metrics"], task["sink_depth"]))
        row.update(status=OK, error=None)
        if task.get("series"):
            row["series"] = {name: np.asarray(series[name], float) for name in ("time", *task["series"])}
    except Exception as exc:  # every failure of a run is data, not a crash of the study
        message = f"{type(exc).__name__}: {exc}"
        if not isinstance(exc, (ValueError, RuntimeError)):  # unexpected: keep where it came from
            message += "\n" + "".join(traceback.format_exception(exc)[-3:])
        row.update(status=ERROR, error=message)
    row["run_time"] = time.perf_counter() - start
    row["cpu_time"] = time.thread_time() - cpu_start
    row["worker"] = _worker_name()
    return row


def fmu_path_or_default(path: str) -> str:
    from wetcloth.fmu import default_fmu_path

    return str(Path(path or default_fmu_path()).resolve())
