"""Forward kinematics speed: armkit against roboticstoolbox-python and a plain NumPy chain.

    python benchmarks/fk.py            # N = 1e5 and 1e6, plus the 1e7 memory check
    python benchmarks/fk.py --quick    # N = 1e5 only

Per call: one configuration from Python, armkit.fk vs rtb's compiled ``ets.eval(q)``.
Batch: ``armkit.fk(robot, Q)`` vs ``ets.eval(Q)`` on the same (N, 6) array, and vs a vectorised
NumPy einsum over the DH matrices. Every ratio is reference time / armkit time, measured in
the same run. Also: the kernels' compile time (fresh numba cache) and load time (warm cache),
and the memory that N = 1e7 takes beyond its output.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import roboticstoolbox as rtb

import armkit
from common import best_of, numpy_chain


def per_call(f, q, calls: int = 20000) -> float:
    """Mean time of one call (s), best of three runs of `calls` calls."""
    def loop():
        for _ in range(calls):
            f(q)
    return best_of(loop, 3) / calls


def rtb_model(robot: armkit.Robot) -> rtb.DHRobot:
    links = [rtb.RevoluteDH(a=r.a, alpha=r.alpha, d=r.d, offset=r.theta)
             for r in robot.table.rows]
    return rtb.DHRobot(links, base=robot.table.T_base, tool=robot.table.T_tool)


def compile_times() -> tuple[float, float]:
    """First fk call in a fresh process: with an empty numba cache, then with it filled (s)."""
    code = ("import time, numpy as np, armkit; r = armkit.robot('ur5'); t = time.perf_counter(); "
            "armkit.fk(r, np.zeros(6)); armkit.fk(r, np.zeros((4096, 6))); "
            "print(time.perf_counter() - t)")
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        run = lambda: float(subprocess.run([sys.executable, "-c", code], env=env, check=True,  # noqa: E731
                                           capture_output=True, text=True).stdout)
        return run(), run()


def memory_at(n: int) -> tuple[float, float, float]:
    """(seconds, output GB, peak GB beyond input and output) for fk of n configurations, in a
    fresh process, so that no earlier high-water mark hides the call's temporaries."""
    code = f"""
import resource, time, numpy as np, armkit
robot = armkit.robot("ur5")
Q = np.random.default_rng(0).uniform(-np.pi, np.pi, ({n}, 6))
armkit.fk(robot, Q[:10])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
t = time.perf_counter()
T = armkit.fk(robot, Q)
seconds = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
print(seconds, T.nbytes / 2**30, peak - before - T.nbytes / 2**30)
"""
    done = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    seconds, out, extra = map(float, done.stdout.split())
    return seconds, out, max(0.0, extra)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 1e5 only, no 1e7 run")
    args = parser.parse_args()
    sizes = [100_000] if args.quick else [100_000, 1_000_000]
    rng = np.random.default_rng(0)
    cold, warm = compile_times()
    print(f"kernel compile (empty numba cache): {cold:.2f} s; load (warm cache): {warm:.3f} s\n")
    print(f"{'robot':16} {'case':14} {'armkit':>12} {'rtb ets.eval':>14} {'ratio':>7} "
          f"{'numpy einsum':>14} {'ratio':>7}")
    for name in ("ur5", "inspection_6dof"):
        robot = armkit.robot(name)
        ets = rtb_model(robot).ets()
        numpy_fk = numpy_chain(robot.table)
        q = rng.uniform(robot.lower, robot.upper)
        check = rng.uniform(robot.lower, robot.upper, (1000, robot.n))
        assert np.abs(armkit.fk(robot, check) - ets.eval(check)).max() < 1e-12
        assert np.abs(armkit.fk(robot, check) - numpy_fk(check)).max() < 1e-12
        ours = per_call(lambda x: armkit.fk(robot, x), q)
        ref = per_call(ets.eval, q)
        numpy_one = per_call(lambda x: numpy_fk(x[None]), q, calls=2000)
        print(f"{name:16} {'one config':14} {ours * 1e6:9.2f} us {ref * 1e6:11.2f} us "
              f"{ref / ours:6.1f}x {numpy_one * 1e6:11.2f} us {numpy_one / ours:6.1f}x")
        for n in sizes:
            Q = rng.uniform(robot.lower, robot.upper, (n, robot.n))
            ours = best_of(lambda: armkit.fk(robot, Q), 5) / n
            ref = best_of(lambda: ets.eval(Q), 3) / n
            base = best_of(lambda: numpy_fk(Q), 3) / n
            print(f"{name:16} {f'batch N={n:.0e}':14} {ours * 1e6:9.3f} us {ref * 1e6:11.3f} us "
                  f"{ref / ours:6.1f}x {base * 1e6:11.3f} us {base / ours:6.1f}x")
    if not args.quick:
        seconds, out, extra = memory_at(10_000_000)
        print(f"\nN = 1e7 (ur5): {seconds:.2f} s ({seconds / 1e7 * 1e6:.3f} us per config), "
              f"output {out:.2f} GB, peak memory beyond input and output {extra:.2f} GB")


if __name__ == "__main__":
    main()
