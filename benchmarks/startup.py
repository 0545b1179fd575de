"""Start-up cost: `import armkit` and the first call of each capability, in fresh processes.

    python benchmarks/startup.py             # 3 rounds
    python benchmarks/startup.py --rounds 5

Each figure is one fresh Python process that imports armkit, loads a built-in robot and makes
one first call, timed from inside the process. "Empty cache" points ``NUMBA_CACHE_DIR`` at a
new temporary directory, so the call compiles its numba kernels as on a fresh install; "warm
cache" runs the same process again on that directory, as every later session does. Each call
gets its own cache directory, so that no call finds kernels another call compiled. Figures are
min-median-max over the rounds, the calls interleaved within a round; the load average is
printed with them.

The calls: `fk` and `jacobian` of one UR5 configuration; `ik` of one UR5 pose (closed form),
its 8 closed-form solutions (`ik_solutions`), and `ik` of one tool_changer_6dof pose (numeric,
Levenberg-Marquardt); `workspace` of inspection_6dof with 10,000 samples; `spline` 4-5-5
through paper 4's Table 1, sampled at 100 times; one 6-joint `jerk_limited` motion; `retime`
of 10 waypoints; "command line", a whole process timed from outside: ``armkit fk ur5 ...``
(``python -m armkit``), with as its reference the process that only imports what such a
command cannot do without (NumPy, typer, rich, pydantic, PyYAML). ``--calls`` runs some of
them only. Beside the wall time of the first call on an empty cache, its CPU time
(``time.process_time``), which a busy machine inflates less. The reference: the same first call
compiled from the start (``ARMKIT_JIT=compiled``, numba's own behaviour, what every call did
before `armkit.jit`) into an empty cache; the ratio is its time over the default's.
Their inputs are built without armkit's kernels, so each process compiles only what its own
call needs.
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

from common import Spread, load

CHILD = """
import json, sys, time
start = time.perf_counter()
cpu_start = time.process_time()
import armkit
imported = time.perf_counter()
import numpy as np
from armkit.spatial import pose_from_xyz_rpy
what = sys.argv[1]
if what in ("fk", "jacobian", "ik closed form", "ik_solutions"):
    robot = armkit.robot("ur5")
elif what == "ik numeric":
    robot = armkit.robot("tool_changer_6dof")
elif what in ("workspace", "retime"):
    robot = armkit.robot("inspection_6dof")
loaded, cpu_loaded = time.perf_counter(), time.process_time()
q = np.deg2rad([10.0, -80.0, 70.0, -60.0, -90.0, 20.0])
if what == "import":
    pass
elif what == "fk":
    armkit.fk(robot, q)
elif what == "jacobian":
    armkit.jacobian(robot, q)
elif what == "ik closed form":
    result = armkit.ik(robot, pose_from_xyz_rpy([0.4, 0.1, 0.3], [np.pi, 0.0, 0.0]))
    assert result.success, result.reason
elif what == "ik_solutions":
    solutions = armkit.ik_solutions(robot, pose_from_xyz_rpy([0.4, 0.1, 0.3], [np.pi, 0.0, 0.0]))
    assert solutions.count == 8, solutions.count
elif what == "ik numeric":
    from armkit.spatial import exp_se3
    # A reachable pose from the product of exponentials (NumPy, no kernel): the tool's pose
    # at q = (20, -20, -60 deg, 0.3 m, 30, 10 deg).
    target = robot.chain.T_home
    for screw, value in reversed(list(zip(robot.chain.screws, np.r_[np.deg2rad(
            [20.0, -20.0, -60.0]), 0.3, np.deg2rad([30.0, 10.0])]))):
        target = exp_se3(screw * value) @ target
    result = armkit.ik(robot, target)
    assert result.success, result.reason
elif what == "workspace":
    armkit.workspace(robot, 10_000)
elif what == "spline":
    points = np.deg2rad([[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]])
    armkit.spline([0, 2, 4, 5], points, "4-5-5").sample(np.linspace(0, 5, 100))
elif what == "jerk_limited":
    armkit.jerk_limited(np.zeros(6), q, 1.0, 2.0, 10.0)
elif what == "retime":
    waypoints = np.random.default_rng(0).uniform(-1.0, 1.0, (10, 6))
    assert armkit.retime(waypoints, robot.velocity_limits, robot.acceleration_limits).success
