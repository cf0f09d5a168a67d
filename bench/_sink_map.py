"""``models/studies/sink_map.toml`` and its runs, after a warm-up run: shared by the sink_map benchmarks."""

from __future__ import annotations

from wetcloth.batch.engines import python_series
from wetcloth.batch.spec import load_study
from wetcloth.scene import preset_dir


def sink_map_runs():
    """(the study, its runs), after one short untimed run (lazy imports, memory first touched)."""
    study = load_study(preset_dir() / "studies" / "sink_map.toml")
    runs = study.runs()
    python_series(runs[0].params, 0.1, study.sample_rate)
    return study, runs
