"""`plan`: from a start to a goal (configurations or a pose) without collision, as a result.

Order of work: the start checked, then the goals (a pose becomes every collision-free IK
solution), the direct start-goal edge tried, then the planner; its path shortcut, resampled to
N waypoints if asked, and certified again (every waypoint and every edge between them) before
it is returned. An unsolvable problem is a `PlanResult` with its reason, never an exception.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model.robot import Robot, joint_array
from armkit.planning.collision import CollisionChecker
from armkit.planning.compiled import plan_compiled
from armkit.planning.rrt import PLANNERS, ValidityFunction
from armkit.planning.scene import Scene
from armkit.planning.smooth import path_length, resample, resample_keeping_vertices, shortcut
from armkit.spatial import as_transform

DEFAULT_ITERATIONS = {"rrt": 100_000, "rrtconnect": 100_000, "rrtstar": 2_000}


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
    if isinstance(robot_or_checker, str):                   # a built-in name or robot file
        from armkit.io.robot_files import robot as load
        robot_or_checker = load(robot_or_checker)
    if isinstance(robot_or_checker, Robot):
        res = 0.005 if resolution is None else resolution
        return CollisionChecker(robot_or_checker, scene if scene is not None else Scene(),
                                resolution=res), robot_or_checker
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
        res = 0.01 if resolution is None else resolution
        return ValidityFunction(robot_or_checker, limits[0], limits[1], res), None
    raise InputError(f"robot: expected a Robot, a CollisionChecker or a validity callable, "
                     f"found {type(robot_or_checker).__name__}")


def plan(robot_or_checker, start: ArrayLike, goal: ArrayLike | None = None, *,
         goal_pose: ArrayLike | None = None, scene: Scene | None = None,
         planner: str = "rrtconnect", seed: int | None = 0, step: float | None = None,
         resolution: float | None = None, max_iterations: int | None = None,
         time_limit: float = 10.0, goal_bias: float = 0.05, simplify: bool = True,
         waypoints: int | None = None, limits: tuple[ArrayLike, ArrayLike] | None = None,
         ik_mask=None) -> PlanResult:
    """A collision-free joint-space path from start to a goal.

    Parameters
    ----------
    robot_or_checker : Robot, str, CollisionChecker or callable
        A robot or its name / file (its capsules against `scene`), a built checker, or a
        validity function ``f(Q (k, n)) -> (k,) bool`` with `limits`.
    start : array_like, (n,)
        rad / m.
    goal : array_like, (n,) or (g, n), optional
        One or several goal configurations (reaching any one is enough).
    goal_pose : array_like, (4, 4), optional
        A tool pose instead: every collision-free IK solution within the limits is a goal.
    scene : Scene, optional
        Obstacles, with a robot.
    planner : {"rrtconnect", "rrt", "rrtstar"}
    seed : int or None
        Same seed, same path (unless the time limit cuts the search).
    step : float, optional
        Largest joint-space step of a tree extension (rad); default a fifth of the diagonal
        of the joint box (OMPL's range).
    resolution : float, optional
        With a robot: m, the most any point of the arm moves between two checked states
        (default 5 mm). With a function: the largest joint step (default 0.01 rad).
    max_iterations : int, optional
        Default 100,000 (RRT* 2,000: it uses its whole budget to improve the path).
    time_limit : float
        s, planner budget.
    goal_bias : float
        RRT and RRT*: probability of sampling a goal.
    simplify : bool
        Shortcut the path (random shortcuts, then greedy vertex reduction).
    waypoints : int, optional
        Resample the path to this many waypoints, evenly spaced by joint-space arc length.
    limits : (lower, upper), optional
        Joint limits to sample within, with a validity function.
    ik_mask : optional
        Task mask for the IK of goal_pose.

    Returns
    -------
    PlanResult
    """
    t0 = time.perf_counter()
    if planner not in PLANNERS:
        raise InputError(f"planner: expected one of {', '.join(PLANNERS)}, found {planner!r}")
    validity, robot = _validity(robot_or_checker, scene, resolution, limits)
    n = validity.n
    start = _configuration(start, n, "start", robot)
    if (goal is None) == (goal_pose is None):
        raise InputError("goal: expected either goal (configurations) or goal_pose, found "
                         + ("neither" if goal is None else "both"))
    lower, upper = np.asarray(validity.lower), np.asarray(validity.upper)
    empty = np.empty((0, n))

    def failed(reason, goals=empty, iterations=0, checked=0):
        dt = time.perf_counter() - t0
        return PlanResult(False, empty, reason, planner, dt, dt, 0.0, iterations, checked,
                          empty, math.nan, math.nan, goals)

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
        goals = goals_from_pose(robot, goal_pose, mask=ik_mask, seed=seed or 0)
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
    free, k = validity.interior_free(start, nearest)
    checked += k
    iterations = 0
    if free:
        raw = np.vstack([start, nearest])
    else:
        if step is None:
            step = 0.2 * math.dist(lower.tolist(), upper.tolist())
        if not (math.isfinite(step) and step > 0):
            raise InputError(f"step: expected a positive joint-space step, found {step}")
        budget = DEFAULT_ITERATIONS[planner] if max_iterations is None else int(max_iterations)
        if isinstance(validity, CollisionChecker):         # the whole loop compiled
            raw, iterations, k, reason = plan_compiled(
                validity, start, goals, planner, step=step, seed=seed, max_iterations=budget,
                time_limit=time_limit, goal_bias=goal_bias)
        else:
            raw, iterations, k, reason = PLANNERS[planner](
                validity, start, goals, step=step, rng=np.random.default_rng(seed),
                max_iterations=budget, time_limit=time_limit, goal_bias=goal_bias)
        checked += k
        if raw is None:
            return failed(reason, goals, iterations, checked)
    t_plan = time.perf_counter() - t0
    t1 = time.perf_counter()
    path = shortcut(raw, validity, seed=seed) if simplify and len(raw) > 2 else raw
    t_short = time.perf_counter() - t1
    certified = False
    if waypoints is not None:
        candidate = resample(path, waypoints)
        certified = _certified(validity, candidate)
        if not certified:
            if waypoints < len(path):
                dt = time.perf_counter() - t0
                return PlanResult(False, empty, f"the path needs at least {len(path)} waypoints",
                                  planner, t_plan, dt, t_short, iterations, checked, raw,
                                  path_length(raw), math.nan, goals)
            candidate = resample_keeping_vertices(path, waypoints)
        path = candidate
    # Every returned path certified once more, as a whole (a guard: a planner's bug must not
    # escape); a resampled path that was just certified is not checked twice.
    if not certified and not _certified(validity, path):
        raise AssertionError("planning: a path failed its final certification")
    return PlanResult(True, path, "ok", planner, t_plan, time.perf_counter() - t0, t_short,
                      iterations, checked, raw, path_length(raw), path_length(path), goals)


def _certified(validity, path: NDArray) -> bool:
    if isinstance(validity, CollisionChecker):
        return validity.polyline_free(path)[0]
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
