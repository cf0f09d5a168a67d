"""Sampling (lhs, sobol) and sensitivity indices (SALib) of batch studies, without Dask or the simulator.

Known functions stand in for the runs: the Ishigami function for the Sobol' indices (analytic
values), a linear function for Morris' elementary effects (exact), and results tables made from
them, so the study's own path (design -> runs and keys -> table -> indices) is what is checked.
"""

import math

import numpy as np
import pandas as pd
import pytest

from wetcloth.batch import Study, StudyError, plot_sensitivity, sensitivity_indices
from wetcloth.batch.axes import Axis, from_unit
from wetcloth.batch.results import make_table
from wetcloth.batch.sensitivity import SensitivitySpec, analyze, design, format_indices

A, B = 7.0, 0.1  # Ishigami constants


def ishigami_exact() -> tuple[np.ndarray, np.ndarray]:
    """First-order and total indices of Ishigami (a = 7, b = 0.1) on [-pi, pi]^3 (Ishigami & Homma 1990;
    Sobol' & Levitan 1999): V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V13 = b^2 pi^8 (1/18 - 1/50),
    V = V1 + V2 + V13.  S1 = 0.3139, 0.4424, 0; ST = 0.5576, 0.4424, 0.2437."""
    v1, v2, v13 = 0.5 * (1 + B * math.pi**4 / 5) ** 2, A**2 / 8, B**2 * math.pi**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def ishigami(x: np.ndarray) -> np.ndarray:
    return np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0])


def test_ishigami_exact_values_are_the_published_ones():
    s1, st = ishigami_exact()
    np.testing.assert_allclose(s1, [0.3139, 0.4424, 0.0], atol=5e-5)
    np.testing.assert_allclose(st, [0.5576, 0.4424, 0.2437], atol=5e-5)


PI_AXES = [Axis(f"x{i}", distribution={"random": "uniform", "low": -math.pi, "high": math.pi}) for i in (1, 2, 3)]
NAMES = [a.name for a in PI_AXES]


def ishigami_indices(samples: int, seed: int) -> dict[str, np.ndarray]:
    """The study's index code on the Ishigami function: its Saltelli design, mapped to [-pi, pi] by the
    axes' own mapping (``from_unit``), evaluated, analysed."""
    spec = SensitivitySpec(method="sobol", samples=samples)
    unit = design(spec, NAMES, seed)
    x = np.column_stack([from_unit(a, unit[:, j]) for j, a in enumerate(PI_AXES)])
    return analyze(spec, NAMES, unit, ishigami(x), seed)


def test_sobol_indices_of_ishigami_match_the_analytic_values_within_their_intervals():
    """N = 1024 base samples (5120 evaluations, 0.2 s).  Seed fixed (2005): the 95% intervals are
    random, and a check against them could fail by chance (about 1 in 20 per index) with another
    seed.  Besides the intervals, an absolute tolerance: over 50 seeds at this N the largest error of
    the six indices was 0.027 and the interval half-widths 0.03 to 0.09, so 0.05 holds with margin
    and would catch a wrong estimator (or a wrong mapping of the design) by far."""
    s1, st = ishigami_exact()
    found = ishigami_indices(1024, seed=2005)
    for name, exact in (("S1", s1), ("ST", st)):
        error = np.abs(found[name] - exact)
        conf = found[f"{name}_conf"]
        assert (error <= conf).all(), (name, found[name], exact, conf)
        assert (error < 0.05).all(), (name, found[name], exact)
        assert (conf < 0.1).all(), (name, conf)  # intervals narrow enough to mean something


def test_sobol_intervals_cover_the_analytic_values_about_as_often_as_they_say():
    """Over 20 seeds (120 indices), 95% intervals hold the exact value at least 90% of the time (at
    N = 1024 they held it in 300 of 300 over 50 seeds: SALib's bootstrap intervals are conservative
    here); a bound of 90% keeps this from failing by chance, and catches intervals that mean nothing."""
    s1, st = ishigami_exact()
    inside = total = 0
    for seed in range(20):
        found = ishigami_indices(1024, seed)
        for name, exact in (("S1", s1), ("ST", st)):
            inside += int((np.abs(found[name] - exact) <= found[f"{name}_conf"]).sum())
            total += 3
    assert inside >= 0.9 * total, f"{inside} of {total}"


# ---------------------------------------------------------------- a study's own path, on stand-in tables

#: Three scene parameters standing for Ishigami's x1, x2, x3 (each range maps linearly onto [-pi, pi]).
FACTORS = {"absorption_rate": (0.1, 0.9), "absorption_capacity": (2.0, 6.0), "initial_tilt": (-30.0, 30.0)}


