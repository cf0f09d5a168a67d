"""Batch studies: parameter sweeps of wetcloth scenes on Dask, one results-table row per run.

    import wetcloth
    table = wetcloth.study("models/studies/sink_map.toml", out="out/batch/sink_map.parquet", workers=2)

Modules: ``spec`` (the study: ``Study``, ``load_study``), ``axes`` (lists, ranges, bounds, random,
Latin-hypercube and Sobol' points), ``sensitivity`` (Sobol' and Morris designs and indices, SALib),
``plot_spec`` and ``plots``, ``series`` (the runs' kept curves: an xarray Dataset in Zarr), ``metrics``, ``engines`` (one run), ``cluster`` (the Dask client),
``execution`` (running a study, the results table's safe points), ``results`` (the table),
``preview`` (a study's runs and their estimated time, without running them).
See ``docs/batch.md`` for the study file, the ``wetcloth batch`` command and this API.
"""

from wetcloth.batch.cluster import dask_client
from wetcloth.batch.engines import ENGINES, execute
from wetcloth.batch.execution import StudyReport, as_study, run_study, study
from wetcloth.batch.metrics import DEFAULT_METRICS, METRICS, compute_metrics, first_crossing
from wetcloth.batch.plot_spec import PlotSpec, SeriesPlotSpec, parse_plot_spec
from wetcloth.batch.plots import heatmap_data, line_data, plot, plot_sensitivity, plot_series
from wetcloth.batch.results import read_table, write_csv, write_table
from wetcloth.batch.sensitivity import SensitivityResult, SensitivitySpec, format_indices, sensitivity_indices
from wetcloth.batch.series import SeriesStore, read_series, series_path
from wetcloth.batch.spec import Run, Study, load_study
from wetcloth.errors import StudyError
from wetcloth.fmu import default_fmu_path

__all__ = [
    "DEFAULT_METRICS", "ENGINES", "METRICS", "PlotSpec", "Run", "SensitivityResult", "SensitivitySpec", "Study",
    "StudyError", "StudyReport", "as_study", "compute_metrics", "dask_client", "default_fmu_path", "execute",
    "first_crossing", "format_indices", "heatmap_data", "line_data", "load_study", "parse_plot_spec", "plot",
    "plot_sensitivity", "plot_series", "read_series", "read_table", "run_study", "SeriesPlotSpec", "SeriesStore",
    "sensitivity_indices", "series_path", "study", "write_csv", "write_table",
]
