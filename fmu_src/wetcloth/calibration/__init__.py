"""Calibration: fit scene parameters to measurements (``wetcloth fit``, docs/fit.md).

    import wetcloth
    from wetcloth.calibration import fit, read_measurements, write_report

    scene = wetcloth.load_scene("towel", nx=9, ny=13)
    result = fit(scene, read_measurements("measured.csv"), ["absorption_rate", "absorption_capacity"])
    print(result.estimates, result.standard_errors, result.intervals)   # 95 % intervals
    write_report(result, "out/fit")          # fit.json, fitted_scene.toml, fit.png

Modules: ``data`` (the measurements CSV, and the values a scene can show), ``parameters`` (what may be
fitted: the scene's number parameters and its tables' number fields, bounds), ``problem``
(the runs a fit evaluates, its finite-difference step and tolerance), ``fitting`` (least squares,
the global search on Dask, the sink-time root search), ``statistics`` (covariance, intervals,
identifiability), ``report`` (text, JSON, TOML, plot).
"""

from wetcloth.calibration.data import Curves, DataError, SinkTimes, read_measurements
from wetcloth.calibration.fitting import FitError, FitResult, fit
from wetcloth.calibration.parameters import BoundsError, parse_bounds
from wetcloth.calibration.report import summary, to_json, scene_toml, write_report

__all__ = ["BoundsError", "Curves", "DataError", "FitError", "FitResult", "SinkTimes", "fit", "parse_bounds",
           "read_measurements", "scene_toml", "summary", "to_json", "write_report"]
