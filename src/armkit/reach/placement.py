"""Base placement: where to stand a robot (on a floor, with a yaw; or along a rail) so that it
reaches every pose of a task, and how much room that leaves.

The candidate bases are a grid (`floor_grid`, `rail_grid`): each is a pose of the robot's base
frame in the world. For every base and task pose, the task pose in the base frame is looked up
in a reachability map (when one is given: the index of its voxel, the share of orientations
reached there, is the pose's reachability; a base with a pose in a voxel of index 0 is not
tried further) and solved by IK (every closed-form solution, or the numeric solver), so that a
base is called feasible only when IK reaches every pose from it, within the joint limits. A
feasible base scores the worst of its poses: their reachability, or the manipulability of each
pose's best solution. The best base is the highest score, and among equal scores the one
farthest from a base that fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.ik import IKSolver
from armkit.kinematics.ik.masks import as_mask, mask_name
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot
from armkit.reach.maps import (ReachMap, manipulability_of, reaching_solutions, robot_key,
                               serves)
from armkit.sampled_workspace import finite_number, whole_number
from armkit.spatial import as_transform, invert, rotz

SCORES = ("reachability", "manipulability")
BLOCK = 1 << 16             # IK problems per block: memory stays bounded for any grid
MOST_BASES = 1_000_000         # 128 MB of base poses


@dataclass(frozen=True, eq=False)
class BaseGrid:
    """Candidate poses of the robot's base frame in the world, on a grid.

    Attributes
    ----------
    kind : {"floor", "rail"}
    poses : ndarray, shape (B, 4, 4)
        ``T_world_base`` of every candidate, in the grid's order (C order over `shape`).
    shape : tuple of int
        Floor: (ny, nx, nyaw), rows of y, columns of x, then yaw. Rail: (ns, nyaw).
    axes : dict of ndarray
        Floor: "x", "y" (m) and "yaw" (rad); rail: "s" (m along the rail from its start) and
        "yaw"; and "z" (m), the base's height; rail: "start", "direction" (3,).
    step : float
        Spacing of positions (m).
    """

    kind: str
    poses: NDArray
    shape: tuple
    axes: dict
    step: float

    def __len__(self) -> int:
        return len(self.poses)

    @property
    def positions(self) -> NDArray:
        """Base positions (B, 3) in the world, m."""
        return self.poses[:, :3, 3]

    @property
    def yaws(self) -> NDArray:
        """Base yaw (B,) about the world z axis, rad."""
        return np.arctan2(self.poses[:, 1, 0], self.poses[:, 0, 0])


def _axis_values(name: str, low: float, high: float, step: float) -> NDArray:
    low, high = finite_number(f"{name}[0]", low), finite_number(f"{name}[1]", high)
    if high < low:
        raise InputError(f"{name}: expected a range low .. high, found {low:g} .. {high:g}")
    steps = (high - low) / step
    if not steps < MOST_BASES:
        raise InputError(f"{name}: expected at most {MOST_BASES:,} steps of {step:g}, found "
                         f"{steps:.3g}")
    return low + step * np.arange(math.floor(steps + 1e-9) + 1)


def _yaw_values(yaw: tuple[float, float] | None, yaw_step: float) -> NDArray:
    """Yaws from a range (low, high) inclusive, or one turn [-pi, pi) when None."""
    yaw_step = finite_number("yaw_step", yaw_step)
    if not 0 < yaw_step <= 2 * math.pi:
        raise InputError(f"yaw_step: expected above 0 and at most 2 pi rad, found {yaw_step:g}")
    if yaw is None:
        if not 2 * math.pi / yaw_step < MOST_BASES:
            raise InputError(f"yaw_step: expected at most {MOST_BASES:,} yaws in a turn, found "
                             f"a step of {yaw_step:g} rad")
        count = max(1, round(2 * math.pi / yaw_step))
        return -math.pi + 2 * math.pi * np.arange(count) / count
    return _axis_values("yaw", yaw[0], yaw[1], yaw_step)


def _step(step: float) -> float:
    step = finite_number("step", step)
    if not step > 0:
        raise InputError(f"step: expected a positive length (m), found {step:g}")
    return step


def floor_grid(x: tuple[float, float], y: tuple[float, float], step: float, *, z: float = 0.0,
               yaw: tuple[float, float] | None = None,
               yaw_step: float = math.radians(10)) -> BaseGrid:
    """Bases on a floor: positions on a square grid over x and y, each with yaws about z.

    Parameters
    ----------
    x, y : (float, float)
        Ranges (m), both ends included where the step lands on them.
    step : float
        Grid spacing (m).
    z : float
        Height of the base frame's origin (m).
    yaw : (float, float) or None
        Range of yaws (rad), both ends included; None: one turn, ``[-pi, pi)``.
    yaw_step : float
        rad (default 10 deg).
    """
    step = _step(step)
    xs, ys = _axis_values("x", *x, step), _axis_values("y", *y, step)
    yaws = _yaw_values(yaw, yaw_step)
    if len(xs) * len(ys) * len(yaws) > MOST_BASES:
        raise InputError(f"step: expected at most {MOST_BASES:,} bases, found "
                         f"{len(xs) * len(ys) * len(yaws):,}")
    z = finite_number("z", z)
    Y, X, A = np.meshgrid(ys, xs, yaws, indexing="ij")
    T = np.zeros(X.shape + (4, 4))
    T[..., :3, :3] = rotz(A)
    T[..., 0, 3], T[..., 1, 3], T[..., 2, 3], T[..., 3, 3] = X, Y, z, 1.0
    axes = {"x": xs, "y": ys, "yaw": yaws, "z": np.array(z)}
    return BaseGrid("floor", frozen_array(T.reshape(-1, 4, 4)), X.shape,
                    {k: frozen_array(v) for k, v in axes.items()}, step)


def rail_grid(start: ArrayLike, end: ArrayLike, step: float, *,
              yaw: float | tuple[float, float] = 0.0,
              yaw_step: float = math.radians(10)) -> BaseGrid:
    """Bases along a straight rail from `start` to `end` (3,) m, every `step` m, with a fixed
    yaw (rad) or a range of yaws (low, high) every `yaw_step`."""
    step = _step(step)
    a = np.array([finite_number("start", v) for v in np.ravel(start)])
    b = np.array([finite_number("end", v) for v in np.ravel(end)])
    if a.shape != (3,) or b.shape != (3,):
        raise InputError(f"start, end: expected 3 coordinates each, found {a.size} and {b.size}")
    length = math.dist(a, b)
    if not math.isfinite(length):
        raise InputError(f"start, end: expected a rail of finite length, found one from "
                         f"{a.tolist()} to {b.tolist()}")
    direction = (b - a) / length if length > 0 else np.array([1.0, 0.0, 0.0])
    s = _axis_values("rail", 0.0, length, step)
    yaws = (np.array([finite_number("yaw", yaw)]) if np.ndim(yaw) == 0
            else _yaw_values(tuple(yaw), yaw_step))
    S, A = np.meshgrid(s, yaws, indexing="ij")
    T = np.zeros(S.shape + (4, 4))
    T[..., :3, :3] = rotz(A)
    T[..., :3, 3] = a + S[..., None] * direction
    T[..., 3, 3] = 1.0
    axes = {"s": s, "yaw": yaws, "z": np.array(a[2]), "start": a, "direction": direction}
    return BaseGrid("rail", frozen_array(T.reshape(-1, 4, 4)), S.shape,
                    {k: frozen_array(v) for k, v in axes.items()}, step)


@dataclass(frozen=True, eq=False)
class Placement:
    """Where the base can stand, and the best place.

    Attributes
    ----------
    grid : BaseGrid
    task : ndarray, shape (P, 4, 4)
        The task poses in the world.
    reached : ndarray of bool, shape (B, P)
        IK reaches pose p from base b (within the limits). False where a map ruled the base
        out before IK (a pose in a voxel of index 0).
    reachability : ndarray, shape (B, P)
        The map's index at each pose (NaN without a map).
    feasible : ndarray of bool, shape (B,)
        Every pose reached.
    score : ndarray, shape (B,)
        The worst pose's score at each feasible base; NaN elsewhere.
    margin : ndarray, shape (B,)
        m: distance from each feasible base to the nearest base of the grid, at the same yaw,
        that fails (to the edge of the grid where none fails: a lower bound); NaN elsewhere.
    best : int or None
        Row of the best base: the highest score, then the largest margin.
    T_world_base : ndarray (4, 4) or None
        The best base's pose.
    q : ndarray (P, n) or None
        Joint values that reach each pose from the best base (IK, the most manipulable
        solution).
    yaw_margin : float
        rad: how far the best base's yaw may turn, either way, before a pose is lost (pi if
        every yaw of a full turn works there; else at least to the end of the grid's yaws);
        NaN without a best base.
    criterion : {"reachability", "manipulability"}
    mask : str
        The IK task.
    success : bool
    reason : str
        "ok", or why no base works.
    """

    grid: BaseGrid
    task: NDArray
    reached: NDArray
    reachability: NDArray
    feasible: NDArray
    score: NDArray
    margin: NDArray
    best: int | None
    T_world_base: NDArray | None
    q: NDArray | None
    yaw_margin: float
    criterion: str
    mask: str
    success: bool
    reason: str
    names: tuple = field(default=())

    def to_dict(self) -> dict:
        """The best base and its figures as JSON-ready values (SI)."""
        best = self.best
        out = {"success": self.success, "reason": self.reason, "criterion": self.criterion,
               "mask": self.mask, "bases": len(self.grid), "feasible": int(self.feasible.sum()),
               "poses": len(self.task)}
        if best is not None:
            p = self.T_world_base[:3, 3]
            out.update(position=p.tolist(), yaw=float(self.grid.yaws[best]),
                       score=float(self.score[best]), margin=float(self.margin[best]),
                       yaw_margin=float(self.yaw_margin), q=self.q.tolist(),
                       reachability=[None if math.isnan(v) else float(v)
                                     for v in self.reachability[best]])
        return out


def base_placement(robot: Robot, task: ArrayLike, grid: BaseGrid, *,
                   reach_map: ReachMap | None = None, criterion: str | None = None,
                   mask: str | ArrayLike | None = None, restarts: int = 20,
                   names: tuple[str, ...] = ()) -> Placement:
    """The bases of a grid from which IK reaches every task pose, scored, and the best one.

    Parameters
    ----------
    robot : Robot
    task : array_like, shape (P, 4, 4)
        Task poses in the world (m).
    grid : BaseGrid
        Candidate bases (`floor_grid`, `rail_grid`).
    reach_map : ReachMap, optional
        The robot's map: gives each pose's reachability, and rules out bases with a pose in a
        voxel that reaches nothing before IK is tried.
    criterion : {"reachability", "manipulability"}, optional
        The score of a pose: the map's index at it (default with a map), or the
        manipulability of its best solution (default without).
    mask : str or 6 flags, optional
        The IK task: the map's orientations' task, else the robot's default.
    restarts : int
        Random restarts of the numeric solver (arms without a closed form for the task).
    names : tuple of str
        The poses' names, for the reason of a failure.

    Returns
    -------
    Placement
        With ``success`` False and a reason when no base reaches every pose (not an error).

    Raises
    ------
    InputError
        Bad shapes or values, a map of another robot, reachability without a map.
    """
    if not isinstance(robot, Robot):
        raise InputError(f"robot: expected a Robot, found {type(robot).__name__}")
    T_task = as_transform(task, "task")
    if T_task.ndim == 2:
        T_task = T_task[None]
    if T_task.ndim != 3 or not 1 <= len(T_task) <= 10_000:
        raise InputError(f"task: expected 1 .. 10000 poses (P, 4, 4), found {T_task.shape}")
    if not isinstance(grid, BaseGrid):
        raise InputError(f"grid: expected a BaseGrid (floor_grid, rail_grid), found "
                         f"{type(grid).__name__}")
    if reach_map is not None and robot_key(reach_map.robot) != robot_key(robot):
        raise InputError(f"reach_map: expected a map of {robot.name}, found one of "
                         f"{reach_map.robot.name}")
    criterion = criterion or ("reachability" if reach_map is not None else "manipulability")
    if criterion not in SCORES:
        raise InputError(f"criterion: expected one of {', '.join(SCORES)}, found {criterion!r}")
    if criterion == "reachability" and reach_map is None:
        raise InputError("criterion: expected 'manipulability' without a map, found "
                         "'reachability' (give a reach map)")
    solver = IKSolver(robot)
    if mask is not None:
        task_mask = as_mask(mask)
    elif reach_map is not None:
        task_mask = np.asarray(reach_map.orientations.mask, dtype=bool)
    else:
        task_mask = solver.default_mask
    restarts = whole_number("restarts", restarts, 0, 10_000)
    B, P = len(grid), len(T_task)
    # The task poses in each base's frame, block by block.
    T_base_world = invert(grid.poses)
    reachability = np.full((B, P), np.nan)
    tried = np.ones(B, dtype=bool)
    if reach_map is not None:
        for rows in _blocks(B, P):
            local = T_base_world[rows, None] @ T_task[None]
            reachability[rows] = reach_map.index_at(local[..., :3, 3])
        tried = (reachability > 0).all(axis=1)
    reached = np.zeros((B, P), dtype=bool)
    quality = np.full((B, P), np.nan)
    method = "analytic" if serves(solver, task_mask) else "lm"
    bases = np.flatnonzero(tried)
    for rows in _blocks(len(bases), P):
        b = bases[rows]
        T = (T_base_world[b, None] @ T_task[None]).reshape(-1, 4, 4)
        Q, ok = reaching_solutions(solver, T, task_mask, method, restarts=restarts)
        reached[b] = ok.any(axis=1).reshape(len(b), P)
        if criterion == "manipulability":
            best = np.full(ok.shape, -np.inf)
            if ok.any():
                best[ok] = manipulability_of(robot, Q[ok])
            quality[b] = best.max(axis=1).reshape(len(b), P)
    feasible = reached.all(axis=1)
    per_pose = reachability if criterion == "reachability" else quality
    score = np.where(feasible, np.min(np.where(feasible[:, None], per_pose, np.inf), axis=1),
                     np.nan)
    margin = _margins(grid, feasible)
    name = mask_name(task_mask)
    if not feasible.any():
        return Placement(grid, T_task, reached, reachability, feasible, score, margin, None,
                         None, None, math.nan, criterion, name, False,
                         _why_none(reached, reachability, names))
    rows = np.flatnonzero(feasible)
    best = int(rows[np.lexsort((-margin[rows], -score[rows]))[0]])
    T_best = grid.poses[best]
    solved = solver.solve(invert(T_best) @ T_task, mask=task_mask,
                          criterion="manipulability", restarts=max(restarts, 50))
    q = np.asarray(solved.q).reshape(P, robot.n)
    return Placement(grid, T_task, reached, reachability, feasible, score, margin, best,
                     T_best, q, _yaw_margin(grid, feasible, best), criterion, name, True, "ok",
                     tuple(names))


def _blocks(count: int, per: int):
    """Slices of `count` bases, each with at most BLOCK problems of `per` poses."""
    size = max(1, BLOCK // per)
    for start in range(0, count, size):
        yield slice(start, min(count, start + size))


def _margins(grid: BaseGrid, feasible: NDArray) -> NDArray:
    """Distance (m) from each feasible base to the nearest failing base at the same yaw, or
    to the grid's edge when none fails (NaN for bases that fail)."""
    ok = feasible.reshape(grid.shape)
    out = np.full(grid.shape, np.nan)
    if grid.kind == "floor":
        xs, ys = grid.axes["x"], grid.axes["y"]
        X, Y = np.meshgrid(xs, ys)                       # (ny, nx), as the grid's rows
        edge = np.minimum.reduce([X - xs[0], xs[-1] - X, Y - ys[0], ys[-1] - Y]) + grid.step
        for k in range(grid.shape[2]):
            good, bad = ok[..., k], ~ok[..., k]
            if not good.any():
                continue
            gap = edge[good]
            if bad.any():
                d = np.hypot(X[good][:, None] - X[bad][None], Y[good][:, None] - Y[bad][None])
                gap = np.minimum(gap, d.min(axis=1))
            out[..., k][good] = gap
    else:
        s = grid.axes["s"]
        edge = np.minimum(s - s[0], s[-1] - s) + grid.step
        for k in range(grid.shape[1]):
            good, bad = ok[:, k], ~ok[:, k]
            gap = edge[good]
            if bad.any():
                gap = np.minimum(gap, np.abs(s[good][:, None] - s[bad][None]).min(axis=1))
            out[good, k] = gap
    return out.reshape(-1)


