"""Dynamics speed: armkit against Pinocchio, roboticstoolbox-python and toppra.

    python benchmarks/dynamics.py            # every case
    python benchmarks/dynamics.py --quick    # fewer rounds, a batch of 1e5
    python benchmarks/dynamics.py --cpu      # CPU time (a loaded machine's waits left out)
    python benchmarks/dynamics.py --threads 2   # the batch on two threads

1. one call from Python, warm: `inverse_dynamics`, `mass_matrix`, `forward_dynamics` against
   Pinocchio's ``rnea``, ``crba``, ``aba`` on the same URDF (example-robot-data's UR5, 6
   joints, and Panda to its hand, 7 joints), and against roboticstoolbox-python's C ``rne`` on
   its DH Puma 560 (armkit's built-in puma560, the same numbers);
2. a batch of 1e6 configurations (UR5): `inverse_dynamics` and `mass_matrix` per
   configuration, on the threads the machine's idle cores allow, against Pinocchio called in
   a Python loop (1e4 configurations, per configuration);
3. torque-limited retiming of a UR5 path through 10 waypoints (velocity, acceleration and
   torque limits): `retime(..., torque=TorqueLimits(...))` against toppra with the same
   three constraints on the same spline and grid, with both durations and each result's
   largest torque over its limit on 10,000 samples in time.

Every figure is min-median-max over rounds in which armkit and its reference take turns
(benchmarks/common.py); every ratio is reference time / armkit time (above 1: armkit
faster). The load average is printed before and after.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.metadata
import logging
import time

import numpy as np
import pinocchio as pin
import roboticstoolbox as rtb
import toppra
import toppra.algorithm
import toppra.constraint

import armkit
from armkit.dynamics import (TorqueLimits, forward_dynamics, inverse_dynamics, mass_matrix,
                             torque_profile)
from armkit.jit import set_mode
from armkit.trajectory import retime, waypoint_path
from common import interleaved, load, ratio

logging.getLogger("toppra").setLevel(logging.ERROR)


def urdf(suffix: str) -> str:
    """The installed example-robot-data file whose path ends with `suffix`."""
    dist = importlib.metadata.distribution("example-robot-data")
    return str(dist.locate_file(next(f for f in dist.files if str(f).endswith(suffix))))


def row(name: str, case: str, ours, ref_name: str, ref, unit: str = "us") -> None:
    print(f"{name:12} {case:28} {ours.text(unit):>24} {ref_name:>10} {ref.text(unit):>22} "
          f"{ratio(ref, ours):>20}")


def single_calls(rounds: int, clock) -> None:
    rng = np.random.default_rng(0)
    for name, suffix, tip in (("ur5", "ur_description/urdf/ur5_robot.urdf", "tool0"),
                              ("panda", "panda_description/urdf/panda.urdf", "panda_hand")):
        path = urdf(suffix)
        loaded = armkit.load_robot(path, tip=tip)
        # Pinocchio's algorithms have no joint friction (the Panda's URDF gives some).
        robot = dataclasses.replace(loaded, inertia=dataclasses.replace(
            loaded.inertia, viscous=None, coulomb=None))
        full = pin.buildModelFromUrdf(path)
        keep = [full.getJointId(j.name) for j in robot.chain.joints]
        for j in range(1, full.njoints):        # the fingers are off armkit's chain
            if j not in keep:
                full.inertias[j] = pin.Inertia.Zero()
        model = pin.buildReducedModel(full, [j for j in range(1, full.njoints)
                                             if j not in keep], pin.neutral(full))
        model.gravity.linear[:] = robot.inertia.gravity
        data = model.createData()
        q, qd, qdd = rng.uniform(-1, 1, (3, robot.n))
        tau = inverse_dynamics(robot, q, qd, qdd)
        assert np.abs(tau - pin.rnea(model, data, q, qd, qdd)).max() < 1e-10
        assert np.abs(forward_dynamics(robot, q, qd, tau) - qdd).max() < 1e-9
        times = interleaved({
            "rnea": lambda: inverse_dynamics(robot, q, qd, qdd),
            "pin rnea": lambda: pin.rnea(model, data, q, qd, qdd),
            "crba": lambda: mass_matrix(robot, q),
            "pin crba": lambda: pin.crba(model, data, q),
            "fd": lambda: forward_dynamics(robot, q, qd, tau),
            "pin aba": lambda: pin.aba(model, data, q, qd, tau)}, rounds, number=5000,
            clock=clock)
        label = f"{name} ({robot.n})"
        row(label, "inverse dynamics", times["rnea"], "pin rnea", times["pin rnea"])
        row(label, "mass matrix", times["crba"], "pin crba", times["pin crba"])
        row(label, "forward dynamics", times["fd"], "pin aba", times["pin aba"])
    puma = armkit.robot("puma560")
    ref = rtb.models.DH.Puma560().nofriction(coulomb=True, viscous=True)
    q, qd, qdd = rng.uniform(-1, 1, (3, 6))
    assert np.abs(inverse_dynamics(puma, q, qd, qdd)
                  - ref.rne(q, qd, qdd, gravity=[0, 0, -9.80665])).max() < 1e-4
    times = interleaved({"rnea": lambda: inverse_dynamics(puma, q, qd, qdd),
                         "rtb rne": lambda: ref.rne(q, qd, qdd, gravity=[0, 0, -9.80665])},
                        rounds, number=2000, clock=clock)
    row("puma560 (6)", "inverse dynamics", times["rnea"], "rtb rne", times["rtb rne"])


def batch(size: int, rounds: int, clock) -> None:
    robot = armkit.load_robot(urdf("ur_description/urdf/ur5_robot.urdf"), tip="tool0")
    model = pin.buildModelFromUrdf(urdf("ur_description/urdf/ur5_robot.urdf"))
    model.gravity.linear[:] = robot.inertia.gravity
    data = model.createData()
    rng = np.random.default_rng(1)
    Q, QD, QDD = rng.uniform(-2, 2, (3, size, 6))
    inverse_dynamics(robot, Q[:5000], QD[:5000], QDD[:5000])     # the parallel kernels warm
    mass_matrix(robot, Q[:5000])
    few = 10_000

    def pin_rnea():
        for k in range(few):
            pin.rnea(model, data, Q[k], QD[k], QDD[k])

    def pin_crba():
        for k in range(few):
            pin.crba(model, data, Q[k])

    times = interleaved({"rnea": lambda: inverse_dynamics(robot, Q, QD, QDD),
                         "pin rnea": pin_rnea,
                         "crba": lambda: mass_matrix(robot, Q), "pin crba": pin_crba}, rounds,
                        clock=clock)
    per = {k: type(v)(tuple(t / (size if k in ("rnea", "crba") else few) for t in v.times))
           for k, v in times.items()}
    threads = armkit.get_num_threads()
    row("ur5", f"ID per config, N={size:.0e}", per["rnea"], "pin loop", per["pin rnea"], "ns")
    row("ur5", f"M per config, N={size:.0e}", per["crba"], "pin loop", per["pin crba"], "ns")
    what = ("CPU time of all threads: on idle cores the wall time is this over the threads"
            if clock is time.process_time else "wall time")
    print(f"{'':12} (armkit's batch on up to {threads} threads, {what}; Pinocchio one call "
          f"per configuration from Python)")


def toppra_retime(robot, path, waypoints, vmax, amax, tau_max, grid):
    spline = toppra.SplineInterpolator(path.knots, waypoints, bc_type="natural")

    def inv_dyn(q, qd, qdd):
        return inverse_dynamics(robot, q, qd, qdd)

    interpolation = toppra.constraint.DiscretizationType.Interpolation
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
        toppra.constraint.JointAccelerationConstraint(np.c_[-amax, amax], interpolation),
        toppra.constraint.JointTorqueConstraint(inv_dyn, np.c_[-tau_max, tau_max],
                                                np.zeros(robot.n), interpolation)]
    algorithm = toppra.algorithm.TOPPRA(constraints, spline, gridpoints=np.linspace(
        0, path.end, grid + 1), parametrizer="ParametrizeConstAccel")
    return algorithm.compute_trajectory()


def retiming(rounds: int, clock) -> None:
    robot = armkit.robot("ur5")
    waypoints = np.random.default_rng(0).uniform(-2, 2, (10, 6))
    vmax, amax = robot.velocity_limits, np.full(6, 20.0)
    tau_max = np.array([60.0, 60.0, 25.0, 10.0, 10.0, 10.0])
    path = waypoint_path(waypoints)
    limits = TorqueLimits(robot, tau_max)
    grid = 1000
    ours = retime(path, vmax, amax, torque=limits, grid=grid)
    theirs = toppra_retime(robot, path, waypoints, vmax, amax, tau_max, grid)
    times = interleaved({"armkit": lambda: retime(path, vmax, amax, torque=limits, grid=grid),
                         "toppra": lambda: toppra_retime(robot, path, waypoints, vmax, amax,
                                                         tau_max, grid)}, rounds,
                        clock=clock)
    row("ur5", "torque-limited retime, 10 wp", times["armkit"], "toppra", times["toppra"],
        "ms")
    t = np.linspace(0, theirs.duration, 10_000)
    toppra_tau = inverse_dynamics(robot, theirs(t), theirs(t, 1), theirs(t, 2))
    ours_peak = torque_profile(robot, ours.trajectory, limits=tau_max).ratio.max()
    print(f"{'':12} durations: armkit {ours.duration:.4f} s, toppra {theirs.duration:.4f} s "
          f"(grid {grid}); largest torque / limit on 10,000 samples: armkit {ours_peak:.6f}, "
          f"toppra {np.max(np.abs(toppra_tau) / tau_max):.4f}")


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer rounds, a batch of 1e5")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--cpu", action="store_true",
                        help="CPU time instead of wall time: this thread's for single calls "
                             "and retiming, the process's (all threads) for the batch")
    parser.add_argument("--threads", type=int, default=None,
                        help="threads for the batch (default: as many as the idle cores)")
    args = parser.parse_args()
    rounds = 3 if args.quick else args.rounds
    armkit.set_num_threads(args.threads)
    print(load())
    print(f"{'robot':12} {'case':28} {'armkit':>24} {'reference':>33} {'ratio':>20}")
    single_calls(rounds, time.thread_time if args.cpu else time.perf_counter)
    batch(100_000 if args.quick else 1_000_000, rounds,
          time.process_time if args.cpu else time.perf_counter)
    retiming(rounds, time.thread_time if args.cpu else time.perf_counter)
    print(load())


if __name__ == "__main__":
    main()
