"""The end-to-end job of SPEC.md section 8: paper 1's system, for any arm.

A camera sees a target; the job maps it to the arm's base frame, reads where the arm is from its
drive, finds every inverse-kinematics solution and takes the collision-free one nearest the arm,
plans a collision-free path there, times a smooth motion along it within the joint limits
(checked again: smoothing must not cut a corner through an obstacle), sends N waypoints of it to
the drive over Modbus TCP, waits until the drive reports arrival, and compares the tool's
position at the drive's final joint values (forward kinematics) with the target.

Every outcome is a `JobResult` with its reason: an unreachable target, no path within the
budget, or a drive fault end the job early with nothing (or nothing more) sent. With no drive in
the task, the built-in simulated drive (a real Modbus TCP server) runs on an ephemeral loopback
port for the length of the job.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from armkit.errors import DriveError, InputError
from armkit.model.robot import Robot, Units

STEPS = ("target", "drive", "ik", "plan", "trajectory", "send", "arrival", "check")
# The drive is taken to have arrived when every joint is within this many counts of its last
# target and reports no motion.
ARRIVAL_COUNTS = 1.0
POLL_PERIOD = 0.02          # s, between status reads while the drive moves


@dataclass(frozen=True, eq=False)
class Task:
    """One job, SI (built by `armkit.io.tasks.load_task` from a task file, or in code).

    Attributes
    ----------
    T_base_camera, T_camera_target : ndarray, (4, 4)
        The camera's pose in the base frame; the target's pose as the camera sees it (None when
        a point cloud gives it).
    target_cloud : dict or None
        A point cloud of the inlet (path, kind, radius m or None, units), searched by
        `armkit.perception.detect_target` when the job runs.
    mask : str or None
        The IK task (a name of `armkit.kinematics.ik.task.NAMED_MASKS`); None: the robot's own.
    start : ndarray (n,) or None
        Where the simulated drive starts (a real drive reports where the arm is).
    scene : armkit.planning.Scene
    planner, seed, time_limit, max_iterations : planner settings (`armkit.planning.plan`).
    resolution : float or None
        m, the most any point of the arm may move between two checked states (default 5 mm).
    radius : float or None
        m, the radius of the default link capsules when the robot file declares none.
    waypoints : int
        Waypoints sent to the drive (paper 1: 10).
    speed : float
        Fraction of the joint velocity and acceleration limits the motion may use, (0, 1].
    drive_host, drive_port, drive_map : the drive; no host means the simulated drive.
    report : Path or None
        The report's folder.
    """

    name: str
    robot: Robot
    units: Units
    T_base_camera: NDArray
    T_camera_target: NDArray | None
    target_cloud: dict | None = None
    mask: str | None = None
    start: NDArray | None = None
    scene: object = None
    planner: str = "rrtconnect"
    seed: int = 0
    time_limit: float = 5.0
    max_iterations: int | None = None
    resolution: float | None = None
    radius: float | None = None
    waypoints: int = 10
    speed: float = 1.0
    drive_host: str | None = None
    drive_port: int | None = None
    drive_map: object = None
    drive_timeout: float = 1.0
    arrival_timeout: float = 30.0
    report: Path | None = None


@dataclass
class JobResult:
    """What each step of the job produced (SI). Steps not reached stay None.

    Attributes
    ----------
    success : bool
        The drive arrived and the tool is at the target within the drive's resolution.
    reason : str
        "ok", or why the job stopped: "out of reach", "no collision-free IK solution", the
        planner's reason, the trajectory's, a drive fault, "did not arrive within N s", ...
    stopped_at : str
        The step that ended the job (one of `STEPS`), or "" on success.
    T_base_target : ndarray, (4, 4)
    q_current : ndarray (n,)
        The arm's joints as the drive reported them before the motion.
    solutions : ndarray (k, n); within_limits, collision_free : (k,) bool; clearance : (k,) m
        Every IK solution considered; `chosen` is the index of the one taken (-1 for none).
    plan : armkit.planning.PlanResult
    trajectory : armkit.trajectory.Trajectory
        The smooth motion along the path, certified collision-free.
    t, q : ndarray (N,), (N, n)
        Waypoint times (s) and joint values as sent.
    sent : SendResult-like dict: waypoints, last_accepted, acknowledged (N, n) as read back.
    executed_t, executed_q : ndarray (k,), (k, n)
        The drive's reported joint values while it moved.
    q_final : ndarray (n,)
        The drive's joints at arrival.
    position_error : float
        m, tool position at q_final (FK) against the target.
    resolution : float
        m, how far the tool moves for half a count on every joint of the drive (the error
        the drive's resolution alone allows).
    timings : dict of str to float
        s per step.
    """

    task: Task
    success: bool = False
    reason: str = ""
    stopped_at: str = ""
    T_base_target: NDArray | None = None
    detection: object = None
    q_current: NDArray | None = None
    solutions: NDArray | None = None
    within_limits: NDArray | None = None
    collision_free: NDArray | None = None
    clearance: NDArray | None = None
    chosen: int = -1
    choice: str = ""
    plan: object = None
    trajectory: object = None
    trajectory_note: str = ""
    t: NDArray | None = None
    q: NDArray | None = None
    sent: dict | None = None
    executed_t: NDArray | None = None
    executed_q: NDArray | None = None
    q_final: NDArray | None = None
    position_error: float = math.nan
    rotation_error: float = math.nan
    resolution: float = math.nan
    drive: str = ""
    drive_map: object = None
    timings: dict = field(default_factory=dict)

    def fail(self, step: str, reason: str) -> JobResult:
        self.success, self.stopped_at, self.reason = False, step, reason
        return self


def demo_task() -> Task:
    """The built-in task: paper 1's water-supply arm, a camera over the track that sees the
    inlet, and a pillar between the arm's rest pose and the inlet."""
    from armkit.io.tasks import load_task

    with resources.as_file(resources.files("armkit") / "tasks" / "water_supply.task.yaml") as p:
        return load_task(p)


def default_register_map(robot: Robot):
    """A register map for any robot: float32 targets and actual positions, a waypoint index,
    and status registers; what the simulated drive holds when the task names no map."""
    from armkit.io.register_maps import parse_register_map

    n = robot.n
    document = {
        "device_id": 1, "word_order": "big", "byte_order": "big", "readback": True,
        "joints": [{"name": name, "target": 2 * i, "actual": 200 + 2 * i, "type": "float32"}
                   for i, name in enumerate(robot.joint_names)],
        "command": {"waypoint": 2 * n},
        "status": {"accepted": 2 * n + 1, "state": 2 * n + 2, "fault_bit": 15,
                   "fault": 2 * n + 3},
    }
    return parse_register_map(document, f"<default register map of {robot.name}>", robot)


def builtin_register_map(robot: Robot):
    """The register map shipped for a built-in robot (water_supply, inspection_6dof), else the
    default one (`default_register_map`)."""
    from armkit.io.register_maps import load_register_map

    shipped = resources.files("armkit.drives") / f"{robot.name}.map.yaml"
    if shipped.is_file():
        with resources.as_file(shipped) as path:
            return load_register_map(path, robot)
    return default_register_map(robot)


def run_task(task: Task, on_step: Callable[[str, str], None] | None = None) -> JobResult:
    """Run the job; never sends a waypoint it has not checked.

    Parameters
    ----------
    on_step : callable(step, detail), optional
        Told when each step of `STEPS` starts (detail "") and ends (detail: what it found).

    Returns
    -------
    JobResult
        Failures (unreachable target, no path, drive fault, no arrival) are results with
        their reason and the step that stopped.
    """
    from armkit.drives import SimDrive

    tell = on_step or (lambda step, detail: None)
    result = JobResult(task)
    drive_map = task.drive_map if task.drive_map is not None else builtin_register_map(task.robot)
    result.drive_map = drive_map
    if task.drive_host is None:
        with SimDrive(drive_map, position=task.start) as sim:
            result.drive = f"simulated drive on 127.0.0.1:{sim.port}"
            return _run(task, result, drive_map, "127.0.0.1", sim.port, tell)
    result.drive = f"{task.drive_host}:{task.drive_port}"
    return _run(task, result, drive_map, task.drive_host, task.drive_port, tell)


def _timed(result: JobResult, step: str, tell, work):
    tell(step, "")
    t0 = time.perf_counter()
    try:
        return work()
    finally:
        result.timings[step] = time.perf_counter() - t0


def _run(task: Task, result: JobResult, drive_map, host: str, port: int, tell) -> JobResult:
    from armkit.drives import DriveClient
    from armkit.planning import CollisionChecker, arm_geometry

    robot = task.robot
    if not _timed(result, "target", tell, lambda: _target(result)):
        return result
    tell("target", "in the base frame" if result.detection is None else
         f"found in the cloud ({result.detection.reason}), in the base frame")
    client = DriveClient(drive_map, host, port, timeout=task.drive_timeout)
    try:
        try:
            status = _timed(result, "drive", tell, lambda: client.connect().status())
        except DriveError as err:
            return result.fail("drive", f"drive: {err}")
        if not np.isfinite(status.q).all():
            return result.fail("drive", "drive: its map has no actual-position registers, so "
                                        "where the arm is cannot be read")
        result.q_current = status.q
        tell("drive", "current joints read")
        geometry = arm_geometry(robot, task.radius)
        checker = CollisionChecker(robot, task.scene, geometry,
                                   resolution=0.005 if task.resolution is None else task.resolution)
        if not _timed(result, "ik", tell, lambda: _choose(result, checker)):
            return result
        tell("ik", result.choice)
        if not _timed(result, "plan", tell, lambda: _plan(result, checker)):
            return result
        tell("plan", f"{len(result.plan.path)} waypoints, {result.plan.reason}")
        if not _timed(result, "trajectory", tell, lambda: _trajectory(result, checker)):
            return result
        tell("trajectory", f"{result.trajectory.duration:.2f} s")
        log = _MotionLog()
        try:
            if not _timed(result, "send", tell, lambda: _send(result, client, log)):
                return result
            tell("send", f"{result.sent['waypoints']} waypoints acknowledged")
            if not _timed(result, "arrival", tell,
                          lambda: _arrive(result, client, drive_map, log)):
                return result
        finally:
            result.executed_t = np.array(log.t)
            result.executed_q = np.array(log.q).reshape(-1, robot.n)
        tell("arrival", "arrived")
        _timed(result, "check", tell, lambda: _check(result, drive_map))
        tell("check", f"{result.position_error * 1e3:.3f} mm")
        return result
    finally:
        client.close()


def _target(result: JobResult) -> bool:
    """The target in the base frame: the camera's pose of it, or the inlet found in a cloud."""
    task = result.task
    if task.target_cloud is None:
        result.T_base_target = task.T_base_camera @ task.T_camera_target
        return True
    from armkit.perception import detect_target

    c = task.target_cloud
    found = detect_target(c["path"], kind=c["kind"], radius=c["radius"], units=c["units"],
                          T_base_sensor=task.T_base_camera)
    result.detection = found
    if not found.success:
        result.fail("target", f"no target in the cloud: {found.reason}")
        return False
    result.T_base_target = np.asarray(found.T_base_target)
    return True


def _choose(result: JobResult, checker) -> bool:
    """Every IK solution of the target, the collision-free ones, the nearest to the arm."""
    from armkit.kinematics.ik import ik, ik_solutions
    from armkit.planning import goals_from_pose

    task, robot = result.task, result.task.robot
    T = result.T_base_target
    try:
        sols = ik_solutions(robot, T, mask=task.mask)
        q_all, inside = sols.q, np.asarray(sols.within_limits, bool)
    except InputError:         # no closed form for this task: numeric solutions from many starts
        q_all = goals_from_pose(robot, T, mask=task.mask, starts=16, seed=task.seed)
        inside = np.ones(len(q_all), bool)
    if len(q_all) == 0:
        verdict = ik(robot, T, result.q_current, mask=task.mask)
        result.fail("ik", f"no IK solution: {verdict.reason}")
        return False
    result.solutions, result.within_limits = q_all.reshape(-1, robot.n), inside
    result.clearance = checker.clearance(result.solutions)
    result.collision_free = checker.valid(result.solutions) & inside
    candidates = np.flatnonzero(result.collision_free)
    if not inside.any():
        result.fail("ik", "every IK solution is outside the joint limits")
        return False
    if len(candidates) == 0:
        result.fail("ik", f"no collision-free IK solution ({int(inside.sum())} within the "
                          f"limits, each in collision)")
        return False
    distance = np.linalg.norm(result.solutions[candidates] - result.q_current, axis=1)
    result.chosen = int(candidates[np.argmin(distance)])
    result.choice = (f"solution {result.chosen + 1} of {len(q_all)}: the nearest to the arm's "
                     f"current joints ({distance.min():.3f} joint-space distance) among "
                     f"{len(candidates)} collision-free within the limits")
    return True


def _plan(result: JobResult, checker) -> bool:
    from armkit.planning import plan

    task = result.task
    result.plan = plan(checker, result.q_current, result.solutions[result.chosen],
                       planner=task.planner, seed=task.seed, time_limit=task.time_limit,
                       max_iterations=task.max_iterations, waypoints=task.waypoints)
    if not result.plan.success:
        result.fail("plan", f"no collision-free path: {result.plan.reason}")
        return False
    return True


def _trajectory(result: JobResult, checker) -> bool:
    """A smooth motion through the path's waypoints within the limits, certified free.

    A cubic spline through the waypoints, densified along the path's segments so that it hugs
    them, timed by `retime`; then sampled so finely that no point of the arm moves more than
    half the checker's resolution between samples, every sample checked. If the spline cuts a
    corner the path is densified further; as a last resort the motion stops at each waypoint
    and follows the certified segments exactly.
    """
    from armkit.planning import resample_keeping_vertices
    from armkit.trajectory import retime, waypoint_path

    task, robot = result.task, result.task.robot
    path = result.plan.path
    V = task.speed * robot.velocity_limits
    A = task.speed * robot.acceleration_limits
    vertices = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
    for per_segment in (8, 32, 128):
        dense = resample_keeping_vertices(path, 1 + per_segment * (len(path) - 1))
        timed = retime(waypoint_path(dense), V, A)
        if timed.success and _certified(timed.trajectory, checker):
            from armkit.trajectory import Trajectory

            tr = timed.trajectory
            s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))]
            t = tr.knots[np.searchsorted(s, vertices - 1e-12)]
            # Its knots: the times it passes the waypoints (not the densified points).
            result.trajectory = Trajectory(tr.breaks, tr.coefficients, t, "smoothed path")
            result.t, result.q = t, path
            result.trajectory_note = (f"cubic spline through the path ({per_segment} points per "
                                      f"segment), time-optimal within the limits, certified")
            return True
    # Rest at every waypoint: each piece follows exactly one certified segment.
    from armkit.trajectory import trapezoidal

    pieces = [trapezoidal(a, b, V, A) for a, b in itertools.pairwise(path)]
    result.trajectory, result.q = _one_after_another(pieces), path
    result.t = np.r_[0.0, np.cumsum([p.duration for p in pieces])]
    result.trajectory_note = ("rest at every waypoint: a spline through them cut a corner; "
                              "each piece follows a certified segment")
    return True


