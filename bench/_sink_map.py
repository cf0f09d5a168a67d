"""``models/studies/sink_map.toml`` and its runs, the kernels loaded: shared by the sink_map benchmarks."""

from __future__ import annotations

from wetcloth.batch.engines import python_series
from wetcloth.batch.spec import load_study
from wetcloth.scene import preset_dir


def sink_map_runs():
    """(the study, its runs), after one short run that loads (or compiles) the kernels, untimed."""
    study = load_study(preset_dir() / "studies" / "sink_map.toml")
    runs = study.runs()
    python_series(runs[0].params, 0.1, study.sample_rate)
    return study, runs