def sensitivity_study(method="sobol", size=256, factors=None, metrics=("final_depth", "time_to_sink"), **more) -> Study:
    factors = FACTORS if factors is None else factors
    axes = {n: {"low": lo, "high": hi} | more.pop(n, {}) for n, (lo, hi) in factors.items()}
    sizes = {"sobol": "samples", "morris": "trajectories"}
    return Study.from_dict(dict(scene="thesis_fast", duration=60.0, seed=11, metrics=list(metrics), axes=axes,
                                sensitivity={"method": method, sizes[method]: size} | more), name="sa")


def standin_table(study: Study, values) -> pd.DataFrame:
    """A results table of ``study`` whose every metric is ``values(point)``: a run standing in for the simulator."""
    rows = []
    for run in study.runs():
        y = values(run.point)
        rows.append({"run_key": run.key, **run.point, "status": "ok", "error": None}
                    | {m: y for m in study.metrics} | ({"sank": True} if "time_to_sink" in study.metrics else {}))
    return make_table(rows, study.axis_names)


def ishigami_of(point) -> float:
    x = [-math.pi + 2 * math.pi * (point[n] - lo) / (hi - lo) for n, (lo, hi) in FACTORS.items()]
    return float(ishigami(np.array([x]))[0])


def test_study_indices_from_its_table_are_those_of_its_design():
    """The study's runs, keyed and stored in a table, give back the design's outputs in design order:
    the indices from the table equal those of ``analyze`` on the design directly (same numbers)."""
    study = sensitivity_study(size=256)
    assert len(study.runs()) == 256 * (3 + 2)
    result = sensitivity_indices(study, standin_table(study, ishigami_of))
    assert result.problems == {} and result.metrics == ["final_depth", "time_to_sink"]
    unit = study.design()
    x = -math.pi + 2 * math.pi * unit  # the factors' ranges are linear images of [-pi, pi]
    direct = analyze(study.sensitivity, study.axis_names, unit, ishigami(x), study.seed)
    table = result.indices[result.indices.metric == "final_depth"].set_index("parameter").loc[study.axis_names]
    for name, values in direct.items():
        np.testing.assert_allclose(table[name], values, rtol=1e-9, atol=1e-12)
    # ranked by ST: x1 (0.56), x2 (0.44), x3 (0.24)
    assert table["rank"].tolist() == [1, 2, 3]
    assert set(table["unit"]) == {"m"} and (table["runs"] == 1280).all() and (table["conf_level"] == 0.95).all()


def test_morris_on_a_linear_function_gives_its_exact_effects_on_log_and_linear_axes():
    """y = 5 u_rate - 2 u_tilt + 0 u_capacity, u the position in each axis's range (for the log axis: of
    the logarithm).  Every elementary effect (the change across the whole range) is exactly 5, -2, 0:
    mu* = 5, 2, 0, mu = 5, -2, 0, sigma = 0, to round-off of the logarithms (1e-9)."""
    study = sensitivity_study("morris", 8, absorption_rate={"log": True})
    lo, hi = FACTORS["absorption_rate"]
    tlo, thi = FACTORS["initial_tilt"]

    def linear(point):
        return (5 * math.log(point["absorption_rate"] / lo) / math.log(hi / lo)
                - 2 * (point["initial_tilt"] - tlo) / (thi - tlo))

    result = sensitivity_indices(study, standin_table(study, linear))
    table = result.indices[result.indices.metric == "final_depth"].set_index("parameter")
    np.testing.assert_allclose(table.loc[["absorption_rate", "initial_tilt", "absorption_capacity"], "mu_star"],
                               [5, 2, 0], atol=1e-9)
    np.testing.assert_allclose(table.loc[["absorption_rate", "initial_tilt", "absorption_capacity"], "mu"],
                               [5, -2, 0], atol=1e-9)
    np.testing.assert_allclose(table["sigma"], 0, atol=1e-9)
    assert table.loc["absorption_rate", "rank"] == 1 and table.loc["absorption_capacity", "rank"] == 3
    assert len(study.runs()) <= 8 * (3 + 1)  # coinciding points of the trajectories run once


