"""The job's steps, each from frozen inputs to a frozen record of what it found.

Every record has ``success`` and ``reason`` ("ok", or why the job stops there). The steps that
talk to the drive (`read_arm`, `send_motion`, `await_arrival`) take a connected
`armkit.drives.DriveClient`; the others are pure functions of the task and earlier records.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.drives import DriveClient, RegisterMap, check_waypoints
from armkit.dynamics import TorqueProfile, torque_profile
from armkit.errors import DriveError, InputError
from armkit.io.tasks import CloudTarget, Task
from armkit.kinematics.forward import fk
from armkit.kinematics.ik import ik, ik_solutions
from armkit.kinematics.jacobian import jacobian
from armkit.perception import TargetResult, detect_target
from armkit.planning import (CollisionChecker, PlanResult, goals_from_pose, plan,
                             resample_keeping_vertices)
from armkit.planning.certify import Certificate, certify
from armkit.trajectory import Trajectory, jerk_limited, retime_jerk, waypoint_path
from armkit.trajectory.bounds import peaks
from armkit.trajectory.concatenate import concatenate

# The drive has arrived when every joint is within this many counts of its last target and
# it reports no motion.
ARRIVAL_COUNTS = 1.0
POLL_PERIOD = 0.02          # s, between status reads while the drive moves
# Points added on each path segment before the spline through them, smoothest first: more
# points hug the planner's straight segments closer (a motion that cuts a corner through an
# obstacle is not certified) at the cost of sharper turns, hence a slower motion.
PER_SEGMENT = (0, 2, 4, 8, 32, 128)
LIMIT_SLACK = 1e-6          # relative, on the motion's checks against the limits


@dataclass(frozen=True, eq=False)
class TargetStep:
    """The target in the base frame.

    Attributes
    ----------
    T_base_target : ndarray (4, 4) or None
        m; None when no target was found in the cloud.
    detection : armkit.perception.TargetResult or None
        What the cloud search found (a cloud target only).
    """

    success: bool
    reason: str
    T_base_target: NDArray | None
    detection: TargetResult | None = None


@dataclass(frozen=True, eq=False)
class ArmState:
    """Where the drive reports the arm before the motion: q (n,), rad and m."""

    success: bool
    reason: str
    q: NDArray | None


@dataclass(frozen=True, eq=False)
class IKChoice:
    """Every IK solution considered and the one taken.

    Attributes
    ----------
    solutions : ndarray (k, n)
    within_limits, collision_free : ndarray (k,) of bool
    clearance : ndarray (k,)
        m, free distance of each solution (negative: penetration).
    chosen : int
        Index of the solution taken, -1 for none.
    why : str
        Why that one.
    """

    success: bool
    reason: str
    solutions: NDArray | None = None
    within_limits: NDArray | None = None
    collision_free: NDArray | None = None
    clearance: NDArray | None = None
    chosen: int = -1
    why: str = ""

    @property
    def q_goal(self) -> NDArray:
        """The solution taken (n,)."""
        return self.solutions[self.chosen]


@dataclass(frozen=True, eq=False)
class Motion:
    """The motion along the path and the waypoints sent from it.

    Attributes
    ----------
    trajectory : Trajectory or None
        Certified clear of the scene, within the velocity, acceleration and jerk limits.
    path : Trajectory or None
        The geometric path it follows (time read as joint-space arc length): the spline
        through the waypoints; None when it rests at every waypoint (it follows the straight
        segments between them).
    t, q : ndarray (N,), (N, n)
        The waypoints: the path's vertices and the times the motion passes them (s).
    how : str
        How it was made.
    certificate : armkit.planning.certify.Certificate or None
    """

    success: bool
    reason: str
    trajectory: Trajectory | None = None
    path: Trajectory | None = None
    t: NDArray | None = None
    q: NDArray | None = None
    how: str = ""
    certificate: Certificate | None = None


@dataclass(frozen=True)
class MotionChecks:
    """The checks between the motion and the send: what was checked, each "ok" or why not.

    Attributes
    ----------
    items : tuple of (str, str)
        (check, verdict) pairs, in the order they ran.
    torques : TorqueProfile or None
        The joint torques along the motion, for a robot with inertias.
    """

    success: bool
    reason: str
    items: tuple[tuple[str, str], ...] = ()
    torques: TorqueProfile | None = None


@dataclass(frozen=True, eq=False)
class Sent:
    """The waypoints as the drive took them.

    Attributes
    ----------
    waypoints : int
        Acknowledged.
    last_accepted : int or None
        Index of the last waypoint the drive acknowledged (None: none).
    t, q : ndarray (k,), (k, n)
        The drive's joints as it reported them between the writes (s since the motion began).
    """

    success: bool
    reason: str
    waypoints: int
    last_accepted: int | None
    t: NDArray
    q: NDArray


@dataclass(frozen=True, eq=False)
class Arrival:
    """How the drive ended.

    Attributes
    ----------
    q_final : ndarray (n,) or None
        The joints at arrival (None when it did not arrive).
    q_reported : ndarray (n,) or None
        Where the drive last said the joints were, arrived or not.
    t, q : ndarray (k,), (k, n)
        The drive's joints as it reported them while it moved (s since the motion began).
    """

    success: bool
    reason: str
    q_final: NDArray | None
    q_reported: NDArray | None
    t: NDArray
    q: NDArray


@dataclass(frozen=True)
class FinalCheck:
    """The tool at the drive's final joints (forward kinematics) against the target.

    Attributes
    ----------
    position_error : float
        m.
    resolution : float
        m, how far the tool moves for half a count on every joint of the drive: the error the
        drive's resolution alone allows there.
    """

    success: bool
    reason: str
    position_error: float
    resolution: float


def locate_target(task: Task) -> TargetStep:
    """The target in the base frame: the camera's pose of it, or the inlet found in a cloud."""
    target = task.target
    if not isinstance(target, CloudTarget):
        return TargetStep(True, "ok", task.T_base_camera @ target.T_camera_target)
    found = detect_target(target.cloud, kind=target.kind, radius=target.radius,
                          T_base_sensor=task.T_base_camera)
    if not found.success:
        return TargetStep(False, f"no target in the cloud: {found.reason}", None, found)
    return TargetStep(True, "ok", np.asarray(found.T_base_target), found)


