"""The job as a line of steps (`armkit.job.steps`), and its record, `JobResult`."""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from armkit.drives import DriveClient, SimDrive
from armkit.io.tasks import Task
from armkit.job.steps import (Arrival, FinalCheck, IKChoice, Motion, MotionChecks, Sent,
                              TargetStep, await_arrival, check_motion, choose_solution,
                              final_check, locate_target, plan_path, read_arm, send_motion,
                              smooth_motion)
from armkit.planning import CollisionChecker, PlanResult, arm_geometry

STEPS = ("target", "drive", "ik", "plan", "motion", "checks", "send", "arrival", "final")
"""The steps in order: the target in the base frame, the arm's joints from the drive, the IK
solution, the path, the motion, the checks before anything is sent, the send, the drive's
arrival, the final position."""


@dataclass(frozen=True, eq=False)
class JobResult:
    """The record of a job: each step's own record, None for steps not reached (SI).

    Attributes
    ----------
    task : Task
    success : bool
        The drive arrived and the tool is at the target within the drive's resolution.
    reason : str
        "ok", or the reason of the step that stopped the job.
    stopped_at : str
        That step (one of `STEPS`), or "" on success.
    drive : str
        Which drive: ``"simulated drive on 127.0.0.1:PORT"`` or ``"HOST:PORT"``.
    target : TargetStep
    q_current : ndarray (n,) or None
        The arm's joints as the drive reported them before the motion.
    ik : IKChoice
    plan : armkit.planning.PlanResult
    motion : Motion
    checks : MotionChecks
    sent : Sent
    arrival : Arrival
    final : FinalCheck
    timings : dict of str to float
        s per step reached.
    """

    task: Task
    success: bool
    reason: str
    stopped_at: str
    drive: str
    target: TargetStep | None = None
    q_current: NDArray | None = None
    ik: IKChoice | None = None
    plan: PlanResult | None = None
    motion: Motion | None = None
    checks: MotionChecks | None = None
    sent: Sent | None = None
    arrival: Arrival | None = None
    final: FinalCheck | None = None
    timings: dict = field(default_factory=dict)

    @property
    def executed(self) -> tuple[NDArray, NDArray]:
        """The drive's joints as it reported them from the first waypoint on: t (k,) s since
        the motion began, q (k, n)."""
        parts = [p for p in (self.sent, self.arrival) if p is not None]
        if not parts:
            return np.zeros(0), np.zeros((0, self.task.robot.n))
        return np.concatenate([p.t for p in parts]), np.concatenate([p.q for p in parts])


def run_job(task: Task, on_step: Callable[[str, str], None] | None = None) -> JobResult:
    """Run the job of a task; never sends a waypoint it has not checked.

    Parameters
    ----------
    task : armkit.io.tasks.Task
    on_step : callable(step, detail), optional
        Told when each step of `STEPS` starts (detail "") and ends (detail: what it found).

    Returns
    -------
    JobResult
        Failures (no target, unreachable target, no path, a motion that fails its checks, a
        drive fault, no arrival, a final error beyond the drive's resolution) are results with
        their reason and the step that stopped.

    Example
    -------
    >>> from armkit.io.tasks import demo_task
    >>> result = run_job(demo_task())            # the simulated drive moves in real time
    >>> result.success, result.sent.waypoints
    (True, 10)
    """
    tell = on_step or (lambda step, detail: None)
    drive = task.drive
    if drive.host is None:
        with SimDrive(drive.register_map, position=task.start) as sim:
            return _run(task, tell, f"simulated drive on 127.0.0.1:{sim.port}", "127.0.0.1",
                        sim.port)
    return _run(task, tell, f"{drive.host}:{drive.port}", drive.host, drive.port)


@contextmanager
def _timed(timings: dict, tell, name: str):
    """Around one step: told when it starts, its time kept in `timings` (s)."""
    tell(name, "")
    t0 = time.perf_counter()
    try:
        yield
    finally:
        timings[name] = time.perf_counter() - t0


def _run(task: Task, tell, drive_text: str, host: str, port: int) -> JobResult:
    """The steps in order, the first that fails ending the job; the records so far."""
    records, timings = {}, {}

    def stop(step: str = "", reason: str = "ok") -> JobResult:
        return JobResult(task, not step, reason, step, drive_text, timings=timings, **records)

    drive = task.drive
    with _timed(timings, tell, "target"):
        records["target"] = target = locate_target(task)
    if not target.success:
        return stop("target", target.reason)
    tell("target", "in the base frame" if target.detection is None else
         f"found in the cloud ({target.detection.reason}), in the base frame")
    client = DriveClient(drive.register_map, host, port, timeout=drive.timeout)
    try:
        with _timed(timings, tell, "drive"):
            arm = read_arm(client)
        if not arm.success:
            return stop("drive", arm.reason)
        records["q_current"] = arm.q
        tell("drive", "current joints read")
        checker = CollisionChecker(task.robot, task.scene,
                                   arm_geometry(task.robot, task.planner.radius),
                                   resolution=task.planner.resolution)
        with _timed(timings, tell, "ik"):
            records["ik"] = choice = choose_solution(task, target.T_base_target, arm.q,
                                                     checker)
        if not choice.success:
            return stop("ik", choice.reason)
        tell("ik", choice.why)
        with _timed(timings, tell, "plan"):
            records["plan"] = path = plan_path(task, checker, arm.q, choice.q_goal)
        if not path.success:
            return stop("plan", f"no collision-free path: {path.reason}")
        tell("plan", f"{len(path.path)} waypoints, {path.reason}")
        with _timed(timings, tell, "motion"):
            records["motion"] = motion = smooth_motion(task, path.path, checker)
        if not motion.success:
            return stop("motion", motion.reason)
        tell("motion", f"{motion.trajectory.duration:.2f} s, {motion.how}")
        # Every check of the motion runs here, before the first waypoint leaves.
        with _timed(timings, tell, "checks"):
            records["checks"] = checks = check_motion(task, motion, drive.register_map)
        if not checks.success:
            return stop("checks", checks.reason)
        tell("checks", f"{len(checks.items)} passed")
        started = time.perf_counter()
        with _timed(timings, tell, "send"):
            records["sent"] = sent = send_motion(client, motion, started)
        if not sent.success:
            return stop("send", sent.reason)
        tell("send", f"{sent.waypoints} waypoints acknowledged")
        with _timed(timings, tell, "arrival"):
            records["arrival"] = arrival = await_arrival(
                client, drive.register_map, motion.q[-1], drive.arrival_timeout, started)
        if not arrival.success:
            return stop("arrival", arrival.reason)
        tell("arrival", "arrived")
    finally:
        client.close()
    with _timed(timings, tell, "final"):
        records["final"] = final = final_check(task, target.T_base_target, arrival.q_final,
                                               drive.register_map)
    tell("final", f"{final.position_error * 1e3:.3f} mm")
    return stop("" if final.success else "final", final.reason)
