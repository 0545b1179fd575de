"""Inverse kinematics: armkit's closed forms and numeric solver against roboticstoolbox's C++
Levenberg-Marquardt (``ets.ik_LM``) and ikpy, on the same targets in the same run.

    python benchmarks/ik.py            # 1000 targets per robot
    python benchmarks/ik.py --quick    # 200 targets, fewer single calls

Targets: the FK of joint vectors drawn uniformly inside the limits (seed 0). Success is judged
by armkit's FK for every solver alike: position error < 1e-9 m, rotation error < 1e-9 rad, and
within the joint limits. rtb runs at ``tol=1e-13`` (its tol bounds half the squared error, so
its default 1e-6 only promises about 1e-3, and 1e-13 about 4.5e-7) and at ``tol=1e-19``
(about 4.5e-10, the accuracy judged here). Times: mean per target of a batch call (armkit only;
the references have no batch call): "first" with the seed bank still to build (see
`armkit.kinematics.ik.numeric`), "batch" the best of five calls after; and mean and median of
one call per target.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
import roboticstoolbox as rtb
from ikpy.chain import Chain as IkpyChain
from ikpy.link import OriginLink, URDFLink

import armkit
from armkit.kinematics.ik import analytic, ik, numeric
from armkit.kinematics.ik.task import as_mask, task_errors
from armkit.spatial import matrix_to_rpy

ROBOTS = ["ur5", "puma560", "inspection_6dof", "panda", "tool_changer_6dof"]
TOL = 1e-9


def judge(robot, q, T) -> np.ndarray:
    """Success of solutions q (N, n) for targets T (N, 4, 4), by armkit's FK."""
    q = np.asarray(q, dtype=float)
    finite = np.isfinite(q).all(axis=1)
    q = np.where(finite[:, None], q, 0.0)
    pe, re = task_errors(armkit.fk(robot, q), T, as_mask("pose"))
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


def singles(solve, T, count):
    """Solve the first `count` targets one call each: (q, times in s, iterations or None)."""
    qs, times, its = [], [], []
    for Ti in T[:count]:
        t = time.perf_counter()
        q, it = solve(Ti)
        times.append(time.perf_counter() - t)
        qs.append(q)
        its.append(it)
    return np.array(qs), np.array(times), its


def report(robot_name, solver, ok, first, batch, single, iterations):
    it = f"{np.mean(iterations):8.1f}" if iterations is not None else f"{'n/a':>8}"
    first, batch = (f"{t * 1e6:9.1f}" if t is not None else f"{'-':>9}" for t in (first, batch))
    print(f"{robot_name:18} {solver:22} {100 * ok.mean():7.2f}% {first} {batch} "
          f"{np.mean(single) * 1e6:9.1f} {np.median(single) * 1e6:9.1f} {it}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="200 targets, fewer single calls")
    args = parser.parse_args()
    n_targets, n_single, n_ikpy = (200, 50, 20) if args.quick else (1000, 200, 50)
    print(f"{'robot':18} {'solver':22} {'success':>8} {'first us':>9} {'batch us':>9} "
          f"{'1-call us':>9} {'median':>9} {'iters':>8}")
    for name in ROBOTS:
        robot = armkit.robot(name)
        Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (n_targets, robot.n))
        T = armkit.fk(robot, Q)
        ets, chain = rtb_ets(robot), ikpy_chain(robot)
        assert np.abs(ets.eval(Q[:50]) - T[:50]).max() < 1e-12
        assert np.abs(chain.forward_kinematics(np.r_[0, Q[0], 0]) - T[0]).max() < 1e-9
        methods = (["auto"] if analytic.family_of(robot.chain) else []) + ["lm"]
        for method in methods:
            ik(robot, T, method=method)                                # compile / warm up
            numeric._bank.cache_clear()
            t = time.perf_counter()
            ik(robot, T, method=method)
            first = time.perf_counter() - t
            best = np.inf
            for _ in range(5):
                t = time.perf_counter()
                result = ik(robot, T, method=method)
                best = min(best, time.perf_counter() - t)
            single = singles(lambda Ti: (ik(robot, Ti, method=method).q, 0), T, n_single)[1]
            label = f"armkit {result.method[0].removeprefix('analytic:')}"
            report(name, label, judge(robot, result.q, T), first / n_targets, best / n_targets,
                   single, result.iterations)
        for tol in (1e-13, 1e-19):
            solve = lambda Ti: (lambda s: (s.q, s.iterations))(              # noqa: E731
                ets.ik_LM(Ti, tol=tol, joint_limits=True))
            q, times, its = singles(solve, T, n_targets)
            report(name, f"rtb ik_LM tol={tol:.0e}", judge(robot, q, T), None, None, times, its)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            q, times, _ = singles(lambda Ti: (chain.inverse_kinematics_frame(Ti)[1:-1], None),
                                  T, n_ikpy)
        report(name, f"ikpy ({n_ikpy} targets)", judge(robot, q, T[:n_ikpy]), None, None, times,
               None)


if __name__ == "__main__":
    main()
