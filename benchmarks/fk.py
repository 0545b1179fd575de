"""Forward kinematics speed: armkit against pinocchio, roboticstoolbox-python and NumPy.

    python benchmarks/fk.py            # N = 1e5 and 1e6, threads, memory at 1e7 and 2e7
    python benchmarks/fk.py --quick    # N = 1e5 only, no memory runs
    python benchmarks/fk.py --single   # one configuration per call only

Per call: one configuration from Python, `armkit.fk` and `armkit.jacobian` against pinocchio
(``forwardKinematics`` + ``updateFramePlacement`` of the tool frame, and
``computeFrameJacobian`` in LOCAL_WORLD_ALIGNED, the same rows as armkit's base-frame
Jacobian) on the same chain, and rtb's compiled ``ets.eval(q)``. Batch: ``armkit.fk(robot, Q)``
vs ``ets.eval(Q)`` on the same (N, 6) array, and vs a vectorised NumPy einsum over the DH
matrices; then armkit's batch on one thread and on two. Each figure is min-median-max over
interleaved rounds (benchmarks/common.py), each ratio reference time / armkit time with the
range of the per-round ratios, with the load average of the run. Also: the memory that fk of
1e7 and `manipulability` of 2e7 configurations take beyond their input and output (fresh
processes). The first call's cost is in benchmarks/startup.py.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

import numpy as np
import pinocchio as pin
import roboticstoolbox as rtb

import armkit
from armkit.jit import set_mode
from common import interleaved, load, numpy_chain, ratio


def pinocchio_model(robot: armkit.Robot):
    """The robot's chain as a pinocchio model: joint i about (or along) z after the placement
    of the kernel form (``pre``, then ``links``), the tool a frame on the last joint."""
    k = robot.chain.kernel
    model, parent = pin.Model(), 0
    for i in range(robot.n):
        placement = k.pre if i == 0 else k.links[i - 1]
        joint = pin.JointModelRZ() if k.kinds[i] == 0 else pin.JointModelPZ()
        parent = model.addJoint(parent, joint, pin.SE3(placement[:3, :3].copy(),
                                                       placement[:3, 3].copy()), f"joint{i}")
    tool = pin.SE3(k.links[-1][:3, :3].copy(), k.links[-1][:3, 3].copy())
    frame = model.addFrame(pin.Frame("tool", parent, 0, tool, pin.FrameType.OP_FRAME))
    return model, model.createData(), frame


def rtb_model(robot: armkit.Robot) -> rtb.DHRobot:
    links = [rtb.RevoluteDH(a=r.a, alpha=r.alpha, d=r.d, offset=r.theta)
             for r in robot.table.rows]
    return rtb.DHRobot(links, base=robot.table.T_base, tool=robot.table.T_tool)


def memory_at(n: int, call: str) -> tuple[float, float, float]:
    """(seconds, output GB, peak GB beyond input and output) of ``armkit.<call>(robot, Q)`` for
    n configurations, in a fresh process, so that no earlier high-water mark hides the call's
    temporaries."""
    code = f"""