def _one_after_another(pieces):
    """One trajectory of motions played in turn, each from its end to the next one's start."""
    from armkit.trajectory import Trajectory

    K = max(p.coefficients.shape[1] for p in pieces)
    breaks, coefficients, offset = [0.0], [], 0.0
    for p in pieces:
        c = np.zeros((p.coefficients.shape[0], K, p.n))
        c[:, :p.coefficients.shape[1]] = p.coefficients
        coefficients.append(c)
        breaks.extend((p.breaks[1:] - p.breaks[0] + offset).tolist())
        offset += p.duration
    knots = np.r_[0.0, np.cumsum([p.duration for p in pieces])]
    return Trajectory(np.array(breaks), np.concatenate(coefficients), knots, "rest-to-rest")


def _certified(trajectory, checker) -> bool:
    """Every state of the motion clear of the scene: samples close enough that no point of the
    arm moves more than half the resolution between two, each sample clear by a quarter of it
    (two neighbours' clearances then exceed the motion between them)."""
    from armkit.trajectory.piecewise import peak

    speed = float(checker.weights @ peak(trajectory, 1))    # m/s: no arm point moves faster
    if speed == 0:
        return bool(checker.valid(trajectory.evaluate(0.0)))
    dt = 0.5 * checker.resolution / (speed * 1.05)
    count = int(min(max(math.ceil(trajectory.duration / dt) + 1, 2), 2_000_000))
    q = trajectory.evaluate(np.linspace(0.0, trajectory.duration, count))
    return bool((checker.clearance(q) > 0.25 * checker.resolution).all())