def test_a_design_with_failed_missing_or_undefined_runs_gets_no_indices_and_names_them(tmp_path):
    study = sensitivity_study(size=8, metrics=("final_depth", "time_to_sink", "final_wet_mass"))
    table = standin_table(study, ishigami_of)
    runs = study.runs()
    table.loc[table.run_key == runs[0].key, ["status", "error", "final_depth", "time_to_sink"]] = \
        ["error", "BlowUpError: the cloth state exploded at t = 1.2 s\n(more)", math.nan, math.nan]
    table.loc[table.run_key == runs[1].key, "time_to_sink"] = math.nan  # ok, but never sank
    table = table[table.run_key != runs[2].key]  # not run yet
    result = sensitivity_indices(study, table)
    assert result.indices.empty and set(result.problems) == {"final_depth", "time_to_sink", "final_wet_mass"}
    depth = result.problems["final_depth"]
    assert depth.startswith("no indices: the sobol design needs a value from each of its 40 runs, and ")
    assert f"1 not run yet (run the same command to run them): run {runs[2].key} (absorption_rate=" in depth
    assert (f"1 failed (after fixing the cause, --retry-errors runs them again): run {runs[0].key} (" in depth
            and "): BlowUpError: the cloth state exploded at t = 1.2 s" in depth and "(more)" not in depth)
    sink = result.problems["time_to_sink"]
    assert (f"1 has no value (NaN: it did not sink within duration = 60 s: a longer duration, or bounds within "
            f"which every run sinks): run {runs[1].key}") in sink
    text = format_indices(result)
    assert "  time_to_sink (s)\n    no indices: the sobol design needs a value from each of its 40 runs, and" in text
    image = plot_sensitivity(result, tmp_path / "refused.png")  # a panel per metric, each saying why
    assert image.exists()


def test_indices_of_the_metrics_that_are_complete_are_kept_beside_refused_ones(tmp_path):
    study = sensitivity_study(size=8, metrics=("final_depth", "time_to_sink", "final_wet_mass"))
    table = standin_table(study, ishigami_of)
    table.loc[table.run_key == study.runs()[3].key, "time_to_sink"] = math.nan
    table["final_wet_mass"] = 0.25  # the same in every run
    result = sensitivity_indices(study, table)
    assert list(result.problems) == ["time_to_sink", "final_wet_mass"]
    assert result.problems["final_wet_mass"] == ("no indices: final_wet_mass is 0.25 in every run, there is no "
                                                 "variation to apportion")
    assert result.indices["metric"].unique().tolist() == ["final_depth"] and len(result.indices) == 3
    assert not result.indices.isna().any().any()  # no NaN written for the refused metric
    import matplotlib.image

    image = matplotlib.image.imread(plot_sensitivity(result, tmp_path / "sa.png"))
    assert image.shape[0] > 300 and image.shape[1] > 300


def test_raising_samples_keeps_the_runs_of_the_smaller_design():
    """Saltelli's design takes its base samples from the front of one scrambled Sobol' sequence: the
    runs of samples = 8 are the first runs of samples = 16 (so a rerun with more samples resumes)."""
    small, large = sensitivity_study(size=8).point_keys(), sensitivity_study(size=16).point_keys()
    assert large[:len(small)] == small and len(set(large)) == 16 * 5


def test_integer_and_choice_factors_are_split_evenly_and_morris_refuses_unordered_ones():
    study = sensitivity_study(size=64, factors={"absorption_rate": (0.1, 0.9), "nx": (5, 8)})
    nx = [p["nx"] for p in study.points()]
    counts = np.bincount(nx)[5:]
    assert len(counts) == 4 and counts.min() > 0.8 * len(nx) / 4  # each of 5, 6, 7, 8 about a quarter
    for kind in ({"random": "choice", "values": ["face", "stokes"]}, {"random": "normal", "mean": 1.0, "std": 0.1}):
        name = "drag_model" if kind["random"] == "choice" else "drag_normal"
        with pytest.raises(StudyError, match="has no ordered, bounded range for Morris' steps") as info:
            Study.from_dict(dict(scene="thesis_fast", axes={"absorption_rate": {"low": 0.1, "high": 0.9}, name: kind},
                                 sensitivity={"method": "morris"}), name="m")
        assert info.value.key == f"axes.{name}"


# ---------------------------------------------------------------- lhs and sobol sampling


def sampled(sampling, samples, seed=5, **axes) -> list[dict]:
    return Study.from_dict(dict(scene="thesis_fast", duration=5.0, sampling=sampling, samples=samples, seed=seed,
                                axes=axes), name="s").points()


def test_latin_hypercube_puts_one_point_in_each_stratum_of_each_axis():
    n = 16
    points = sampled("lhs", n, absorption_rate={"low": 0.1, "high": 10.0, "log": True},
                     initial_tilt={"low": -30.0, "high": 30.0}, drag_normal={"random": "normal", "mean": 1.2, "std": 0.2},
                     nx={"low": 5, "high": 8}, drag_model={"random": "choice", "values": ["face", "stokes"]})
    from scipy.stats import norm

    positions = {  # each axis's values back in [0, 1] (the inverse of its mapping)
        "absorption_rate": [math.log(p["absorption_rate"] / 0.1) / math.log(100.0) for p in points],
        "initial_tilt": [(p["initial_tilt"] + 30.0) / 60.0 for p in points],
        "drag_normal": norm.cdf([(p["drag_normal"] - 1.2) / 0.2 for p in points]),
    }
    for name, u in positions.items():
        assert sorted(np.floor(np.asarray(u) * n).astype(int)) == list(range(n)), name
    assert np.bincount([p["nx"] for p in points])[5:].tolist() == [4, 4, 4, 4]  # 16 strata over 4 values
    assert sorted(p["drag_model"] for p in points) == ["face"] * 8 + ["stokes"] * 8
    assert sampled("lhs", n, initial_tilt={"low": -30.0, "high": 30.0}) == \
        sampled("lhs", n, initial_tilt={"random": "uniform", "low": -30.0, "high": 30.0})  # bounds = uniform


