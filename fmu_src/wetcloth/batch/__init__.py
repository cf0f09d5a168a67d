"""Batch studies: parameter sweeps of wetcloth scenes on Dask, one results-table row per run.

    import wetcloth
    table = wetcloth.study("models/studies/sink_map.toml", out="out/batch/sink_map.parquet", workers=2)

See ``docs/batch.md`` for the study file, the ``wetcloth batch`` command and this API.
"""

from wetcloth.batch.engines import execute
from wetcloth.batch.metrics import DEFAULT_METRICS, METRICS, compute_metrics, first_crossing
from wetcloth.batch.plots import heatmap_data, line_data, plot
from wetcloth.batch.results import read_table, write_csv, write_table
from wetcloth.batch.runner import StudyReport, as_study, dask_client, run_study, study
from wetcloth.batch.study import PlotSpec, Run, Study, StudyError, default_fmu_path, load_study, parse_plot_spec

__all__ = [
    "DEFAULT_METRICS", "METRICS", "PlotSpec", "Run", "Study", "StudyError", "StudyReport", "as_study",
    "compute_metrics", "dask_client", "default_fmu_path", "execute", "first_crossing", "heatmap_data", "line_data", "load_study",
    "parse_plot_spec", "plot", "read_table", "run_study", "study", "write_csv", "write_table",
]