def read_arm(client: DriveClient) -> ArmState:
    """The arm's joints as the drive reports them."""
    try:
        status = client.connect().status()
    except DriveError as err:
        return ArmState(False, f"drive: {err}", None)
    if not np.isfinite(status.q).all():
        return ArmState(False, "drive: its map has no actual-position registers, so where the "
                        "arm is cannot be read", None)
    return ArmState(True, "ok", status.q)


def choose_solution(task: Task, T_base_target: NDArray, q_current: NDArray,
                    checker: CollisionChecker) -> IKChoice:
    """Every IK solution of the target, the collision-free ones within the limits, and the
    nearest of them to the arm (joint-space distance)."""
    robot, mask = task.robot, task.target.mask
    try:
        found = ik_solutions(robot, T_base_target, mask=mask)
        q_all, inside = found.q.reshape(-1, robot.n), np.asarray(found.within_limits, bool)
    except InputError:         # no closed form for this mask: numeric ones from many starts
        q_all = goals_from_pose(robot, T_base_target, mask=mask, starts=16,
                                seed=task.planner.seed).reshape(-1, robot.n)
        inside = np.ones(len(q_all), bool)
    if len(q_all) == 0:
        verdict = ik(robot, T_base_target, q_current, mask=mask)
        return IKChoice(False, f"no IK solution: {verdict.reason}")
    clearance = checker.clearance(q_all)
    free = np.asarray(checker.valid(q_all), bool) & inside
    record = dict(solutions=q_all, within_limits=inside, collision_free=free,
                  clearance=clearance)
    if not inside.any():
        return IKChoice(False, "every IK solution is outside the joint limits", **record)
    candidates = np.flatnonzero(free)
    if len(candidates) == 0:
        return IKChoice(False, f"no collision-free IK solution ({int(inside.sum())} within "
                        "the limits, each in collision)", **record)
    distance = np.linalg.norm(q_all[candidates] - q_current, axis=1)
    chosen = int(candidates[np.argmin(distance)])
    why = (f"solution {chosen + 1} of {len(q_all)}: the nearest to the arm's current joints "
           f"({distance.min():.3f} joint-space distance) among {len(candidates)} "
           f"collision-free within the limits")
    return IKChoice(True, "ok", **record, chosen=chosen, why=why)