@dataclass
class _MotionLog:
    """The drive's joints as it reports them while it moves: times (s) since the first waypoint
    was due, and joint values (rad, m)."""

    started: float = field(default_factory=time.perf_counter)
    t: list = field(default_factory=list)
    q: list = field(default_factory=list)

    def read(self, client):
        status = client.status()
        self.t.append(time.perf_counter() - self.started)
        self.q.append(status.q)
        return status


def _send(result: JobResult, client, log: _MotionLog) -> bool:
    """Each waypoint at its time, as the trajectory passes it; the drive's state read between."""
    t, q = result.t, result.q
    accepted = -1
    try:
        for k in range(len(q)):
            while (wait := t[k] - (time.perf_counter() - log.started)) > 0:
                log.read(client)
                time.sleep(min(POLL_PERIOD, wait))
            client.write_waypoint(q[k])
            accepted = k
    except DriveError as err:
        result.sent = {"waypoints": accepted + 1, "last_accepted": err.last_accepted
                       if err.last_accepted is not None else accepted}
        result.fail("send", f"drive fault: {err}")
        return False
    result.sent = {"waypoints": len(q), "last_accepted": len(q) - 1}
    return True


def _arrive(result: JobResult, client, drive_map, log: _MotionLog) -> bool:
    """Wait (bounded) until the drive reports its joints at the last waypoint and still."""
    from armkit.drives.simdrive import MOVING_BIT

    target = result.q[-1]
    tolerance = 2 * ARRIVAL_COUNTS * half_count(drive_map, target) + 1e-12
    deadline = time.perf_counter() + result.task.arrival_timeout
    try:
        while True:
            status = log.read(client)
            if status.faulted:
                result.fail("arrival", f"drive fault while moving (code {status.fault_code})")
                return False
            moving = status.state is not None and bool(status.state >> MOVING_BIT & 1)
            if np.all(np.abs(status.q - target) <= tolerance) and not moving:
                break
            if time.perf_counter() > deadline:
                result.fail("arrival", f"the drive did not arrive within "
                                       f"{result.task.arrival_timeout:g} s")
                return False
            time.sleep(POLL_PERIOD)
    except DriveError as err:
        result.fail("arrival", f"drive fault: {err}")
        return False
    result.q_final = status.q
    return True