done, cpu_done = time.perf_counter(), time.process_time()
print(json.dumps({"import": imported - start, "robot": loaded - imported, "call": done - loaded,
                  "call_cpu": cpu_done - cpu_loaded, "numba": "numba" in sys.modules}))
"""

CALLS = ("import", "fk", "jacobian", "ik closed form", "ik_solutions", "ik numeric", "workspace",
         "spline", "jerk_limited", "retime", "command line")
COMMAND = ["-m", "armkit", "fk", "ur5", "0", "-90", "90", "-90", "-90", "0"]
FLOOR = ["-c", "import numpy, typer, rich.console, pydantic, yaml"]


def run(what: str, cache: str, mode: str = "auto") -> dict[str, float]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "ARMKIT_JIT": mode}
    if what == "command line":
        arguments = COMMAND if mode == "auto" else FLOOR
        return {"call": process_wall_time(arguments, env), "numba": False}
    done = subprocess.run([sys.executable, "-c", CHILD, what], env=env, capture_output=True,
                          text=True)
    if done.returncode:
        raise SystemExit(f"{what}: {done.stderr.strip().splitlines()[-1]}")
    return json.loads(done.stdout)


def process_wall_time(arguments: list[str], env: dict) -> float:
    """Wall time (s) of a fresh Python process with these arguments, from start to exit."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, *arguments], env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{arguments}: {done.stderr.strip().splitlines()[-1]}")
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--calls", nargs="+", choices=CALLS, default=CALLS,
                        help="only these first calls")
    args = parser.parse_args()
    calls = tuple(args.calls)
    print(load())
    cold: dict[str, list[dict]] = {c: [] for c in calls}
    warm: dict[str, list[dict]] = {c: [] for c in calls}
    compiled: dict[str, list[dict]] = {c: [] for c in calls}
    for _ in range(args.rounds):
        for what in calls:
            with tempfile.TemporaryDirectory() as cache:
                cold[what].append(run(what, cache))
                warm[what].append(run(what, cache))
            if what != "import":
                with tempfile.TemporaryDirectory() as cache:
                    compiled[what].append(run(what, cache, "compiled"))
    print(load())
    print(f"\n{'first call':16} {'empty numba cache':>24} {'its CPU time':>24} "
          f"{'warm numba cache':>24} {'compiled, empty cache':>24} {'ratio':>20}")
    for what in calls:
        key = "import" if what == "import" else "call"
        a = Spread(tuple(r[key] for r in cold[what]))
        cpu = Spread(tuple(r["call_cpu"] for r in cold[what])).text("s") \
            if what not in ("import", "command line") else ""
        b = Spread(tuple(r[key] for r in warm[what]))
        c = ratio = ""
        if compiled[what]:
            reference = Spread(tuple(r[key] for r in compiled[what]))
            c = reference.text("s")
            ratio = Spread(tuple(r[key] / q[key] for r, q in zip(compiled[what], cold[what])))
            digits = 0 if ratio.min >= 10 else 2
            ratio = (f"{reference.median / a.median:.{digits}f}x "
                     f"[{ratio.min:.{digits}f}-{ratio.max:.{digits}f}]")
        numba = sum(r["numba"] for r in cold[what] + warm[what])
        print(f"{what:16} {a.text('s'):>24} {cpu:>24} {b.text('s'):>24} {c:>24} {ratio:>20}"
              + (f"  (numba imported in {numba} of {2 * len(cold[what])})" if numba else ""))
    robots = Spread(tuple(r["robot"] for c in calls if c not in ("import", "command line")
                          for r in cold[c] + warm[c]))
    print(f"\n`import armkit` is the import alone; every other row is the call alone, after the"
          f"\nimport and `armkit.robot(...)` (loading a built-in robot: {robots.text('s')}).")
    if "command line" in calls:
        print("`command line`: the whole process; its reference column is the process that only "
              "imports\nNumPy, typer, rich, pydantic and PyYAML.")
    imports = [r["import"] for c in calls if c != "command line" for r in cold[c] + warm[c]]
    print(f"`import armkit` over all {len(imports)} processes: median {np.median(imports):.3f} s")


if __name__ == "__main__":
    main()