import resource, time, numpy as np, armkit
robot = armkit.robot("ur5")
Q = np.random.default_rng(0).uniform(-np.pi, np.pi, ({n}, 6))
armkit.{call}(robot, Q[:10])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
t = time.perf_counter()
out = armkit.{call}(robot, Q)
seconds = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
print(seconds, out.nbytes / 2**30, peak - before - out.nbytes / 2**30)
"""
    done = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    seconds, out, extra = map(float, done.stdout.split())
    return seconds, out, max(0.0, extra)


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 1e5 only, no memory runs")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--single", action="store_true",
                        help="one configuration per call only (no batch, threads or memory)")
    args = parser.parse_args()
    sizes = [100_000] if args.quick else [100_000, 1_000_000]
    rounds = args.rounds
    rng = np.random.default_rng(0)
    print(load())
    print(f"{'robot':16} {'case':22} {'armkit':>26} {'reference':>34} {'ratio':>22}")

    def row(name, case, ours, ref_name, ref, unit="us"):
        print(f"{name:16} {case:22} {ours.text(unit):>26} {ref_name:>12} {ref.text(unit):>21} "
              f"{ratio(ref, ours):>22}")

    for name in ("ur5", "inspection_6dof"):
        robot = armkit.robot(name)
        ets = rtb_model(robot).ets()
        numpy_fk = numpy_chain(robot.table)
        model, data, frame = pinocchio_model(robot)
        offsets = robot.chain.kernel.offsets
        q = rng.uniform(robot.lower, robot.upper)
        qp = q + offsets                                # pinocchio's joint values
        check = rng.uniform(robot.lower, robot.upper, (1000, robot.n))
        assert np.abs(armkit.fk(robot, check) - ets.eval(check)).max() < 1e-12
        assert np.abs(armkit.fk(robot, check) - numpy_fk(check)).max() < 1e-12
        pin.forwardKinematics(model, data, qp)
        pin.updateFramePlacement(model, data, frame)
        assert np.abs(data.oMf[frame].homogeneous - armkit.fk(robot, q)).max() < 1e-12
        J = pin.computeFrameJacobian(model, data, qp, frame, pin.LOCAL_WORLD_ALIGNED)
        assert np.abs(J - armkit.jacobian(robot, q)).max() < 1e-12

        def pin_fk():
            pin.forwardKinematics(model, data, qp)
            pin.updateFramePlacement(model, data, frame)

        one = interleaved({
            "fk": lambda: armkit.fk(robot, q), "pin": pin_fk, "rtb": lambda: ets.eval(q),
            "jac": lambda: armkit.jacobian(robot, q),
            "pin jac": lambda: pin.computeFrameJacobian(model, data, qp, frame,
                                                        pin.LOCAL_WORLD_ALIGNED),
            "numpy": lambda: numpy_fk(q[None])}, rounds, number=2000)
        row(name, "one fk", one["fk"], "pinocchio", one["pin"])
        row("", "one fk", one["fk"], "rtb", one["rtb"])
        row("", "one fk", one["fk"], "numpy", one["numpy"])
        row("", "one jacobian", one["jac"], "pinocchio", one["pin jac"])
        if args.single:
            continue
        for n in sizes:
            Q = rng.uniform(robot.lower, robot.upper, (n, robot.n))
            batch = interleaved({"fk": lambda: armkit.fk(robot, Q), "rtb": lambda: ets.eval(Q),
                                 "numpy": lambda: numpy_fk(Q)}, max(3, rounds // 2))
            per = {k: type(v)(tuple(t / n for t in v.times)) for k, v in batch.items()}
            row("", f"batch N={n:.0e}", per["fk"], "rtb", per["rtb"], "ns")
            row("", f"batch N={n:.0e}", per["fk"], "numpy", per["numpy"], "ns")
        Q = rng.uniform(robot.lower, robot.upper, (sizes[-1], robot.n))

        def on(threads):
            def call():
                armkit.set_num_threads(threads)
                try:
                    armkit.fk(robot, Q)
                finally:
                    armkit.set_num_threads(None)
            return call

        threads = interleaved({"1": on(1), "2": on(2), "auto": on(None)}, max(3, rounds // 2))
        per = {k: type(v)(tuple(t / len(Q) for t in v.times)) for k, v in threads.items()}
        row("", f"threads N={len(Q):.0e}", per["2"], "1 thread", per["1"], "ns")
        row("", f"auto N={len(Q):.0e}", per["auto"], "1 thread", per["1"], "ns")
    print(load())
    if not (args.quick or args.single):
        for n, call in ((10_000_000, "fk"), (20_000_000, "manipulability")):
            seconds, out, extra = memory_at(n, call)
            print(f"\n{call} of {n:.0e} configurations (ur5): {seconds:.2f} s, output "
                  f"{out:.2f} GB, peak memory beyond input and output {extra:.2f} GB "
                  f"({extra / out:.2f} x the output)")


if __name__ == "__main__":
    main()
