"""Inverse kinematics: armkit's closed forms and numeric solver against roboticstoolbox's C++
Levenberg-Marquardt (``ets.ik_LM``) and ikpy, on the same targets in the same run.

    python benchmarks/ik.py            # 1000 targets per robot, 3 rounds
    python benchmarks/ik.py --quick    # 200 targets, 2 rounds
    python benchmarks/ik.py --single   # one numeric target per call only

Targets: the FK of joint vectors drawn uniformly inside the limits (seed 0). Success is judged
by armkit's FK for every solver alike: position error < 1e-9 m, rotation error < 1e-9 rad
(under the task's mask), and within the joint limits. rtb runs at ``tol=1e-19`` (its tol bounds
half the squared error: about 4.5e-10, the accuracy judged here). Times, as min / median / max
over rounds (armkit and rtb interleaved round by round):

- "batch": one `IKSolver.solve` call for all targets, per target;
- "1 call": one `IKSolver.solve` per target (a held solver, as rtb's cached ``ets``), mean;
- "ik()": one `armkit.ik` per target (a solver derived per call), mean;
- the partial tasks (position, +yaw, +pitch, +axis) on the 6- and 7-joint arms: success and
  batch time;
- every closed-form solution (``--solutions`` runs only this part): 1000 UR5 and Puma 560
  targets in one `IKSolver.solutions` call, against one target per call (a held solver, and
  `armkit.ik_solutions`) and, on the Puma, roboticstoolbox's ``ikine_a`` for its 8
  configurations; interleaved rounds, median [min-max];
- one numeric target per call (``--single`` runs only this part): a held solver from nothing
  and from a start 0.05 rad off, and `armkit.ik`, against rtb's ``ik_LM``, interleaved
  rounds, median [min-max] of the mean per call.

The load average is printed before and after: the machine may be shared.
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
import warnings

import numpy as np
import roboticstoolbox as rtb
from ikpy.chain import Chain as IkpyChain
from ikpy.link import OriginLink, URDFLink

import armkit
from armkit.jit import set_mode
from armkit.kinematics.ik import IKSolver, ik
from armkit.kinematics.ik.masks import as_mask, task_errors
from armkit.spatial import matrix_to_rpy
from common import Spread, interleaved, load, ratio

ROBOTS = ["ur5", "puma560", "inspection_6dof", "stanford", "panda", "tool_changer_6dof"]
PARTIAL = ["position", "position+yaw", "position+pitch", "position+axis"]
TOL = 1e-9


def judge(robot, q, T, mask="pose") -> np.ndarray:
    """Success of solutions q (N, n) for targets T (N, 4, 4), by armkit's FK."""
    q = np.asarray(q, dtype=float)
    finite = np.isfinite(q).all(axis=1)
    q = np.where(finite[:, None], q, 0.0)
    pe, re = task_errors(armkit.fk(robot, q), T, as_mask(mask))
    inside = np.all((q >= robot.lower - 1e-12) & (q <= robot.upper + 1e-12), axis=1)
    return finite & (pe < TOL) & (re < TOL) & inside


def kernel_steps(robot):
    """The chain as (fixed transform, joint kind) pairs: pre, then a motion and a link each."""
    k = robot.chain.kernel
    fixed = [k.pre] + [k.links[i] for i in range(robot.n)]
    # Fold each joint's offset into the fixed transform before it (motions are about z).
    for i, off in enumerate(k.offsets):
        M = np.eye(4)
        if k.kinds[i] == 0:
            M[:2, :2] = [[np.cos(off), -np.sin(off)], [np.sin(off), np.cos(off)]]
        else:
            M[2, 3] = off
        fixed[i] = fixed[i] @ M
    return fixed, k.kinds


def rtb_ets(robot) -> rtb.ETS:
    fixed, kinds = kernel_steps(robot)
    ets = rtb.ETS(rtb.ET.SE3(fixed[0]))
    for i, kind in enumerate(kinds):
        motion = rtb.ET.Rz(jindex=i) if kind == 0 else rtb.ET.tz(jindex=i)
        ets *= motion * rtb.ET.SE3(fixed[i + 1])
    ets.qlim = np.vstack([robot.lower, robot.upper])
    return ets


