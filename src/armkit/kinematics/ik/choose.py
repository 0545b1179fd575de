"""Choosing among solutions: the criteria for the best (the closed-form kernels fold angles into
the limits and check them: `armkit.kinematics.ik.analytic`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

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