def plan_path(task: Task, checker: CollisionChecker, q_current: NDArray,
              q_goal: NDArray) -> PlanResult:
    """A certified collision-free path (`armkit.planning.plan`) of the task's waypoint count."""
    p = task.planner
    return plan(checker, q_current, q_goal, planner=p.name, seed=p.seed,
                time_limit=p.time_limit, max_iterations=p.max_iterations,
                waypoints=task.motion.waypoints)


def motion_limits(task: Task) -> tuple[NDArray, NDArray, NDArray]:
    """Velocity, acceleration and jerk limits (n,) the motion may use: the task's fraction of
    the robot's."""
    r, s = task.robot, task.motion.speed
    return s * r.velocity_limits, s * r.acceleration_limits, s * r.jerk_limits


def smooth_motion(task: Task, path: NDArray, checker: CollisionChecker) -> Motion:
    """A jerk-limited motion through the path's waypoints, certified clear of the scene.

    A cubic spline through the waypoints (then through more points on each segment, so that
    it hugs the straight segments the planner certified, until it is certified itself), timed
    by `armkit.trajectory.retime_jerk` within the task's limits; as a last resort the motion
    rests at each waypoint, a double-S on each certified segment. The waypoints sent are the
    path's own, at the times the motion passes them.
    """
    V, A, J = motion_limits(task)
    vertices = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
    last = None
    for per_segment in PER_SEGMENT:
        dense = (resample_keeping_vertices(path, 1 + per_segment * (len(path) - 1))
                 if per_segment else path)
        spline = waypoint_path(dense)
        timed = retime_jerk(spline, V, A, J)
        if not timed.success:
            last = timed.reason
            continue
        certificate = certify(checker, timed.trajectory)
        if certificate.success:
            s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))]
            t = timed.trajectory.knots[np.searchsorted(s, vertices - 1e-12)]
            how = (f"jerk-limited along a cubic spline through the path"
                   f"{f' ({per_segment} points added per segment)' if per_segment else ''}"
                   f", certified")
            return Motion(True, "ok", timed.trajectory, spline, t, path, how, certificate)
        last = certificate.reason
    pieces = [jerk_limited(a, b, V, A, J, sync="phase") for a, b in zip(path, path[1:])]
    motion = concatenate(pieces, "rest at every waypoint")
    certificate = certify(checker, motion)
    t = np.r_[0.0, np.cumsum([p.duration for p in pieces])]
    how = (f"rest at every waypoint, a double-S along each certified segment (a spline "
           f"through them: {last})")
    if not certificate.success:
        return Motion(False, f"no certified motion: {certificate.reason}", motion, None, t,
                      path, how, certificate)
    return Motion(True, "ok", motion, None, t, path, how, certificate)


def check_motion(task: Task, motion: Motion, register_map: RegisterMap) -> MotionChecks:
    """What must hold before anything is sent: the motion within the joint limits at every
    instant (positions at 1 kHz; velocity, acceleration and jerk by their exact peaks,
    `armkit.trajectory.bounds.peaks`), for a robot with inertias its joint torques within the
    torque limits (`armkit.dynamics.torque_profile`, payload and friction included), and the
    waypoints as the drive will take them (`armkit.drives.check_waypoints`: limits, timing,
    what the registers can hold)."""
    robot, tr = task.robot, motion.trajectory
    items = []
    q = tr.evaluate(np.linspace(tr.start, tr.end, max(2, math.ceil(tr.duration * 1000) + 1)))
    outside = (q < robot.lower - 1e-9) | (q > robot.upper + 1e-9)
    items.append(("joint positions within the limits",
                  "ok" if not outside.any() else
                  f"{robot.joint_names[int(np.argmax(outside.any(axis=0)))]} leaves its limits"))
    for name, order, limit in zip(("velocity", "acceleration", "jerk"), (1, 2, 3),
                                  motion_limits(task)):
        ratio = peaks(tr, order) / limit
        j = int(np.argmax(ratio))
        items.append((f"joint {name} within the limits",
                      "ok" if ratio[j] <= 1 + LIMIT_SLACK else
                      f"{robot.joint_names[j]} at {ratio[j]:.3f} times its limit"))
    torques = None
    if robot.inertia is not None:
        torques = torque_profile(robot, tr)
        j = int(np.argmax(torques.ratio))
        items.append(("joint torques within the limits",
                      "ok" if torques.within else
                      f"{robot.joint_names[j]} at {torques.ratio[j]:.3f} times its limit "
                      f"({torques.peak[j]:.4g} of {torques.limits[j]:.4g} "
                      f"{'N m' if robot.chain.revolute[j] else 'N'})"))
    try:
        check_waypoints(register_map, motion.q, motion.t)
        items.append(("waypoints as the drive takes them", "ok"))
    except InputError as err:
        items.append(("waypoints as the drive takes them", str(err)))
    failed = [f"{what}: {verdict}" for what, verdict in items if verdict != "ok"]
    return MotionChecks(not failed, failed[0] if failed else "ok", tuple(items), torques)


