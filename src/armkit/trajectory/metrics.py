"""Numbers that describe a joint trajectory: peaks, jumps at knots, integrated squared jerk,
and the comparison of spline patterns the tool-changer paper makes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.trajectory.piecewise import DERIVATIVES, Samples, Trajectory, falling_factorial, peak

@dataclass(frozen=True)
class Stats:
    """Peaks and effort of one trajectory, per joint; SI (rad or m per joint, s).

    Attributes
    ----------
    label : str
    duration : float
        s.
    peak_velocity, peak_acceleration, peak_jerk : ndarray, shape (n,)
        Largest absolute value over the motion (rad/s, rad/s^2, rad/s^3).
    squared_jerk : ndarray, shape (n,)
        ``int q'''(t)^2 dt`` over the motion, rad^2/s^5 (m^2/s^5).
        Steps of acceleration (at the ends of a 3-3-3 spline, at a trapezoid's switches) are
        impulses of jerk that this integral leaves out; `knot_jumps` shows them.
    """

    label: str
    duration: float
    peak_velocity: NDArray
    peak_acceleration: NDArray
    peak_jerk: NDArray
    squared_jerk: NDArray


@dataclass(frozen=True)
class Jumps:
    """How much position and each derivative step at each break of a trajectory.

    Attributes
    ----------
    t : ndarray, shape (k,)
        The breaks (s), start and end included.
    jump : ndarray, shape (k, 4, n)
        Right limit minus left limit of position, velocity, acceleration, jerk. The arm is
        taken at rest before the start and after the end, so at the start the jump is the
        motion's initial velocity, acceleration and jerk, and at the end minus its final ones
        (3-3-3's acceleration steps show there).
    """

    t: NDArray
    jump: NDArray


def peaks(samples: Samples) -> tuple[NDArray, NDArray, NDArray]:
    """Largest |velocity|, |acceleration|, |jerk| per joint (n,) over sampled motion."""
    axes = tuple(range(samples.q.ndim - 1))
    return tuple(np.max(np.abs(x), axis=axes) for x in (samples.qd, samples.qdd, samples.qddd))


def squared_jerk(tr: Trajectory) -> NDArray:
    """``int q'''(t)^2 dt`` per joint (n,), exact (rad^2/s^5 or m^2/s^5).

    With the jerk on a piece of length h written sum_k d_k tau^k,
    ``int_0^h (sum_k d_k tau^k)^2 dtau = sum_kl d_k d_l h^(k+l+1) / (k+l+1)``.
    """
    c = tr.coefficients
    if c.shape[1] < 4:
        return np.zeros(tr.n)
    k = np.arange(c.shape[1] - 3)
    d = c[:, 3:] * np.array([falling_factorial(i + 3, 3) for i in k])[None, :, None]     # (m, L, n)
    power = k[:, None] + k[None, :] + 1
    h = np.diff(tr.breaks)
    W = h[:, None, None] ** power / power                                        # (m, L, L)
    return np.einsum("mkn,mkl,mln->n", d, W, d)


def knot_jumps(tr: Trajectory) -> Jumps:
    """Steps of position, velocity, acceleration and jerk at every break (see `Jumps`)."""
    h = np.diff(tr.breaks)
    m, count = h.shape[0], len(DERIVATIVES)
    right = np.stack([tr.piece_values(np.zeros((m, 1)), r)[:, 0] for r in range(count)], 1)
    left = np.stack([tr.piece_values(h[:, None], r)[:, 0] for r in range(count)], 1)
    rest = np.zeros((1, count, tr.n))
    before = np.concatenate([rest, left])             # (m + 1, 4, n) left limits
    after = np.concatenate([right, rest])             # right limits
    before[0, 0] = right[0, 0]                        # position: continuous at both ends
    after[-1, 0] = left[-1, 0]
    return Jumps(tr.breaks.copy(), after - before)


def stats(tr: Trajectory) -> Stats:
    """`Stats` of a trajectory: peaks found on every piece (`piecewise.peak`: samples, ends
    included so steps at breaks count, then Newton steps) and the exact integrated squared jerk.
    """
    v, a, j = (peak(tr, r) for r in (1, 2, 3))
    return Stats(tr.label, tr.duration, v, a, j, squared_jerk(tr))


def compare(trajectories: Mapping[str, Trajectory]) -> dict[str, Stats]:
    """`stats` of each trajectory, by name: the paper's comparison of 3-3-3, 4-5-5, 5-5-5.

    Example
    -------
    >>> from armkit.trajectory import patterns
    >>> points = np.deg2rad([[50.4], [43.2], [35], [27]])         # paper 4, joint 2
    >>> table = compare(patterns([0, 2, 4, 5], points))
    >>> sorted(table)
    ['3-3-3', '4-5-5', '5-5-5']
    >>> np.rad2deg(table["3-3-3"].peak_acceleration).round(2)       # deg/s^2
    array([29.03])
    """
    return {name: stats(tr) for name, tr in trajectories.items()}
