"""Trajectory case files: a point-to-point or via-point motion of one robot, in file units.

A case comes from a YAML file or from a command's options (options override the file); joint
values and limits are in the robot file's units (deg, mm, per second...). Via points (paper 4,
Table 1)::

    robot: tool_changer_6dof
    joints: [2, 3, 5]              # the columns of points: 1-based numbers or joint names
    times: [0, 2, 4, 5]            # s
    points: [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    patterns: [3-3-3, 4-5-5, 5-5-5]
    hold: [0, 0, 0, 0, 0, 0]       # optional: where the other joints stay (default 0)

Point to point::

    robot: inspection_6dof
    start: [0, 0, 0, 0, 0, 0]
    goal: [30, -45, 60, 0, 90, 0]
    profiles: [quintic, jerk-limited]   # cubic | quintic | trapezoidal | jerk-limited
    duration: 10                        # s, for cubic and quintic (default: shortest in limits)
    jerk: 400                           # deg/s^3 (robot files carry no jerk limit)

``velocity``, ``acceleration`` and ``jerk`` (one value or one per joint) replace the robot
file's limits; ``sync: phase`` makes profiles straight lines in joint space.

`read_case` turns a case into trajectories (SI); `limit_excesses` lists where they go beyond
the velocity and acceleration limits. Positions outside the joint limits are bad input.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator, model_validator

from armkit import trajectory as tj
from armkit.errors import ArmkitError, InputError, ModelFileError
from armkit.io.documents import Value, StrictModel, bounded, read_yaml, validated, whole
from armkit.model import Robot

Profile = Literal["cubic", "quintic", "trapezoidal", "jerk-limited"]
Limit = Value | list[Value] | None
# Ranges that make sense, in file units: beyond them the arithmetic overflows or underflows
# (1e308 s, a jerk of 1e-300) long before a motion could mean anything.
VALUE = 1e9             # joint values, file units
LIMIT = (1e-6, 1e9)     # velocity, acceleration, jerk limits, file units per s, s^2, s^3
TIME = 1e6              # s: knot times and durations, about eleven days


def _finite_values(name: str, values: Any, low: float, high: float) -> Any:
    """Every number in (nested lists of) `values` within [low, high]."""
    def flat(v):
        if isinstance(v, (list, tuple)):
            for item in v:
                yield from flat(item)
        elif v is not None:
            yield float(v)

    for x in flat(values):
        if not low <= x <= high:
            raise ValueError(f"expected numbers from {low:g} to {high:g}, found {x:g}")
    return values


class CaseFile(StrictModel):
    """A trajectory case as its file (or the command's options) gives it, in file units."""

    robot: str = Field(max_length=4096)
    start: list[Value] | None = None
    goal: list[Value] | None = None
    profiles: list[Profile] = ["quintic"]
    duration: bounded(0.0, TIME, low_open=True) | None = None
    joints: list[whole(-10_000, 10_000) | Annotated[str, Field(max_length=200)]] | None = None
    times: list[Value] | None = None
    points: list[list[Value]] | None = None
    hold: list[Value] | None = None
    patterns: list[Annotated[str, Field(max_length=200)] | whole(0, 10**9)] | None = None
    velocity: Limit = None
    acceleration: Limit = None
    jerk: Limit = None
    sync: Literal["time", "phase"] = "time"

    @field_validator("start", "goal", "points", "hold")
    @classmethod
    def _values(cls, v):
        return _finite_values("", v, -VALUE, VALUE)

    @field_validator("times")
    @classmethod
    def _times(cls, v):
        return _finite_values("", v, -TIME, TIME)

    @field_validator("velocity", "acceleration", "jerk")
    @classmethod
    def _limits(cls, v):
        return _finite_values("", v, *LIMIT)

    @model_validator(mode="after")
    def _one_kind(self):
        p2p, via = self.start is not None or self.goal is not None, self.times is not None
        if p2p == via or (p2p and (self.start is None or self.goal is None)) or \
                (via and self.points is None):
            raise ValueError("expected start and goal (point to point) or times and points "
                             "(via points), found " + (
                                 "both" if p2p and via else "an incomplete case"))
        return self


@dataclass(frozen=True, eq=False)
class TrajectoryCase:
    """A case's trajectories (SI), the joints that move and the limits they answer to.

    Attributes
    ----------
    robot : Robot
    trajectories : dict of str to Trajectory
        By label: the profile ("quintic", ...) or the pattern ("4-5-5", ...).
    moving : list of int
        The joints that move (0-based), or those the via points give.
    via : bool
        Via points (a spline through knots) rather than point to point.
    velocity_limits, acceleration_limits : ndarray, shape (n,)
        rad/s or m/s, rad/s^2 or m/s^2: the case's or else the robot file's.
    source : str
        The case file, or "" for a case given by options.
    """

    robot: Robot
    trajectories: dict
    moving: list
    via: bool
    velocity_limits: NDArray
    acceleration_limits: NDArray
    source: str


@dataclass(frozen=True)
class LimitExcess:
    """A trajectory that goes beyond a joint's velocity or acceleration limit.

    Attributes
    ----------
    trajectory : str
        Its label.
    joint : int
        0-based joint index.
    quantity : {"velocity", "acceleration"}
    peak, limit : float
        Largest absolute value reached and the limit, SI (rad/s, m/s, rad/s^2, m/s^2).
    time : float
        When the peak is reached (s, from the trajectory's start).
    """

    trajectory: str
    joint: int
    quantity: str
    peak: float
    limit: float
    time: float

    @property
    def ratio(self) -> float:
        """peak / limit: how many times the limit."""
        return self.peak / self.limit


def _case_document(source: str) -> dict | None:
    """The document of a case file, or None if the source names a robot (a built-in name or
    a robot file: a YAML file without a ``robot`` field)."""
    if not source.endswith((".yaml", ".yml")):
        return None
    try:
        is_file = Path(source).is_file()
    except (OSError, ValueError):
        is_file = False
    if not is_file:
        raise InputError(f"case: expected a case file or a robot, found no file "
                         f"{source if len(source) <= 60 else source[:57] + '...'}")
    document = read_yaml(source)
    return document if isinstance(document, dict) and "robot" in document else None


def load_case(source: str, overrides: dict[str, Any] | None = None) -> tuple[CaseFile, bool]:
    """The case from a file (or a robot) with `overrides` (file units) laid over it, and
    whether it came from a case file.

    Raises
    ------
    ModelFileError
        A field of the file (or an option) that is missing, unknown or out of range.
    """
    document = _case_document(source)
    from_file = document is not None
    where = source if from_file else (
        f"{source} (read as a robot: it has no robot field) and the command line"
        if source.endswith((".yaml", ".yml")) else "command line")
    document = {**document} if from_file else {"robot": source}
    document.update({k: v for k, v in (overrides or {}).items() if v is not None})
    return validated(where, document, CaseFile), from_file


def read_case(source: str, overrides: dict[str, Any] | None = None) -> TrajectoryCase:
    """A case file (or a robot with the case in `overrides`) as trajectories, SI.

    Parameters
    ----------
    source : str
        A case file (.yaml with a ``robot`` field), or a robot (built-in name or robot file).
    overrides : dict or None
        Fields of `CaseFile` (file units) that replace the file's.

    Returns
    -------
    TrajectoryCase

    Raises
    ------
    InputError, ModelFileError
        A bad field, a start equal to the goal, or a position outside the joint limits.
    """
    case, from_file = load_case(source, overrides)
    try:
        robot = _robot(case.robot, source if from_file else "")
        trajectories, moving, (vmax, amax) = build(case, robot)
    except ModelFileError:
        raise
    except InputError as err:
        if not from_file:
            raise
        # The file's mistake, named with the file: "velocity: expected ..., found 0".
        field, _, rest = str(err).partition(": ")
        expected, _, found = rest.removeprefix("expected ").partition(", found ")
        raise ModelFileError(source, field, expected, found) from None
    return TrajectoryCase(robot, trajectories, moving, case.times is not None, vmax, amax,
                          source if from_file else "")


def _robot(name: str, source: str) -> Robot:
    from armkit.io.robot_files import robot as named_robot

    try:
        return named_robot(name)
    except ArmkitError:
        raise
    except (OSError, ValueError) as err:
        shown = name if len(name) <= 60 else name[:57] + "..."
        if source:
            raise ModelFileError(source, "robot", "a built-in name or a robot file",
                                 f"{shown!r} ({getattr(err, 'strerror', None) or err})") \
                from None
        raise InputError(f"robot: expected a built-in name or a robot file, found {shown!r} "
                         f"({getattr(err, 'strerror', None) or err})") from None


def _per_joint(robot: Robot, name: str, value: Limit, default: np.ndarray) -> np.ndarray:
    """A limit per joint in SI from file units (one value for all, or one per joint)."""
    if value is None:
        return default
    v = np.asarray(value, dtype=float).ravel()
    if v.shape not in ((1,), (robot.n,)):
        raise InputError(f"{name}: expected one value or {robot.n} (one per joint), "
                         f"found {v.size}")
    if not (v > 0).all():
        raise InputError(f"{name}: expected positive limits, found {v.tolist()}")
    return robot.q_to_si(np.broadcast_to(v, (robot.n,)))


def _joint_index(robot: Robot, joint: int | str) -> int:
    if isinstance(joint, int) and 1 <= joint <= robot.n:
        return joint - 1
    if isinstance(joint, str) and joint in robot.joint_names:
        return robot.joint_names.index(joint)
    if isinstance(joint, str) and joint.isdigit():
        return _joint_index(robot, int(joint))
    raise InputError(f"joints: expected joint numbers 1..{robot.n} or names "
                     f"({', '.join(robot.joint_names)}), found {joint!r}")


def _within_limits(robot: Robot, name: str, q: NDArray) -> None:
    """Refuse joint positions (SI, (..., n)) outside the limits, named in file units."""
    q = np.atleast_2d(q)
    tol = 1e-12 * (1.0 + np.abs(robot.upper - robot.lower))
    bad = (q < robot.lower - tol) | (q > robot.upper + tol)
    if not bad.any():
        return
    row, j = np.argwhere(bad)[0]
    lo, hi, value = robot.q_from_si(np.stack([robot.lower, robot.upper, q[row]]))[:, j]
    where = f"{name}[{row}]" if len(q) > 1 else name
    raise InputError(f"{where}: expected joint {j + 1} ({robot.joint_names[j]}) within its "
                     f"limits {lo:g} .. {hi:g} {robot.joint_units[j]}, found {value:g}")


def build(case: CaseFile, robot: Robot) -> tuple[dict[str, tj.Trajectory], list[int],
                                                  tuple[NDArray, NDArray]]:
    """The case's trajectories by label (SI), the joints that move (0-based), and the
    velocity and acceleration limits they answer to (SI, (n,) each)."""
    vmax = _per_joint(robot, "velocity", case.velocity, robot.chain.velocity_limits)
    amax = _per_joint(robot, "acceleration", case.acceleration, robot.chain.acceleration_limits)
    jmax = _per_joint(robot, "jerk", case.jerk, np.full(robot.n, np.inf))
    if case.times is None:
        q0, qf = (robot.q_to_si(_joint_vector(robot, name, v))
                  for name, v in (("start", case.start), ("goal", case.goal)))
        _within_limits(robot, "start", q0)
        _within_limits(robot, "goal", qf)
        if np.array_equal(q0, qf):
            raise InputError("goal: expected a configuration other than the start, found the "
                             "start itself: there is no motion to plan")
        out = {}
        for name in dict.fromkeys(case.profiles):
            if name in ("cubic", "quintic"):
                law = tj.cubic if name == "cubic" else tj.quintic
                out[name] = law(q0, qf, case.duration, vmax=vmax, amax=amax, jmax=jmax)
            elif name == "trapezoidal":
                out[name] = tj.trapezoidal(q0, qf, vmax, amax, sync=case.sync)
            else:
                if not np.isfinite(jmax).all():
                    raise InputError("jerk: expected a jerk limit for jerk-limited profiles "
                                     "(robot files carry none), found none")
                out[name] = tj.jerk_limited(q0, qf, vmax, amax, jmax, sync=case.sync)
        return out, [j for j in range(robot.n) if q0[j] != qf[j]], (vmax, amax)
    joints = [_joint_index(robot, j) for j in (case.joints or range(1, robot.n + 1))]
    if any(len(p) != len(joints) for p in case.points):
        raise InputError(f"points: expected rows of {len(joints)} values (one per joint in "
                         f"joints), found rows of {[len(p) for p in case.points]}")
    points = np.asarray(case.points, dtype=float)
    hold = (robot.q_to_si(_joint_vector(robot, "hold", case.hold)) if case.hold is not None
            else np.clip(0.0, robot.lower, robot.upper))
    _within_limits(robot, "hold", hold)
    q = np.tile(hold, (len(points), 1))
    q[:, joints] = robot.q_to_si(_full(robot, joints, points))[:, joints]
    _within_limits(robot, "points", q)
    patterns = case.patterns or (list(tj.PAPER_PATTERNS) if len(points) == 4 else [3, 5])
    return tj.patterns(case.times, q, patterns), joints, (vmax, amax)


def _joint_vector(robot: Robot, name: str, values: list[float]) -> np.ndarray:
    if len(values) != robot.n:
        raise InputError(f"{name}: expected {robot.n} joint values for {robot.name}, "
                         f"found {len(values)}")
    return np.asarray(values, dtype=float)


def _full(robot: Robot, joints: list[int], points: np.ndarray) -> np.ndarray:
    """Points of some joints placed in rows of all joints (file units), so units convert."""
    full = np.zeros((len(points), robot.n))
    full[:, joints] = points
    return full


def limit_excesses(case: TrajectoryCase, samples_per_piece: int = 257) -> list[LimitExcess]:
    """Where the case's trajectories go beyond the velocity or acceleration limits.

    The peaks are `armkit.trajectory.stats`'s (exact to rounding); the time of each is that
    of the largest sample, `samples_per_piece` per piece with the knots included. A peak up
    to 1e-9 relative above its limit counts as within (rounding of profiles built to it).

    Returns
    -------
    list of LimitExcess
        One per trajectory, joint and quantity beyond its limit, in the trajectories' order.
    """
    out = []
    for label, tr in case.trajectories.items():
        s = tj.stats(tr)
        t = np.unique(np.concatenate([np.linspace(a, b, samples_per_piece)
                                      for a, b in zip(tr.knots[:-1], tr.knots[1:])]))
        sampled = tr.sample(t)
        for quantity, peak, values, limit in (
                ("velocity", s.peak_velocity, sampled.qd, case.velocity_limits),
                ("acceleration", s.peak_acceleration, sampled.qdd, case.acceleration_limits)):
            for j in np.flatnonzero(peak > limit * (1 + 1e-9)):
                at = float(t[np.argmax(np.abs(values[:, j]))] - tr.knots[0])
                out.append(LimitExcess(label, int(j), quantity, float(peak[j]),
                                       float(limit[j]), at))
    return out