def _yaw_margin(grid: BaseGrid, feasible: NDArray, best: int) -> float:
    """How far the best base may turn, either way, before a pose is lost, at its position
    (rad): to the nearest yaw of the grid that fails there; where none fails, pi if the
    grid's yaws go round a full turn, else to the end of their range (a lower bound)."""
    ok = feasible.reshape(-1, grid.shape[-1])
    row, k = divmod(best, grid.shape[-1])
    yaws = grid.axes["yaw"]
    bad = ~ok[row]
    if bad.any():
        turn = np.abs((yaws[bad] - yaws[k] + math.pi) % (2 * math.pi) - math.pi)
        return float(turn.min())
    if len(yaws) > 1 and math.isclose(len(yaws) * (yaws[1] - yaws[0]), 2 * math.pi):
        return math.pi
    return float(min(yaws[k] - yaws[0], yaws[-1] - yaws[k]))


def _why_none(reached: NDArray, reachability: NDArray, names: tuple) -> str:
    """Why no base works: poses outside the map's reach from every base, else poses IK
    reaches from none, else the most poses one base reaches."""
    label = lambda p: f"pose {p}" + (f" ({names[p]})" if p < len(names) else "")  # noqa: E731
    listed = lambda poses: (", ".join(label(p) for p in poses[:5])           # noqa: E731
                            + (" ..." if len(poses) > 5 else ""))
    start = "no base of the grid reaches every pose: "
    blocked = np.flatnonzero((reachability == 0).all(axis=0))
    if blocked.size:
        verb = "is" if blocked.size == 1 else "are"
        return f"{start}{listed(blocked)} {verb} in no voxel the map reaches, from any base"
    never = np.flatnonzero(~reached.any(axis=0))
    if never.size:
        return f"{start}{listed(never)} from none"
    most = int(reached.sum(axis=1).max())
    return (f"{start}each is reached from some base, but at most {most} of "
            f"{reached.shape[1]} from one")
