"""Uncertainty of fitted parameters from the Jacobian at the optimum (linearised least squares).

With residuals r_i = (model_i - data_i) / sigma_i and their Jacobian J (per unit of each parameter),
the covariance of the estimates is (J^T J)^-1; where sigma is not given, each output's sigma is
estimated from its residuals first (``estimate_sigma``, the fit repeated with the estimates as
weights until they settle), which for one output is the textbook s^2 (J^T J)^-1 with
s^2 = RSS / (N - p).  The 95 % intervals use the normal quantile when every
sigma was given and Student's t with N - p degrees of freedom when one was estimated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

#: A parameter is flat when its Jacobian column (per relative change of the parameter) is below
#: this fraction of the largest one: the data then hardly change with it.
FLAT = 1e-3
#: Correlation beyond which two parameters are reported as not separately identifiable.
CORRELATED = 0.95
#: A parameter whose standard error exceeds this fraction of its magnitude is poorly determined.
VAGUE = 0.5
#: chi^2 probability below which data of given sigma do not fit: the sigmas are too small or the model misses something.
CHI2_P = 1e-3


def leverage(jacobian: np.ndarray) -> np.ndarray:
    """The diagonal of the hat matrix J (J^T J)^-1 J^T: how much of the fit each value takes up (they
    sum to the number of parameters); NaN if J^T J is singular."""
    try:
        inverse = np.linalg.inv(jacobian.T @ jacobian)
    except np.linalg.LinAlgError:
        return np.full(jacobian.shape[0], np.nan)
    return np.einsum("ij,jk,ik->i", jacobian, inverse, jacobian)


def estimate_sigma(residuals: dict[str, np.ndarray], leverages: dict[str, np.ndarray]) -> dict[str, float]:
    """Each output's noise (its unit) from its unweighted residuals: sqrt(RSS_k / (n_k - h_k)), with
    h_k the sum of the output's leverages (the degrees of freedom the fit spent on it; shared in
    proportion to the values when the leverages are not known)."""
    total = sum(r.size for r in residuals.values())
    spent = sum(float(np.sum(h)) for h in leverages.values())
    out = {}
    for name, r in residuals.items():
        h = float(np.sum(leverages[name]))
        if not math.isfinite(h):
            h = r.size * spent / total if math.isfinite(spent) else r.size * len(leverages) / total
        dof = r.size - h
        out[name] = math.sqrt(float(r @ r) / dof) if dof > 0 else math.nan
    return out


@dataclass
class Uncertainty:
    covariance: np.ndarray
    standard_error: np.ndarray
    interval: np.ndarray  # (p, 2)
    correlation: np.ndarray
    quantile: float
    dof: int | None  # Student t's degrees of freedom; None: normal (every sigma given)
    warnings: list[str] = field(default_factory=list)


def uncertainty(jacobian: np.ndarray, estimate: np.ndarray, names: list[str], scales: np.ndarray,
                dof: int | None, level: float = 0.95) -> Uncertainty:
    """Covariance, standard errors, ``level`` intervals and correlations of ``estimate`` from the
    weighted ``jacobian`` (rows: residuals, columns: parameters, per unit of each), with warnings
    for parameters the data do not identify.  ``scales``: each parameter's size (for 'flat')."""
    p = len(names)
    warnings = []
    sensitivity = np.linalg.norm(jacobian, axis=0) * scales  # residual change per 100 % change
    largest = sensitivity.max() if p else 0.0
    for j in range(p):
        if not sensitivity[j] > FLAT * largest or sensitivity[j] == 0.0:
            warnings.append(f"{names[j]} is not identifiable: the data hardly change with it (a 1 % change moves "
                            f"the weighted residuals by {0.01 * sensitivity[j]:.2g}, against "
                            f"{0.01 * largest:.2g} for the most sensitive parameter)")
    information = jacobian.T @ jacobian
    singular = np.linalg.matrix_rank(information * np.outer(scales, scales)) < p
    if singular:
        covariance = np.full((p, p), np.inf)
        warnings.append("the parameters are not identifiable together: the Jacobian's columns are linearly "
                        "dependent, so no standard errors exist (fix some of them, or add data that separates them)")
    else:
        covariance = np.linalg.inv(information)
    se = np.sqrt(np.clip(np.diag(covariance), 0.0, np.inf))
    quantile = float(stats.norm.ppf(0.5 + level / 2) if dof is None else stats.t.ppf(0.5 + level / 2, dof))
    interval = np.column_stack([estimate - quantile * se, estimate + quantile * se])
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = covariance / np.outer(se, se)
    if not singular:
        np.fill_diagonal(correlation, 1.0)
        for i in range(p):
            for j in range(i + 1, p):
                if abs(correlation[i, j]) > CORRELATED:
                    widened = 1.0 / math.sqrt(max(1.0 - correlation[i, j] ** 2, 1e-300))
                    warnings.append(f"{names[i]} and {names[j]} are not separately identifiable: correlation "
                                    f"{correlation[i, j]:+.3f}; the data fix mainly a combination of them, and "
                                    f"each one's standard error is {widened:.3g}x what it would be with the other "
                                    f"known: measure one of them and fit the other, or add data that separates "
                                    f"them (another output, or times where they act differently)")
        for j in range(p):
            size = abs(estimate[j]) if estimate[j] != 0 else scales[j]
            if se[j] > VAGUE * size:
                warnings.append(f"{names[j]} is poorly determined: its standard error {se[j]:.3g} is "
                                f"{se[j] / size:.0%} of its value")
    return Uncertainty(covariance, se, interval, correlation, quantile, dof, warnings)


def chi2_check(chi2: float, dof: int) -> tuple[float, str | None]:
    """(probability of a chi^2 at least this large, a warning when it is below CHI2_P)."""
    if dof <= 0:
        return math.nan, None
    prob = float(stats.chi2.sf(chi2, dof))
    if prob < CHI2_P:
        return prob, (f"the fit does not match the data within their sigma: chi^2 = {chi2:.4g} for {dof} degrees "
                      f"of freedom (probability {prob:.2g}): the given sigma are too small, or the scene's fixed "
                      f"parameters do not describe the cloth; the intervals are then too narrow")
    return prob, None
