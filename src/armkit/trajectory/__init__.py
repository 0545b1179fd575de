"""Joint trajectories (SPEC.md section 4), all returned as one piecewise-polynomial type.

- `cubic`, `quintic`: point to point over one duration (the quintic is the 10-15-6 law);
- `trapezoidal`, `jerk_limited`: point to point under velocity, acceleration (and jerk) limits,
  all joints synchronised; `*_profile` for batches of problems;
- `spline`, `patterns`: through via points with a degree per segment (3-3-3, 4-5-5, 5-5-5...);
- `retime`: the time-optimal motion along a path within velocity and acceleration limits;
- `retime_jerk`: a motion along a path within velocity, acceleration and jerk limits, its
  acceleration continuous (no steps);
- `stats`, `compare`, `knot_jumps`, `squared_jerk`: peaks, steps at knots, effort;
- `tool_motion`: the tool's path, velocity and acceleration along a joint trajectory;
- `cartesian_line`: straight-line tool motion through inverse kinematics, stopping with its
  reason where the arm cannot follow.

Every builder returns a `Trajectory` (breaks and coefficients, SI); `Trajectory.sample(t)` gives
`Samples` (q, qd, qdd, qddd), the form the metrics, the tool motion and the figures read.

The names are loaded on first use (PEP 562): building a spline does not import the inverse
kinematics that `cartesian_line` needs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.trajectory.cartesian import CartesianPath, cartesian_line
    from armkit.trajectory.metrics import (Jumps, Stats, compare, knot_jumps, peaks,
                                           squared_jerk, stats)
    from armkit.trajectory.piecewise import Samples, Trajectory
    from armkit.trajectory.polynomial import cubic, quintic
    from armkit.trajectory.profiles import (Profile, jerk_limited, jerk_limited_profile,
                                            profile_trajectory, trapezoidal,
                                            trapezoidal_profile)
    from armkit.trajectory.jerk_retiming import retime_jerk
    from armkit.trajectory.retiming import RetimeResult, retime, waypoint_path
    from armkit.trajectory.splines import PAPER_PATTERNS, patterns, spline
    from armkit.trajectory.tool import ToolMotion, tool_motion


__getattr__, __dir__, __all__ = lazy_names(__name__)




