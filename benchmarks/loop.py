"""Single calls in a loop, each capability in a fresh process: the latency of every call.

    python benchmarks/loop.py                    # warm and empty numba cache, 2000 calls
    python benchmarks/loop.py --cache warm --calls 500 --cases fk,ik

A user's loop of single calls (a control loop, a script over targets) starts in a fresh
process. Each case runs there: `--calls` calls, each on its own input, timed one by one with
the wall clock; then the loop goes on until armkit's background compiler is idle (at most
`--until` s), and the compiled steady state is timed over `--calls` more calls. The table
gives the median per-call time in windows of calls (1-10, 11-100, 101-1000, 1001-2000), the
worst single call after the first, the first call, when the background thread had compiled
everything the loop uses (s after the first call), the steady state and the ratio of calls
101-2000 to it, and a reference library's call on the same inputs measured in the same
process: pinocchio (fk, jacobian), roboticstoolbox's C++ Levenberg-Marquardt on a held ``ets``
(ik, against a held `IKSolver`'s `solve`; ik_solutions is its `solutions`), ruckig
(jerk_limited). A warm cache is armkit's own cache in __pycache__ (run `armkit warm-up` first);
an empty one is a new NUMBA_CACHE_DIR, so the background thread compiles from nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

CASES = ("fk", "jacobian", "ik", "ik_solutions", "jerk_limited", "plan")
WINDOWS = ((1, 10), (11, 100), (101, 1000), (1001, 2000))


def inputs(case: str, calls: int):
    """The robot-side callables: (armkit call of input i, reference call of input i or None)."""
    import armkit

    rng = np.random.default_rng(0)
    if case in ("fk", "jacobian"):
        import pinocchio as pin
        from fk import pinocchio_model

        robot = armkit.robot("ur5")
        Q = rng.uniform(*robot.chain.sampling_limits, (calls, robot.n))
        model, data, frame = pinocchio_model(robot)
        P = Q + robot.chain.kernel.offsets

        if case == "fk":
            def reference(i):
                pin.forwardKinematics(model, data, P[i])
                return pin.updateFramePlacement(model, data, frame)
            return (lambda i: armkit.fk(robot, Q[i])), reference
        return ((lambda i: armkit.jacobian(robot, Q[i])),
                lambda i: pin.computeFrameJacobian(model, data, P[i], frame,
                                                   pin.LOCAL_WORLD_ALIGNED))
    if case in ("ik", "ik_solutions"):
        from ik import rtb_ets

        robot = armkit.robot("ur5")
        Q = rng.uniform(*robot.chain.sampling_limits, (calls, robot.n))
        T = armkit.fk(robot, Q)
        Q0 = Q + rng.uniform(-0.05, 0.05, Q.shape)      # near the answer, as a loop is
        solver = armkit.IKSolver(robot)             # held, as the README says for loops
        if case == "ik_solutions":
            return (lambda i: solver.solutions(T[i])), None
        ets = rtb_ets(robot)
        return ((lambda i: solver.solve(T[i], Q0[i])),
                lambda i: ets.ik_LM(T[i], q0=Q0[i], tol=1e-13, joint_limits=True))
    if case == "jerk_limited":
        import ruckig

        q0, q1 = rng.uniform(-2, 2, (calls, 6)), rng.uniform(-2, 2, (calls, 6))
        vmax, amax, jmax = np.full(6, 1.5), np.full(6, 3.0), np.full(6, 30.0)
        otg, inp, out = ruckig.Ruckig(6), ruckig.InputParameter(6), ruckig.Trajectory(6)
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = (vmax.tolist(), amax.tolist(),
                                                                jmax.tolist())
        starts, goals = q0.tolist(), q1.tolist()

        def reference(i):
            inp.current_position, inp.target_position = starts[i], goals[i]
            return otg.calculate(inp, out)
        return (lambda i: armkit.jerk_limited(q0[i], q1[i], vmax, amax, jmax)), reference
    if case == "plan":
        from armkit.planning import CollisionChecker, plan
        sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
        from tests.planning.scenes import SHELF_GOAL, SHELF_START, shelf

        checker = CollisionChecker(armkit.robot("inspection_6dof"), shelf())
        return (lambda i: plan(checker, SHELF_START, SHELF_GOAL, seed=i, waypoints=10)), None
    raise ValueError(case)


def child(case: str, calls: int, until: float) -> None:
    """Run one case in this fresh process; print its latencies as JSON."""
    from armkit import jit

    ours, reference = inputs(case, calls)
    clock = time.perf_counter
    latencies, start = [], clock()
    compiled_at = None
    i = 0
    while i < calls or (jit._compiler.busy.is_set() and clock() - start < until):
        t = clock()
        ours(i % calls)
        latencies.append(clock() - t)
        if compiled_at is None and jit._compiler.started and not jit._compiler.busy.is_set():
            compiled_at = clock() - start
        i += 1
    jit.wait_for_background()
    steady, ref = [], []
    for k in range(calls):
        t = clock()
        ours(k)
        steady.append(clock() - t)
        if reference is not None:
            t = clock()
            reference(k)
            ref.append(clock() - t)
    print(json.dumps({"latencies": latencies[:calls], "loop_seconds": clock() - start,
                      "compiled_at": compiled_at, "steady": steady, "reference": ref}))


def run(case: str, calls: int, until: float, cache: str) -> dict:
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as folder:
        if cache == "empty":
            env["NUMBA_CACHE_DIR"] = folder
        result = subprocess.run([sys.executable, __file__, "--child", case, "--calls",
                                 str(calls), "--until", str(until)], capture_output=True,
                                text=True, env=env, cwd=os.path.dirname(__file__))
    if result.returncode != 0:
        raise SystemExit(f"{case}: {result.stderr[-2000:]}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--until", type=float, default=90.0,
                        help="s the loop may go on for the background compiler")
    parser.add_argument("--cache", choices=("warm", "empty", "both"), default="both")
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--child")
    args = parser.parse_args()
    if args.child:
        child(args.child, args.calls, args.until)
        return
    caches = ("warm", "empty") if args.cache == "both" else (args.cache,)
    print(f"{args.calls} single calls per fresh process; load {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores; times in us unless marked")
    header = ("case", "cache", *(f"{a}-{b}" for a, b in WINDOWS), "worst (ms)", "first (ms)",
              "compiled at (s)", "steady", "101+/steady", "reference")
    print(" | ".join(header))
    for cache in caches:
        for case in args.cases.split(","):
            found = run(case, args.calls, args.until, cache)
            lat = np.array(found["latencies"]) * 1e6
            steady = float(np.median(found["steady"])) * 1e6
            cells = [case, cache]
            for a, b in WINDOWS:
                window = lat[a - 1:b]
                cells.append(f"{np.median(window):.1f}" if window.size else "-")
            cells.append(f"{lat[1:].max() / 1e3:.1f} (call {int(lat[1:].argmax()) + 2})")
            cells.append(f"{lat[0] / 1e3:.1f}")
            at = found["compiled_at"]
            cells.append("-" if at is None else f"{at:.1f}")
            cells.append(f"{steady:.2f}")
            cells.append(f"{np.median(lat[100:]) / steady:.2f}x" if lat.size > 100 else "-")
            ref = found["reference"]
            cells.append(f"{np.median(ref) * 1e6:.2f}" if ref else "-")
            print(" | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
