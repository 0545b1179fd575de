"""`plan`: from a start to a goal (configurations or a pose) without collision, as a result.

Order of work: the start checked, then the goals (a pose becomes every collision-free IK
solution), the direct start-goal edge tried, then the planner; its path shortcut, resampled to
N waypoints if asked, and checked again (every waypoint and every edge between them) before
it is returned. The settings travel as one record, `PlanSettings` (keywords of `plan` build
it). The time limit holds for the whole call: it starts when `plan` is called, and the
planner's loop, the shortcuts and the final check all read it (inside the compiled loops too),
so a call returns within about the limit whichever tier its kernels run in. An unsolvable
problem, a time limit reached, a path that fails its final check: each is a `PlanResult` with
its reason, never an exception.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model.robot import Robot, joint_array
from armkit.planning.clock import left, timer
from armkit.planning.collision import CollisionChecker
from armkit.planning.compiled import plan_compiled
from armkit.planning.planners import planner_named
from armkit.planning.rrt import ValidityFunction
from armkit.planning.scene import Scene
from armkit.planning.smooth import resample, resample_keeping_vertices, shortcut
from armkit.spatial import as_transform

JOINT_STEP = 0.01       # rad (or m): a validity function's edges are checked this finely


@dataclass(frozen=True)
class PlanSettings:
    """How `plan` works, in one record (ruckig's input style); `plan`'s keywords build one.

    Parameters
    ----------
    planner : {"rrtconnect", "rrt", "rrtstar"}
    seed : int or None
        Same seed, same path (unless the time limit cuts the search).
    step : float, optional
        Largest joint-space step of a tree extension (rad); default a fifth of the diagonal
        of the joint box (OMPL's range).
    resolution : float, optional
        With a validity function: the largest joint step (rad, or m) between the states
        checked on an edge, which is all a sampled edge is shown free at (default 0.01). With
        a robot: the resolution of the checker built for it (m, `CollisionChecker`'s
        default). A built checker keeps its own.
    max_iterations : int, optional
        Default the planner's (`armkit.planning.planners.PLANNERS`: 100,000; RRT* 2,000: it
        uses its whole budget to improve the path).
    time_limit : float
        s, the whole call: planning, shortcutting and the final check.
    goal_bias : float
        RRT and RRT*: probability of sampling a goal.
    simplify : bool
        Shortcut the path (random shortcuts, then greedy vertex reduction).
    shortcut_tries : int
        Random shortcut attempts.
    waypoints : int, optional
        Resample the path to this many waypoints, evenly spaced by joint-space arc length.
    ik_mask : optional
        Task mask for the IK of a goal pose.
    """

    planner: str = "rrtconnect"
    seed: int | None = 0
    step: float | None = None
    resolution: float | None = None
    max_iterations: int | None = None
    time_limit: float = 10.0
    goal_bias: float = 0.05
    simplify: bool = True
    shortcut_tries: int = 64
    waypoints: int | None = None
    ik_mask: object = None

    def __post_init__(self):
        planner_named(self.planner)
        for name in ("step", "resolution"):
            value = getattr(self, name)
            if value is not None and not (_real(value) and math.isfinite(value) and value > 0):
                raise InputError(f"{name}: expected a positive number, found {value!r}")
        if not (_real(self.time_limit) and self.time_limit >= 0 and not
                math.isnan(self.time_limit)):
            raise InputError(f"time_limit: expected a duration >= 0 (s), found "
                             f"{self.time_limit!r}")
        if not (_real(self.goal_bias) and 0 <= self.goal_bias <= 1):
            raise InputError(f"goal_bias: expected a probability in [0, 1], found "
                             f"{self.goal_bias!r}")
        for name, low in (("max_iterations", 0), ("shortcut_tries", 0), ("waypoints", 2)):
            value = getattr(self, name)
            if value is None and name != "shortcut_tries":
                continue
            if not (isinstance(value, (int, np.integer)) and not isinstance(value, bool)
                    and value >= low):
                raise InputError(f"{name}: expected a whole number >= {low}, found {value!r}")
        if self.seed is not None and not (isinstance(self.seed, (int, np.integer))
                                          and not isinstance(self.seed, bool)):
            raise InputError(f"seed: expected a whole number or None, found {self.seed!r}")


def _real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not \
        isinstance(value, bool)


DEFAULTS = PlanSettings()


@dataclass(frozen=True)
class PlanResult:
    """Outcome of `plan`.

    Attributes
    ----------
    success : bool
        A path was found and certified.
    path : ndarray, (k, n)
        The returned path (shortcut, and resampled to the asked waypoints); (0, n) on failure.
    reason : str
        "ok", "start in collision", "start outside the joint limits", "goal in collision",
        "no collision-free IK solution for the goal pose", "no path within the budget (...)",
        "the path needs at least K waypoints".
    planner : str
    planning_time : float
        s, from the call to the planner's first path (checks of start and goals included).
    total_time : float
        s, the whole call (shortcutting, resampling and the final certification included).
    shortcut_time : float
        s.
    iterations : int
        Planner iterations (0 when the direct edge was free).
    states_checked : int
        States the validity checker was asked about by the planner.
    raw_path : ndarray, (k0, n)
        The planner's path before shortcutting.
    raw_length, length : float
        Joint-space lengths of raw_path and path (rad, and m for prismatic joints).
    goals : ndarray, (g, n)
        The goal configurations tried (for a pose: its valid IK solutions).
    """

    success: bool
    path: NDArray
    reason: str
    planner: str
    planning_time: float
    total_time: float
    shortcut_time: float
    iterations: int
    states_checked: int
    raw_path: NDArray
    raw_length: float
    length: float
    goals: NDArray


def goals_from_pose(robot: Robot, pose: ArrayLike, *, mask=None, starts: int = 8,
                    seed: int = 0) -> NDArray:
    """Every distinct IK solution of a pose (k, n) within the joint limits.

    Closed-form solutions where the arm has them (`armkit.ik_solutions`), else numeric ones
    from several random starts (`armkit.ik`, one seed each).
    """
    from armkit.kinematics.ik import ik, ik_solutions

    T = as_transform(pose, "goal pose")
    if T.shape != (4, 4):
        raise InputError(f"goal pose: expected one pose (4, 4), found {T.shape}")
    try:
        sols = ik_solutions(robot, T, mask=mask)
        found = sols.q[sols.within_limits]
    except InputError:
        found = np.empty((0, robot.n))
    if len(found) == 0:
        lo, hi = robot.chain.sampling_limits
        q0 = np.random.default_rng(seed).uniform(lo, hi, (starts, robot.n))
        res = ik(robot, np.broadcast_to(T, (starts, 4, 4)), q0, mask=mask, seed=seed)
        found = res.q[res.success]
    distinct: list[NDArray] = []
    for q in found:
        if all(np.abs(q - d).max() > 1e-6 for d in distinct):
            distinct.append(q)
    return np.array(distinct).reshape(-1, robot.n)


def _validity(robot_or_checker, scene, resolution, limits):
    if isinstance(robot_or_checker, Robot):
        checker = CollisionChecker(robot_or_checker, scene if scene is not None else Scene(),
                                   **({} if resolution is None else {"resolution": resolution}))
        return checker, robot_or_checker
    if isinstance(robot_or_checker, CollisionChecker):
        if scene is not None:
            raise InputError("scene: expected none with a CollisionChecker (it holds its scene), "
                             "found one")
        return robot_or_checker, robot_or_checker.robot
    if isinstance(robot_or_checker, ValidityFunction):
        return robot_or_checker, None
    if callable(robot_or_checker):
        if limits is None:
            raise InputError("limits: expected (lower, upper) with a validity function, found "
                             "none")
        step = JOINT_STEP if resolution is None else resolution
        return ValidityFunction(robot_or_checker, limits[0], limits[1], step), None
    raise InputError(f"robot: expected a Robot, a CollisionChecker or a validity callable, "
                     f"found {type(robot_or_checker).__name__}")


def plan(robot_or_checker, start: ArrayLike, goal: ArrayLike | None = None,
         settings: PlanSettings | None = None, *, goal_pose: ArrayLike | None = None,
         scene: Scene | None = None, limits: tuple[ArrayLike, ArrayLike] | None = None,
         **keywords) -> PlanResult:
    """A collision-free joint-space path from start to a goal.

    Parameters
    ----------
    robot_or_checker : Robot, CollisionChecker or callable
        A robot (its collision model against `scene`), a built checker (cheapest when the
        robot plans many times: build its `CollisionModel` once), or a validity function
        ``f(Q (k, n)) -> (k,) bool`` with `limits` (its edges are sampled, see
        `PlanSettings.resolution`).
    start : array_like, (n,)
        rad / m.
    goal : array_like, (n,) or (g, n), optional
        One or several goal configurations (reaching any one is enough).
    settings : PlanSettings, optional
        How to plan; keywords (``planner="rrt"``, ``seed=3``, ``time_limit=0.5``, ...) build
        one, or replace fields of the one given.
    goal_pose : array_like, (4, 4), optional
        A tool pose instead: every collision-free IK solution within the limits is a goal.
    scene : Scene, optional
        Obstacles, with a robot.
    limits : (lower, upper), optional
        Joint limits to sample within, with a validity function.

    Returns
    -------
    PlanResult
    """
    t0 = time.perf_counter()
    if settings is None:
        settings = PlanSettings(**keywords) if keywords else DEFAULTS
    elif keywords:
        settings = dataclasses.replace(settings, **keywords)
    elif not isinstance(settings, PlanSettings):
        raise InputError(f"settings: expected a PlanSettings, found {type(settings).__name__}")
    deadline = timer(settings.time_limit)
    planner = planner_named(settings.planner)
    validity, robot = _validity(robot_or_checker, scene, settings.resolution, limits)
    native = isinstance(validity, CollisionChecker)
    n = validity.n
    start = _configuration(start, n, "start", robot)
    if (goal is None) == (goal_pose is None):
        raise InputError("goal: expected either goal (configurations) or goal_pose, found "
                         + ("neither" if goal is None else "both"))
    lower, upper = np.asarray(validity.lower), np.asarray(validity.upper)
    empty = np.empty((0, n))

    def failed(reason, goals=empty, iterations=0, checked=0, raw=empty, t_plan=None,
               t_short=0.0):
        dt = time.perf_counter() - t0
        return PlanResult(False, empty, reason, planner.name, dt if t_plan is None else t_plan,
                          dt, t_short, iterations, checked, raw,
                          _length(raw) if len(raw) else math.nan, math.nan, goals)

    # Small arrays: Python lists cost less than NumPy calls here.
    low, high = (lower - 1e-12).tolist(), (upper + 1e-12).tolist()

    def within(q):
        return all(lo <= v <= hi for v, lo, hi in zip(q.tolist(), low, high))

    if not within(start):
        return failed("start outside the joint limits")
    if goal_pose is None:
        # Start and goal configurations checked in one call.
        goals = _configuration(goal, n, "goal", robot).reshape(-1, n)
        inside = np.array([within(q) for q in goals], dtype=bool)
        ok = validity.valid_states(np.vstack([start, goals]))
        if not ok[0]:
            return failed("start in collision")
        if not inside.any():
            return failed("goal outside the joint limits", goals)
        ok = ok[1:] & inside
        if not ok.any():
            return failed("goal in collision", goals)
        goals = goals[ok]
    elif not validity.valid_states(start[None])[0]:
        return failed("start in collision")
    else:
        if robot is None:
            raise InputError("goal_pose: expected a Robot or a CollisionChecker to solve its IK, "
                             "found a validity function")
        goals = goals_from_pose(robot, goal_pose, mask=settings.ik_mask,
                                seed=settings.seed or 0)
        if len(goals) == 0:
            return failed("no IK solution for the goal pose within the joint limits")
        goals = goals[validity.valid_states(goals)]
        if len(goals) == 0:
            return failed("no collision-free IK solution for the goal pose")
    goals = np.ascontiguousarray(goals)
    checked = 1 + len(goals)

    # The direct edge first: to the nearest goal.
    nearest = goals[0] if len(goals) == 1 else \
        goals[np.argmin(np.linalg.norm(goals - start, axis=1))]
    direct = np.vstack([start, nearest])
    if native:
        free, k = validity.polyline_free(direct, deadline)
    else:
        free, k = validity.interior_free(start, nearest)
    checked += k
    iterations = 0
    if free:
        raw = direct
    else:
        step = settings.step
        if step is None:
            step = 0.2 * math.dist(lower.tolist(), upper.tolist())
        budget = planner.iterations if settings.max_iterations is None else \
            int(settings.max_iterations)
        if native:
            raw, iterations, k, reason = plan_compiled(
                validity, start, goals, planner, step=step, seed=settings.seed,
                max_iterations=budget, deadline=deadline, goal_bias=settings.goal_bias)
        else:
            raw, iterations, k, reason = planner.python(
                validity, start, goals, step=step, rng=np.random.default_rng(settings.seed),
                max_iterations=budget, deadline=deadline, goal_bias=settings.goal_bias)
        checked += k
        if raw is None:
            return failed(reason, goals, iterations, checked)
    t_plan = time.perf_counter() - t0
    t1 = time.perf_counter()
    path = shortcut(raw, validity, seed=settings.seed, tries=settings.shortcut_tries,
                    deadline=deadline) if settings.simplify and len(raw) > 2 else raw
    t_short = time.perf_counter() - t1
    waypoints = settings.waypoints
    if waypoints is not None:
        candidate = resample(path, waypoints)
        if not _checked(validity, candidate, deadline):
            if waypoints < len(path):
                return failed(f"the path needs at least {len(path)} waypoints", goals,
                              iterations, checked, raw, t_plan, t_short)
            candidate = resample_keeping_vertices(path, waypoints)
            if not _checked(validity, candidate, deadline):
                return _final_failure(failed, deadline, goals, iterations, checked, raw,
                                      t_plan, t_short)
        path = candidate
    elif path is not direct and not _checked(validity, path, deadline):
        # Every returned path is checked once more as a whole (a guard: a planner's bug, or a
        # sampled checker that sees a shortcut differently, must not escape); the direct edge
        # was just checked, as it is.
        return _final_failure(failed, deadline, goals, iterations, checked, raw, t_plan,
                              t_short)
    return PlanResult(True, path, "ok", planner.name, t_plan, time.perf_counter() - t0,
                      t_short, iterations, checked, raw, _length(raw), _length(path), goals)


def _length(path: NDArray) -> float:
    """`path_length` of a checked path: Python's arithmetic, cheaper on a few rows."""
    rows = path.tolist()
    return float(sum(map(math.dist, rows[:-1], rows[1:])))


def _final_failure(failed, deadline, goals, iterations, checked, raw, t_plan, t_short):
    reason = ("the time limit was reached while the path was checked" if left(deadline) <= 0
              else "the path failed its final check")
    return failed(reason, goals, iterations, checked, raw, t_plan, t_short)


def _checked(validity, path: NDArray, deadline: NDArray) -> bool:
    """Every waypoint of path and every edge between them free (by the deadline, for armkit's
    checker)."""
    if isinstance(validity, CollisionChecker):
        return validity.polyline_free(path, deadline)[0]
    if not validity.valid_states(path).all():
        return False
    return all(validity.interior_free(a, b)[0] for a, b in zip(path[:-1], path[1:]))


def _configuration(q, n: int, name: str, robot: Robot | None) -> NDArray:
    if robot is not None:
        return joint_array(robot, q, name)
    try:
        a = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected numbers, found {type(q).__name__}") from None
    if a.ndim == 0 or a.shape[-1] != n or not np.isfinite(a).all():
        raise InputError(f"{name}: expected finite values with last axis {n}, found shape "
                         f"{a.shape}")
    return np.ascontiguousarray(a)