class _Reports:
    """The drive's joints as it reports them while it moves: times since `started` (s)."""

    def __init__(self, client: DriveClient, started: float):
        self.client, self.started = client, started
        self.t: list[float] = []
        self.q: list[NDArray] = []

    def read(self):
        status = self.client.status()
        self.t.append(time.perf_counter() - self.started)
        self.q.append(status.q)
        return status

    def arrays(self, n: int) -> tuple[NDArray, NDArray]:
        return np.array(self.t), np.array(self.q).reshape(-1, n)


def send_motion(client: DriveClient, motion: Motion, started: float) -> Sent:
    """Each waypoint at its time (s after `started`, a `time.perf_counter` reading), as the
    motion passes it; the drive's state read between the writes."""
    reports = _Reports(client, started)
    n = motion.q.shape[1]
    accepted = None
    try:
        for k in range(len(motion.q)):
            while (wait := motion.t[k] - (time.perf_counter() - started)) > 0:
                reports.read()
                time.sleep(min(POLL_PERIOD, wait))
            client.write_waypoint(motion.q[k])
            accepted = k
    except DriveError as err:
        last = err.last_accepted if err.last_accepted is not None else accepted
        why = DriveError(err.cause, last, waypoint=err.waypoint,
                         outcome_unknown=err.outcome_unknown)
        return Sent(False, f"drive fault: {why}", 0 if last is None else last + 1, last,
                    *reports.arrays(n))
    return Sent(True, "ok", len(motion.q), len(motion.q) - 1, *reports.arrays(n))


def await_arrival(client: DriveClient, register_map: RegisterMap, q_goal: NDArray,
                  timeout: float, started: float) -> Arrival:
    """Wait (at most `timeout` s) until the drive reports its joints at q_goal, within
    `ARRIVAL_COUNTS` counts of each register, and no motion (its moving bit, if it has one)."""
    reports = _Reports(client, started)
    robot = register_map.robot
    tolerance = 2 * ARRIVAL_COUNTS * register_map.half_count(q_goal) + 1e-12
    deadline = time.perf_counter() + timeout

    def ended(success: bool, reason: str, q_final=None) -> Arrival:
        t, q = reports.arrays(robot.n)
        return Arrival(success, reason, q_final, q[-1] if len(q) else None, t, q)

    try:
        while True:
            status = reports.read()
            if status.faulted:
                return ended(False, f"drive fault while moving (code {status.fault_code})")
            if np.all(np.abs(status.q - q_goal) <= tolerance) and not status.moving:
                return ended(True, "ok", status.q)
            if time.perf_counter() > deadline:
                off = robot.q_from_si(status.q) - robot.q_from_si(q_goal)
                j = int(np.argmax(np.abs(off) / robot.q_from_si(tolerance)))
                return ended(False, f"the drive did not arrive within {timeout:g} s: it "
                             f"reports {robot.joint_names[j]} {off[j]:+.6g} "
                             f"{robot.joint_units[j]} from the last waypoint"
                             + (" and still moving" if status.moving else ""))
            time.sleep(POLL_PERIOD)
    except DriveError as err:
        return ended(False, f"drive fault: {err}")


def final_check(task: Task, T_base_target: NDArray, q_final: NDArray,
                register_map: RegisterMap) -> FinalCheck:
    """Tool position at the drive's final joints against the target, and the error the
    drive's resolution alone allows there (|J| times half a count on every joint)."""
    robot = task.robot
    error = float(np.linalg.norm(fk(robot, q_final)[:3, 3] - T_base_target[:3, 3]))
    resolution = float(np.linalg.norm(np.abs(jacobian(robot, q_final)[:3])
                                      @ register_map.half_count(q_final)))
    if error <= resolution + 1e-9:
        return FinalCheck(True, "ok", error, resolution)
    return FinalCheck(False, f"the tool is {error * 1e3:.3f} mm from the target, more than "
                      f"the drive's resolution allows ({resolution * 1e3:.3f} mm)", error,
                      resolution)
