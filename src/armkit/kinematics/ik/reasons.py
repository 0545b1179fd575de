"""Why a solve failed: one vocabulary for inverse kinematics, Cartesian lines and planners.

Import the constants rather than spelling the words, so that a result's reason can be compared
with them anywhere (``result.reason == OUT_OF_REACH``).
"""

from __future__ import annotations

OK = "ok"
OUT_OF_REACH = "out of reach"
"""No configuration reaches the target: beyond the reach bound, or no closed-form branch."""
OUTSIDE_JOINT_LIMITS = "outside joint limits"
"""The target is reached only by configurations outside the joint limits (or a joint limit
stops a motion)."""
SINGULAR = "singular"
"""At a singularity: the task Jacobian lost rank, or a motion would jump across one."""
NOT_CONVERGED_PREFIX = "did not converge"

REASONS = (OK, OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, SINGULAR, NOT_CONVERGED_PREFIX)


def not_converged(iterations: int, starts: int) -> str:
    """The reason of a numeric solve that used up its budget:
    ``"did not converge in 20 iterations x 251 starts"``."""
    return f"{NOT_CONVERGED_PREFIX} in {iterations} iterations x {starts} starts"
