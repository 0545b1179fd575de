"""The job's jerk-limited motion along a planned path, against the acceleration-limited
optimum along the same path and against ruckig through the same waypoints.

    python benchmarks/motion.py              # every example task
    python benchmarks/motion.py --rounds 5

For each task of examples/tasks, the job's own steps find the target, the IK solution and a
certified path from the task's start (no drive); then, within the robot's velocity,
acceleration and jerk limits (the task's speed fraction of them):

- armkit.retime_jerk along the spline the job's motion follows (the job's motion itself);
- armkit.retime, the time-optimal motion within velocity and acceleration limits alone, along
  the same spline: the duration no motion along that path can beat; its jerk is unbounded;
- ruckig (community version: no intermediate waypoints offline) through the same waypoints,
  twice: resting at every waypoint, each segment a time-optimal jerk-limited motion on the
  straight line (phase synchronisation: the certified segments themselves), and passing each
  waypoint with the velocity and acceleration armkit's motion has there (time
  synchronisation: each joint's own profile, which leaves the path between waypoints).

Per motion: duration (s) and its ratio to the acceleration-limited optimum, the peak |jerk| of
any joint as a fraction of its limit (the change of acceleration between 10 kHz samples, so an
acceleration step counts as the drive sees it), and the computing time, interleaved over rounds
(benchmarks/common.py), with the load average.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import ruckig

from armkit.io.tasks import load_task
from armkit.job.steps import (choose_solution, locate_target, motion_limits, plan_path,
                              smooth_motion)
from armkit.planning import CollisionChecker, arm_geometry
from armkit.trajectory import retime, retime_jerk
from common import interleaved, load

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "tasks"
RATE = 10_000            # Hz, the samples the peak jerk is read on


def planned(task):
    """The job's motion from the task's start (its steps before the drive)."""
    checker = CollisionChecker(task.robot, task.scene,
                               arm_geometry(task.robot, task.planner.radius),
                               resolution=task.planner.resolution)
    target = locate_target(task)
    choice = choose_solution(task, target.T_base_target, task.start, checker)
    path = plan_path(task, checker, task.start, choice.q_goal)
    motion = smooth_motion(task, path.path, checker)
    if not motion.success or motion.path is None:
        raise SystemExit(f"{task.name}: no motion along a spline ({motion.reason})")
    return motion


def ruckig_segment(q0, q1, v0, v1, a0, a1, V, A, J, sync) -> ruckig.Trajectory:
    """One ruckig motion from a state to a state."""
    n = len(q0)
    inp = ruckig.InputParameter(n)
    inp.current_position, inp.target_position = list(q0), list(q1)
    inp.current_velocity, inp.target_velocity = list(v0), list(v1)
    inp.current_acceleration, inp.target_acceleration = list(a0), list(a1)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(V), list(A), list(J)
    inp.synchronization = sync
    out = ruckig.Trajectory(n)
    result = ruckig.Ruckig(n).calculate(inp, out)
    if result != ruckig.Result.Working:
        raise SystemExit(f"ruckig: {result}")
    return out


def segments(motion, V, A, J, passing: bool) -> list[ruckig.Trajectory]:
    """ruckig through the motion's waypoints: resting at each (phase synchronisation), or
    passing each with armkit's velocity and acceleration there (time synchronisation)."""
    q = motion.q
    if passing:
        states = motion.trajectory.sample(motion.t)
        v, a = states.qd, states.qdd
        v[[0, -1]], a[[0, -1]] = 0.0, 0.0
        sync = ruckig.Synchronization.Time
    else:
        v, a = np.zeros_like(q), np.zeros_like(q)
        sync = ruckig.Synchronization.Phase
    return [ruckig_segment(q[k], q[k + 1], v[k], v[k + 1], a[k], a[k + 1], V, A, J, sync)
            for k in range(len(q) - 1)]


def ruckig_through(motion, V, A, J, passing: bool) -> tuple[float, np.ndarray]:
    """Duration (s) and peak |jerk| per joint (from the acceleration sampled at RATE, ruckig
    giving position, velocity and acceleration) of `segments`."""
    total, peak = 0.0, np.zeros(motion.q.shape[1])
    for out in segments(motion, V, A, J, passing):
        total += out.duration
        t = np.r_[np.arange(0.0, out.duration, 1.0 / RATE), out.duration]
        acc = np.array([out.at_time(ti)[2] for ti in t])     # one time per call
        if len(acc) > 1:
            peak = np.maximum(peak, np.abs(np.diff(acc, axis=0) * RATE).max(axis=0))
    return total, peak


def peak_jerk(trajectory) -> np.ndarray:
    """Peak |jerk| per joint as the change of acceleration between samples at RATE (so that
    an acceleration step counts, as it does for a drive), as for ruckig's motions."""
    s = trajectory.sample(np.r_[np.arange(0.0, trajectory.end, 1.0 / RATE), trajectory.end])
    return np.abs(np.diff(s.qdd, axis=0) * RATE).max(axis=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    rounds = parser.parse_args().rounds
    print(f"jerk-limited motion along the planned path; {load()}")
    print(f"{'task':24s} {'motion':34s} {'duration s':>10s} {'x optimum':>9s} "
          f"{'peak |j|/J':>10s}")
    for path in sorted(EXAMPLES.glob("*.task.yaml")):
        task = load_task(path)
        motion = planned(task)
        V, A, J = motion_limits(task)
        optimum = retime(motion.path, V, A)
        rows = [("armkit retime_jerk (the job's)", motion.trajectory.duration,
                 peak_jerk(motion.trajectory)),
                ("armkit retime (acceleration only)", optimum.duration,
                 peak_jerk(optimum.trajectory))]
        rows.append(("ruckig, rest at each waypoint", *ruckig_through(motion, V, A, J, False)))
        rows.append(("ruckig, passing each waypoint", *ruckig_through(motion, V, A, J, True)))
        for i, (name, duration, peak) in enumerate(rows):
            print(f"{path.name.split('.')[0] if i == 0 else '':24s} {name:34s} "
                  f"{duration:10.3f} {duration / optimum.duration:9.2f} "
                  f"{np.max(peak / J):10.2f}")
        times = interleaved({
            "retime_jerk": lambda: retime_jerk(motion.path, V, A, J),
            "retime": lambda: retime(motion.path, V, A),
            "ruckig": lambda: segments(motion, V, A, J, True)}, rounds=rounds)
        ours = times["retime_jerk"]
        print(f"{'':24s} computing: retime_jerk {ours.text('ms')}; retime "
              f"{times['retime'].text('ms')} ({ours.median / times['retime'].median:.1f}x "
              f"that); ruckig passing {times['ruckig'].text('ms')} "
              f"({ours.median / times['ruckig'].median:.0f}x that)")
    print(load())


if __name__ == "__main__":
    main()
