"""The end-to-end job of SPEC.md section 8: paper 1's system, for any arm.

A camera sees a target; the job maps it to the arm's base frame, reads where the arm is from its
drive, finds every inverse-kinematics solution and takes the collision-free one nearest the arm,
plans a collision-free path there, times a jerk-limited motion along it (certified again:
smoothing must not cut a corner through an obstacle), checks the motion against every limit,
sends N waypoints of it to the drive over Modbus TCP, waits until the drive reports arrival, and
compares the tool's position at the drive's final joint values (forward kinematics) with the
target.

`run_job` is a line of steps (`armkit.job.steps`), each from frozen inputs to a frozen record;
the job's `JobResult` is the record of them. The task comes from a task file
(`armkit.io.tasks.load_task`) or is built in code (`armkit.io.tasks.Task`). With no drive in
the task, the built-in simulated drive (a real Modbus TCP server) runs on an ephemeral loopback
port for the length of the job.

The names are loaded on first use (PEP 562).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.job.run import STEPS, JobResult, run_job
    from armkit.job.steps import (ArmState, Arrival, FinalCheck, IKChoice, Motion,
                                  MotionChecks, Sent, TargetStep)

__getattr__, __dir__, __all__ = lazy_names(__name__)

