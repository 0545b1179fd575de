"""Circles fitted to points in a plane: an algebraic start (Kasa), geometric least squares,
robust passes, and the arc the kept points span."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError


@dataclass(frozen=True)
class Circle:
    """A circle fitted to points in a plane.

    Attributes
    ----------
    centre : ndarray, shape (2,)
    radius : float
    rms : float
        RMS of the radial residuals of the points kept, same unit as the points.
    used : ndarray, shape (N,), bool
        The points kept after the robust passes.
    coverage : float
        Angle of the arc the kept points span, rad (2 pi for a full circle).
    """

    centre: NDArray
    radius: float
    rms: float
    used: NDArray
    coverage: float


def _kasa(xy: NDArray) -> tuple[NDArray, float]:
    """Algebraic circle fit (Kasa): centre and radius by linear least squares."""
    mean = xy.mean(axis=0)
    q = xy - mean
    A = np.column_stack([2 * q, np.ones(len(q))])
    sol, *_ = np.linalg.lstsq(A, (q * q).sum(axis=1), rcond=None)
    centre = sol[:2]
    return centre + mean, float(np.sqrt(max(sol[2] + centre @ centre, 0.0)))


def _geometric(xy: NDArray, centre: NDArray, radius: float, known: bool,
               iterations: int = 20) -> tuple[NDArray, float]:
    """Gauss-Newton on the geometric residuals |p - c| - r (r fixed when `known`)."""
    c, r = centre.astype(float).copy(), float(radius)
    for _ in range(iterations):
        diff = xy - c
        dist = np.maximum(np.linalg.norm(diff, axis=1), 1e-12)
        res = dist - r
        J = -diff / dist[:, None]
        if not known:
            J = np.column_stack([J, -np.ones(len(xy))])
        step, *_ = np.linalg.lstsq(J, -res, rcond=None)
        c += step[:2]
        if not known:
            r += step[2]
        if np.abs(step).max() < 1e-10:
            break
    return c, r


def _coverage(angles: NDArray) -> float:
    """Span of the arc covered by `angles` (rad): 2 pi minus the largest gap between them."""
    if len(angles) < 2:
        return 0.0
    a = np.sort(np.mod(angles, 2 * np.pi))
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]]))
    return float(2 * np.pi - gaps.max())


def fit_circle(xy: ArrayLike, radius: float | None = None, *, passes: int = 2,
               cut: float = 3.0, start: ArrayLike | None = None,
               keep_within: float = 0.0) -> Circle:
    """Circle through 2-D points: algebraic start, geometric least squares, robust passes.

    Parameters
    ----------
    xy : array_like, shape (N, 2), N >= 3
    radius : float or None
        The known radius (same unit as xy), or None to fit it.
    passes : int
        Times points with a residual beyond `cut` robust standard deviations (1.4826 MAD, at
        least 1e-4 of the radius) are set aside and the fit redone.
    cut : float
    start : array_like, shape (2,), optional
        Where the iterations start from, instead of the algebraic fit's centre (on a short arc
        a known radius fits on either side of it).
    keep_within : float
        Points within this residual (same unit) are never set aside, however small the MAD.

    Returns
    -------
    Circle

    Raises
    ------
    InputError
        If xy is not (N, 2) finite with N >= 3, or radius is not positive.
    """
    p = np.asarray(xy, float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3 or not np.isfinite(p).all():
        raise InputError(f"xy: expected at least 3 finite points of shape (N, 2), found "
                         f"{p.shape}")
    known = radius is not None
    if known and not (np.isfinite(radius) and radius > 0):
        raise InputError(f"radius: expected a positive radius, found {radius}")
    centre, r = _kasa(p)
    if start is not None:
        centre = np.asarray(start, float)
        r = float(radius) if known else float(np.linalg.norm(p - centre, axis=1).mean())
    elif known:
        # Start from the algebraic centre moved so that the known radius fits the arc: on a
        # short arc the algebraic radius is off, the direction to the arc is not.
        mean = p.mean(axis=0)
        towards = centre - mean
        norm = np.linalg.norm(towards)
        if norm > 1e-12 and np.isfinite(r):
            spread = np.linalg.norm(p - mean, axis=1).mean()
            centre = mean + towards / norm * np.sqrt(max(radius**2 - spread**2, 0.0))
        r = float(radius)
    used = np.ones(len(p), bool)
    centre, r = _geometric(p, centre, r, known)
    for _ in range(passes):
        res = np.linalg.norm(p - centre, axis=1) - r
        mad = 1.4826 * np.median(np.abs(res[used] - np.median(res[used])))
        keep = np.abs(res) <= max(cut * max(mad, 1e-4 * abs(r)), keep_within)
        if keep.sum() < 3 or (keep == used).all():
            break
        used = keep
        centre, r = _geometric(p[used], centre, r, known)
    res = np.linalg.norm(p[used] - centre, axis=1) - r
    angles = np.arctan2(p[used, 1] - centre[1], p[used, 0] - centre[0])
    return Circle(centre, float(r), float(np.sqrt(np.mean(res * res))), used, _coverage(angles))
