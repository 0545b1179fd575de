"""Joint trajectories (SPEC.md section 4), all returned as one piecewise-polynomial type.

- `cubic`, `quintic`: point to point over one duration (the quintic is the 10-15-6 law);
- `trapezoidal`, `jerk_limited`: point to point under velocity, acceleration (and jerk) limits,
  all joints synchronised; `*_profile` for batches of problems;
- `spline`, `patterns`: through via points with a degree per segment (3-3-3, 4-5-5, 5-5-5...);
- `retime`: the time-optimal motion along a path within velocity and acceleration limits;
- `stats`, `compare`, `knot_jumps`, `squared_jerk`: peaks, steps at knots, effort;
- `tool_motion`: the tool's path, velocity and acceleration along a joint trajectory;
- `cartesian_line`: straight-line tool motion through inverse kinematics, stopping with its
  reason where the arm cannot follow.

Every builder returns a `Trajectory` (breaks and coefficients, SI); `Trajectory.sample(t)` gives
`Samples` (q, qd, qdd, qddd), the form the metrics, the tool motion and the figures read.
"""

from armkit.trajectory.cartesian import CartesianPath, cartesian_line
from armkit.trajectory.metrics import (Jumps, Stats, compare, knot_jumps, peaks, squared_jerk,
                                       stats)
from armkit.trajectory.piecewise import Samples, Trajectory
from armkit.trajectory.polynomial import cubic, quintic
from armkit.trajectory.profiles import (Profile, jerk_limited, jerk_limited_profile,
                                        profile_trajectory, trapezoidal, trapezoidal_profile)
from armkit.trajectory.retime import retime, waypoint_path
from armkit.trajectory.spline import PAPER_PATTERNS, patterns, spline
from armkit.trajectory.tool import ToolMotion, tool_motion

__all__ = ["CartesianPath", "cartesian_line", "Trajectory", "Samples", "cubic", "quintic", "trapezoidal", "jerk_limited",
           "trapezoidal_profile", "jerk_limited_profile", "profile_trajectory", "Profile",
           "spline", "patterns", "PAPER_PATTERNS", "retime", "waypoint_path", "stats", "compare",
           "knot_jumps", "squared_jerk", "peaks", "Stats", "Jumps", "tool_motion", "ToolMotion"]