def ikpy_chain(robot) -> IkpyChain:
    fixed, kinds = kernel_steps(robot)
    links = [OriginLink()]
    for i, kind in enumerate(kinds):
        links.append(URDFLink(f"j{i}", fixed[i][:3, 3], matrix_to_rpy(fixed[i][:3, :3]),
                              rotation=[0, 0, 1] if kind == 0 else None,
                              translation=None if kind == 0 else [0, 0, 1],
                              joint_type="revolute" if kind == 0 else "prismatic",
                              bounds=(robot.lower[i], robot.upper[i])))
    links.append(URDFLink("tool", fixed[-1][:3, 3], matrix_to_rpy(fixed[-1][:3, :3]),
                          joint_type="fixed"))
    mask = [False] + [True] * robot.n + [False]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return IkpyChain(links, active_links_mask=mask, jax_precompile=False)


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def spread(times, per: int = 1) -> str:
    """min / median / max of times (s) per item, in us."""
    t = np.asarray(times) / per * 1e6
    return f"{t.min():7.1f} / {np.median(t):7.1f} / {t.max():7.1f}"


def row(robot, solver, success, batch, one, wrapper, iterations):
    it = f"{np.mean(iterations):6.1f}" if iterations is not None else f"{'':>6}"
    print(f"| {robot} | {solver} | {100 * np.mean(success):.1f} % | {batch} | {one} | "
          f"{wrapper} | {it} |", flush=True)


def solutions(rounds: int) -> None:
    """Every closed-form solution: one batch call of 1000 targets against single calls (a held
    solver, and `armkit.ik_solutions`, which derives the solver per call), interleaved round by
    round; on the Puma 560 also against roboticstoolbox's analytic solver (``ikine_a``, one
    call per configuration: 8 per target), in the same rounds."""
    print(f"\nEvery closed-form solution, one target per call and 1000 in one call; median "
          f"[min-max] over {rounds} interleaved rounds, {load()}")
    for name in ("ur5", "puma560"):
        robot = armkit.robot(name)
        T = armkit.fk(robot, np.random.default_rng(2).uniform(robot.lower, robot.upper,
                                                              (1000, robot.n)))
        solver = IKSolver(robot)
        solver.solutions(T[:2])
        solver.solutions(T[0])
        single = 200
        cases = {"batch": lambda: solver.solutions(T),
                 "held": lambda: [solver.solutions(T[i]) for i in range(single)],
                 "ik_solutions": lambda: [armkit.ik_solutions(robot, T[i])
                                          for i in range(single)]}
        configs = ["".join(c) for c in itertools.product("lr", "ud", "nf")]
        if name == "puma560":
            puma = rtb.models.DH.Puma560()
            cases["rtb"] = lambda: [[puma.ikine_a(T[i], config=c) for c in configs]
                                    for i in range(20)]
        times = interleaved(cases, rounds)
        per = {"batch": 1000, "held": single, "ik_solutions": single, "rtb": 20}
        spread = {k: Spread(tuple(t / per[k] for t in v.times)) for k, v in times.items()}
        sols = solver.solutions(T)
        print(f"  {name}: {sols.count.sum()} solutions of 1000 targets, "
              f"{sols.count.min()}-{sols.count.max()} per target")
        print(f"    one call, 1000 targets, per target   {spread['batch'].text()}")
        print(f"    IKSolver.solutions, one target       {spread['held'].text()}   "
              f"(batch faster per target: {ratio(spread['held'], spread['batch'])})")
        print(f"    armkit.ik_solutions, one target      {spread['ik_solutions'].text()}")
        if "rtb" in spread:
            print(f"    rtb ikine_a x 8 configurations       {spread['rtb'].text()}   "
                  f"(rtb / held solver: {ratio(spread['rtb'], spread['held'])}; rtb / "
                  f"ik_solutions: {ratio(spread['rtb'], spread['ik_solutions'])})")