def test_sobol_sampling_is_seeded_balanced_and_extends_its_prefix():
    axes = dict(absorption_rate={"low": 0.0, "high": 1.0}, initial_tilt={"low": 0.0, "high": 1.0})
    eight, sixteen = sampled("sobol", 8, **axes), sampled("sobol", 16, **axes)
    assert sixteen[:8] == eight and sampled("sobol", 8, **axes) == eight and sampled("sobol", 8, seed=6, **axes) != eight
    for name in axes:  # a scrambled Sobol' set of 2^m points has one point in each interval [k/2^m, (k+1)/2^m)
        assert sorted(np.floor(np.array([p[name] for p in sixteen]) * 16).astype(int)) == list(range(16))


def test_random_sampling_draws_as_before():
    """The default placement is today's: independent draws of ``numpy.random.default_rng(seed)``, axis
    by axis, so the run keys of existing tables stay valid."""
    points = sampled("random", 3, absorption_rate={"random": "uniform", "low": 0.1, "high": 0.5})
    rng = np.random.default_rng(5)
    assert [p["absorption_rate"] for p in points] == rng.uniform(0.1, 0.5, 3).tolist()


@pytest.mark.parametrize("data, key, match", [
    (dict(sampling="sobol", samples=12, axes={"absorption_rate": {"low": 0.1, "high": 1.0}}), "samples",
     "sampling = 'sobol' needs a power of 2 .* got 12: take 8 or 16"),
    (dict(sampling="lhs", axes={"absorption_rate": [0.1, 0.2]}), "sampling", "'lhs' places the points of sampled axes"),
    (dict(sampling="halton", samples=4, axes={"absorption_rate": {"low": 0.1, "high": 1.0}}), "sampling",
     "allowed: random, lhs, sobol"),
    (dict(samples=4, axes={"absorption_rate": {"low": 0.1}}), "axes.absorption_rate", "bounds need both low and high"),
    (dict(samples=4, axes={"absorption_rate": {"low": 0.0, "high": 1.0, "log": True}}), "axes.absorption_rate",
     "loguniform needs low > 0"),
    (dict(samples=4, axes={"nx": {"low": 5, "high": 9, "log": True}}), "axes.nx", "bounds of a whole-number parameter take no log"),
    (dict(samples=4, axes={"drag_model": {"low": 0, "high": 1}}), "axes.drag_model", "drag_model is a string parameter"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}, "initial_tilt": [0.0, 10.0]}, sensitivity={}),
     "axes.initial_tilt", "a sensitivity study's axes are its factors"),
    (dict(samples=4, axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={}), "samples",
     "the \\[sensitivity\\] design places the runs"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"method": "morris", "samples": 8}),
     "sensitivity.samples", "is for method = 'sobol'; method 'morris' takes trajectories"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"method": "fast"}), "sensitivity.method",
     "allowed: sobol, morris"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"samples": 48}), "sensitivity.samples",
     "must be a power of 2 .* got 48: take 32 or 64"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"method": "morris", "levels": 5}),
     "sensitivity.levels", "must be even"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"conf_level": 95}), "sensitivity.conf_level",
     "between 0 and 1"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"sample": 8}), "sensitivity.sample",
     "did you mean 'samples'"),
    (dict(metrics=["final_depth"], axes={"absorption_rate": {"low": 0.1, "high": 1.0}},
          sensitivity={"metrics": ["time_to_sink"]}), "sensitivity.metrics", "'time_to_sink' is not recorded; recorded: final_depth"),
    (dict(axes={"absorption_rate": {"low": 0.1, "high": 1.0}}, sensitivity={"samples": 1 << 17}), "sensitivity",
     "the sobol design of 1 factors has 3.93e[+]05; at most 100000 runs"),
])
def test_bad_sampling_and_sensitivity_settings_name_the_key(data, key, match):
    with pytest.raises(StudyError, match=match) as info:
        Study.from_dict(dict(scene="thesis_fast", duration=5.0) | data, name="t")
    assert info.value.key == key
