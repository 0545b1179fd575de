"""Accuracy report: commanded (theoretical) against measured tool positions.

The inspection-robot paper's experiment (SPEC.md, R3) is the model: five points, their
theoretical and measured positions, and the claim that every error is within 1 cm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.spatial import as_array


@dataclass(frozen=True)
class AccuracyReport:
    """Position errors of measured against commanded points, m.

    Attributes
    ----------
    commanded, measured : ndarray, shape (m, 3)
    errors : ndarray, shape (m, 3)
        ``measured - commanded`` per point.
    distances : ndarray, shape (m,)
        The length of each error.
    mean, max, rms : float
        Of the distances.
    bias : ndarray, shape (3,)
        Mean error per axis (x, y, z): a systematic offset.
    std : ndarray, shape (3,)
        Standard deviation of the error per axis (0 for a single point).
    tolerance : float or None
        The limit the points are held to, if one was given.
    within : bool or None
        Every distance within the tolerance (None without one).
    """

    commanded: NDArray
    measured: NDArray
    errors: NDArray
    distances: NDArray
    mean: float
    max: float
    rms: float
    bias: NDArray
    std: NDArray
    tolerance: float | None
    within: bool | None


def accuracy_report(commanded: ArrayLike, measured: ArrayLike,
             tolerance: float | None = None) -> AccuracyReport:
    """Per-point error and its statistics.

    Parameters
    ----------
    commanded, measured : array_like, shape (m, 3)
        Positions in one frame, m.
    tolerance : float, optional
        A limit on every point's error, m (e.g. 0.01 for "within 1 cm").

    Returns
    -------
    AccuracyReport

    Raises
    ------
    InputError
        Shapes that differ or are not (m, 3), no points, NaN or inf, a non-positive tolerance.

    Example
    -------
    >>> accuracy_report([[0.2, 0.3, 0.5]], [[0.202, 0.296, 0.503]]).max
    0.00538...
    """
    c = as_array(commanded, "commanded", (3,))
    m = as_array(measured, "measured", (3,))
    if c.ndim != 2 or len(c) == 0:
        raise InputError(f"commanded: expected shape (m, 3) with m >= 1, found {c.shape}")
    if m.shape != c.shape:
        raise InputError(f"measured: expected shape {c.shape} (one per commanded point), "
                         f"found {m.shape}")
    if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
        raise InputError(f"tolerance: expected a positive length, found {tolerance}")
    e = m - c
    d = np.linalg.norm(e, axis=-1)
    within = None if tolerance is None else bool(np.all(d <= tolerance))
    return AccuracyReport(c, m, e, d, float(d.mean()), float(d.max()),
                          float(np.sqrt(np.mean(d ** 2))), e.mean(axis=0),
                          e.std(axis=0, ddof=1) if len(e) > 1 else np.zeros(3),
                          None if tolerance is None else float(tolerance), within)