def single(rounds: int) -> None:
    """One numeric target per call (Levenberg-Marquardt, 6-DOF arms, reachable targets): a
    held `IKSolver` from no q0 (its seed bank built before timing) and from a q0 0.05 rad off
    the target's joint values, `armkit.ik` (a solver derived per call, no bank), and rtb's
    ``ik_LM`` on a cached ``ets``; interleaved round by round, 100 targets per round."""
    print(f"\nOne numeric target per call, mean us per call over 100 targets; median [min-max] "
          f"over {rounds} interleaved rounds, {load()}")
    print("| robot | held solver, no q0 | held solver, q0 0.05 rad off | `armkit.ik` | rtb "
          "`ik_LM` | rtb / held solver |")
    print("|---|---|---|---|---|---|")
    for name in ("tool_changer_6dof", "ur5", "inspection_6dof"):
        robot = armkit.robot(name)
        Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (100, robot.n))
        T = armkit.fk(robot, Q)
        near = np.clip(Q + 0.05, robot.lower, robot.upper)
        ets = rtb_ets(robot)
        solver = IKSolver(robot)
        solver.solve(T[0], method="lm")
        solver.solve(T[0], near[0], method="lm")
        ik(robot, T[0], method="lm")
        times = interleaved({
            "held": lambda: [solver.solve(T[i], method="lm") for i in range(100)],
            "near": lambda: [solver.solve(T[i], near[i], method="lm") for i in range(100)],
            "ik": lambda: [ik(robot, T[i], method="lm") for i in range(100)],
            "rtb": lambda: [ets.ik_LM(T[i], tol=1e-19, joint_limits=True) for i in range(100)]},
            rounds)
        per = {k: Spread(tuple(t / 100 for t in v.times)) for k, v in times.items()}
        print(f"| {name} | {per['held'].text()} | {per['near'].text()} | {per['ik'].text()} | "
              f"{per['rtb'].text()} | {ratio(per['rtb'], per['held'])} |", flush=True)
    print(load())


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="200 targets, 2 rounds")
    parser.add_argument("--solutions", action="store_true",
                        help="only every closed-form solution (the last section)")
    parser.add_argument("--single", action="store_true",
                        help="only one numeric target per call")
    parser.add_argument("--rounds", type=int, default=None, help="rounds (default 3, quick 2)")
    args = parser.parse_args()
    n_targets, n_single, n_ikpy, rounds = (200, 50, 10, 2) if args.quick else (1000, 200, 30, 3)
    rounds = args.rounds or rounds
    if args.solutions:
        solutions(rounds)
        return
    if args.single:
        single(rounds)
        return
    print(f"load average before: {os.getloadavg()}")
    print("| robot | solver | success | batch us/target min/med/max | 1 call us | ik() us | "
          "iterations |")
    print("|---|---|---|---|---|---|---|")
    for name in ROBOTS:
        robot = armkit.robot(name)
        Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (n_targets, robot.n))
        T = armkit.fk(robot, Q)
        ets = rtb_ets(robot)
        assert np.abs(ets.eval(Q[:50]) - T[:50]).max() < 1e-12
        warm = IKSolver(robot)
        methods = (["auto"] if warm.family else []) + ["lm"]
        for method in methods:
            warm.solve(T[:3], method=method)
            warm.solve(T[0], method=method)
            batch, one, wrapper, rtb_one = [], [], [], []
            for _ in range(rounds):
                solver = IKSolver(robot)
                result, dt = timed(lambda: solver.solve(T, method=method))
                batch.append(dt)
                _, dt = timed(lambda: [solver.solve(T[i], method=method)
                                       for i in range(n_single)])
                one.append(dt)
                _, dt = timed(lambda: [ik(robot, T[i], method=method) for i in range(n_single)])
                wrapper.append(dt)
                if method == methods[-1]:       # the reference, interleaved
                    sols, dt = timed(lambda: [ets.ik_LM(T[i], tol=1e-19, joint_limits=True)
                                              for i in range(n_single)])
                    rtb_one.append(dt)
            label = ("armkit closed form " + result.method[0].removeprefix("analytic:")
                     if method == "auto" else "armkit Levenberg-Marquardt")
            row(name, label, judge(robot, result.q, T), spread(batch, n_targets),
                spread(one, n_single), spread(wrapper, n_single), result.iterations)
        rtb_q = [ets.ik_LM(T[i], tol=1e-19, joint_limits=True) for i in range(n_targets)]
        row(name, "rtb `ik_LM` tol=1e-19", judge(robot, [s.q for s in rtb_q], T), "", 
            spread(rtb_one, n_single), "", [s.iterations for s in rtb_q])
        chain = ikpy_chain(robot)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            q, dt = timed(lambda: [chain.inverse_kinematics_frame(T[i])[1:-1]
                                   for i in range(n_ikpy)])
        row(name, f"ikpy ({n_ikpy} targets)", judge(robot, q, T[:n_ikpy]), "",
            spread([dt], n_ikpy), "", None)
    print(f"\nPartial tasks (position + ...): success at {TOL:g}, batch us per target "
          f"(min / median / max of {rounds})")
    print("| robot | " + " | ".join(PARTIAL) + " |")
    print("|---|" + "---|" * len(PARTIAL))
    for name in ROBOTS:
        robot = armkit.robot(name)
        Q = np.random.default_rng(1).uniform(robot.lower, robot.upper, (n_targets, robot.n))
        T = armkit.fk(robot, Q)
        solver = IKSolver(robot)
        cells = []
        for mask in PARTIAL:
            times = []
            for _ in range(rounds):
                result, dt = timed(lambda: solver.solve(T, mask=mask))
                times.append(dt)
            ok = judge(robot, result.q, T, mask)
            cells.append(f"{100 * ok.mean():.1f} %, {spread(times, n_targets)}")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    solutions(rounds)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
