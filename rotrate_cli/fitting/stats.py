"""Small statistics the stages share: a weighted median and Student's t quantile."""

from __future__ import annotations

import numpy as np


def weighted_median(values: np.ndarray, weight: np.ndarray) -> float:
    """The value at which the cumulative weight, in order of value, reaches half the total."""
    order = np.argsort(values)
    cumulative = np.cumsum(weight[order])
    return float(values[order][np.searchsorted(cumulative, cumulative[-1] / 2)])


def student_t_975(dof: float) -> float:
    """The 97.5% quantile of Student's t with ``dof`` degrees of freedom (two-sided 95%).
    SciPy is imported here, when first needed: it weighs on every run's start otherwise."""
    from scipy.special import stdtrit

    return float(stdtrit(dof, 0.975))
