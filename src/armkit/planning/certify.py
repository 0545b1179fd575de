"""A timed motion certified against a scene: every state between start and end clear.

A planner's path is certified segment by segment; a motion along it (a spline, a retimed path)
leaves the straight segments, so it is certified again as a motion: sampled so densely that no
point of the arm moves more than half the checker's resolution between two samples, and every
sample's clearance (`CollisionChecker.clearance`) above a quarter of the resolution. Between two
samples every point of the arm stays within a quarter of a resolution of where it was at one of
them, which the clearance covers (for two parts of the arm, half their gap: both move).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armkit.trajectory.bounds import peaks
from armkit.trajectory.piecewise import Trajectory

MAX_SAMPLES = 2_000_000
"""The most samples a certification takes; a motion that needs more is not certified."""
SPEED_MARGIN = 1.05        # on the peak joint speeds: the samples come a little closer
CLEARANCE = 0.25           # of the resolution: each sample's clearance (see the module notes)


@dataclass(frozen=True)
class Certificate:
    """Whether a motion is clear of the scene, and what the check did.

    Attributes
    ----------
    success : bool
        Every sample clear by a quarter of the resolution.
    reason : str
        "ok"; "in collision at t = ... s"; or "needs more than ... samples".
    samples : int
        States checked.
    first_collision : float
        Time (s) of the first sample in collision; NaN if none.
    """

    success: bool
    reason: str
    samples: int
    first_collision: float = math.nan


def certify(checker, motion: Trajectory) -> Certificate:
    """Certify a timed motion against a `CollisionChecker`'s scene (see the module notes).

    Parameters
    ----------
    checker : armkit.planning.CollisionChecker
        Its `weights` (m per unit of each joint: how far any point of the arm moves) and
        `resolution` (m) set the sampling; `clearance` checks the samples.
    motion : Trajectory

    Returns
    -------
    Certificate
    """
    # No point of the arm moves faster than the weighted sum of the peak joint speeds.
    speed = float(checker.weights @ peaks(motion, 1)) if motion.duration > 0 else 0.0
    if speed == 0:
        count = 1
    else:
        dt = 0.5 * checker.resolution / (speed * SPEED_MARGIN)
        count = max(math.ceil(motion.duration / dt) + 1, 2)
        if count > MAX_SAMPLES:
            return Certificate(False, f"needs more than {MAX_SAMPLES:,} samples", 0)
    t = np.linspace(motion.start, motion.end, count)
    valid = np.asarray(checker.clearance(motion.evaluate(t))) > CLEARANCE * checker.resolution
    if valid.all():
        return Certificate(True, "ok", count)
    first = float(t[np.argmin(valid)])
    return Certificate(False, f"in collision at t = {first:.4g} s", count, first)