def half_count(drive_map, q: NDArray) -> NDArray:
    """Half of one count of each joint's register near q (n,), rad or m: how far a value can
    move when the drive stores it (integers: 1 / scale; float32: its relative precision)."""
    robot = drive_map.robot
    q_file = np.abs(robot.q_from_si(q))
    count = np.array([max(v, 1.0) * 2.0 ** -23 if j.type == "float32" else 1.0 / j.scale
                      for j, v in zip(drive_map.joints, q_file)])
    return 0.5 * robot.q_to_si(count)


def _check(result: JobResult, drive_map) -> None:
    """Tool position at the drive's final joints against the target, and the error the drive's
    resolution alone allows there."""
    from armkit.kinematics import fk
    from armkit.kinematics.jacobian import jacobian

    robot = result.task.robot
    T = fk(robot, result.q_final)
    result.position_error = float(np.linalg.norm(T[:3, 3] - result.T_base_target[:3, 3]))
    J = jacobian(robot, result.q_final)
    result.resolution = float(np.linalg.norm(np.abs(J[:3]) @ half_count(drive_map,
                                                                         result.q_final)))
    result.success = result.position_error <= result.resolution + 1e-9
    result.reason = "ok" if result.success else (
        f"the tool is {result.position_error * 1e3:.3f} mm from the target, more than the "
        f"drive's resolution allows ({result.resolution * 1e3:.3f} mm)")
    result.stopped_at = "" if result.success else "check"
