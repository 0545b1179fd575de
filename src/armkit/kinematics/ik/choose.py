"""Choosing among solutions: the criteria for the best (the closed-form kernels fold angles into
the limits and check them: `armkit.kinematics.ik.analytic`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from armkit.jit import kernel
from armkit.model.robot import Robot

CRITERIA = {
    "nearest": "weighted distance to the current configuration (sum of w_i dq_i^2)",
    "least_travel": "longest joint travel time at the velocity limits (max |dq_i| / v_i)",
    "manipulability": "largest manipulability (Yoshikawa), farthest from singularities",
    "limits": "farthest from the joint limits (smallest margin over range, largest)",
}


def scores(robot: Robot, q: NDArray, q_ref: NDArray, criterion: str,
           weights: NDArray | None) -> NDArray:
    """Cost of each candidate (..., K, n) under a criterion of `CRITERIA` (checked by the
    caller), lower is better; (..., K)."""
    dq = q - q_ref[..., None, :]
    if criterion == "nearest":
        w = np.ones(robot.n) if weights is None else weights
        return np.sum(w * dq**2, axis=-1)
    if criterion == "least_travel":
        v = np.where(np.isfinite(robot.chain.velocity_limits), robot.chain.velocity_limits, 1.0)
        return np.max(np.abs(dq) / v, axis=-1)
    if criterion == "manipulability":
        from armkit.kinematics.jacobian import manipulability
        return -manipulability(robot, np.nan_to_num(q))
    # A joint without finite limits has all the margin there is.
    finite = np.isfinite(robot.lower) & np.isfinite(robot.upper)
    span = np.where(finite, robot.upper - robot.lower, 1.0)
    margin = np.where(finite, np.minimum(q - robot.lower, robot.upper - q) / span, np.inf)
    return -np.min(margin, axis=-1)


CRITERION_CODES = {"nearest": 0, "least_travel": 1, "manipulability": 2, "limits": 3}
USABLE, REACHED_OUTSIDE, NOT_REACHED = 0, 1, 2
"""What `pick` found for a target: a usable branch (reached, within the limits), one that
reaches the target outside the limits only, or none that reaches it (the closest real one, or
none at all)."""


@kernel(cache=True, nogil=True)
def pick(C, errors, flags, q_ref, code, weights, bounds, given, out):
    """The best branch of each target, as `scores` and the solver's rule choose it: the best
    usable one, else the best that reaches the target, else the real one closest to it.

    C (N, K, n) branches, errors (N, K, 2), flags (N, K, 4) (`analytic.candidates`); q_ref
    (N, n); code: `CRITERION_CODES`; weights (n,) of "nearest"; bounds (3, n): velocity limits
    (1 where none) of "least_travel", lower and upper limits of "limits"; given (N, K): the
    scores of "manipulability" (computed by the caller). out (N, 2) int: the branch, and
    `USABLE`, `REACHED_OUTSIDE` or `NOT_REACHED`; a target without a real branch gets branch
    0 (ties go to the first branch, as NumPy's argmin).
    """
    N, K, n = C.shape
    for t in range(N):
        best_usable, best_reached, best_close = -1, -1, -1
        s_usable, s_reached, s_close = math.inf, math.inf, math.inf
        for b in range(K):
            if code == 2:
                score = given[t, b]
            else:
                score = math.inf if code == 3 else 0.0      # "limits": the smallest margin
                for j in range(n):
                    dq = C[t, b, j] - q_ref[t, j]
                    if code == 0:
                        score += weights[j] * dq * dq
                    elif code == 1:
                        score = max(score, abs(dq) / bounds[0, j])
                    elif math.isfinite(bounds[1, j]) and math.isfinite(bounds[2, j]):
                        low, high = bounds[1, j], bounds[2, j]
                        score = min(score, min(C[t, b, j] - low, high - C[t, b, j])
                                    / (high - low))
                if code == 3:
                    score = -score
            reached, inside = flags[t, b, 1], flags[t, b, 2]
            if reached and inside and (best_usable < 0 or score < s_usable):
                best_usable, s_usable = b, score
            if reached and (best_reached < 0 or score < s_reached):
                best_reached, s_reached = b, score
            close = errors[t, b, 0] + errors[t, b, 1]
            if flags[t, b, 0] and (best_close < 0 or close < s_close):
                best_close, s_close = b, close
        if best_usable >= 0:
            out[t, 0], out[t, 1] = best_usable, USABLE
        elif best_reached >= 0:
            out[t, 0], out[t, 1] = best_reached, REACHED_OUTSIDE
        else:
            out[t, 0], out[t, 1] = max(best_close, 0), NOT_REACHED
