"""Motions played one after another as one `Trajectory`."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from armkit.errors import InputError
from armkit.trajectory.piecewise import Trajectory


def concatenate(motions: Sequence[Trajectory], label: str = "") -> Trajectory:
    """One trajectory of motions played in turn, each starting when the one before ends.

    Parameters
    ----------
    motions : sequence of Trajectory
        Of the same joints; each should start where the one before ends (checked to 1e-9 in
        position: a jump would be a step no drive can follow).
    label : str
        Of the result; default the motions' labels joined by "+".

    Returns
    -------
    Trajectory
        From the first motion's start; its knots are every motion's knots, shifted to when
        that motion plays; pieces padded with zero coefficients to the highest degree.

    Raises
    ------
    InputError
        For no motions, different joint counts, or a motion that does not start where the one
        before ends.

    Example
    -------
    >>> from armkit.trajectory import quintic
    >>> both = concatenate([quintic([0.0], [1.0], 2.0), quintic([1.0], [0.0], 1.0)])
    >>> both.duration, both.evaluate([0.0, 2.0, 3.0])[:, 0].tolist()
    (3.0, [0.0, 1.0, 0.0])
    """
    motions = list(motions)
    if not motions:
        raise InputError("motions: expected at least one trajectory, found none")
    n = motions[0].n
    if any(m.n != n for m in motions):
        raise InputError(f"motions: expected trajectories of {n} joints each, found "
                         f"{[m.n for m in motions]}")
    for i, (a, b) in enumerate(zip(motions, motions[1:]), start=1):
        gap = np.abs(a.evaluate(a.end) - b.evaluate(b.start)).max()
        if not gap <= 1e-9:
            raise InputError(f"motions[{i}]: expected to start where motions[{i - 1}] ends, "
                             f"found a jump of {gap:.3g}")
    K = max(m.coefficients.shape[1] for m in motions)
    breaks, coefficients, knots = [np.array([motions[0].start])], [], []
    offset = motions[0].start
    for m in motions:
        if m.duration == 0:
            continue                    # a motion at rest takes no time
        c = np.zeros((m.coefficients.shape[0], K, n))
        c[:, :m.coefficients.shape[1]] = m.coefficients
        coefficients.append(c)
        breaks.append(m.breaks[1:] - m.start + offset)
        knots.append(m.knots - m.start + offset)
        offset += m.duration
    if not coefficients:
        return motions[0]
    breaks, coefficients = np.concatenate(breaks), np.concatenate(coefficients)
    # A piece too short to move its end past the rounding of the time it starts at (a motion
    # of 1e-50 s after 1 s) takes no time: it goes, and the continuity checked above holds.
    kept = np.r_[True, np.diff(breaks) > 0]
    return Trajectory(breaks[kept], coefficients[kept[1:]], np.unique(np.concatenate(knots)),
                      label or "+".join(m.label for m in motions))
