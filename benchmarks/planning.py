"""Collision-free planning on MotionBenchMaker-style problems: armkit (its compiled checker, and a
user's Python checker) beside OMPL given the same Python checker, with VAMP's figure as
published; the checker's cost per state; plan()'s overhead and the model's build; the time
limit kept from a fresh process; the shelf of earlier runs.

    python benchmarks/planning.py                 # 15 problems per family and arm
    python benchmarks/planning.py --quick         # 3 per family
    python benchmarks/planning.py --armkit-only   # without OMPL's rows
    python benchmarks/planning.py --before DIR    # also the code in DIR (a checkout) "before"

Problems: benchmarks/mbm.py (six families, UR5 and Panda of example-robot-data as spherized
URDFs with their SRDFs). Each call gets a 1 s time limit. armkit native: `plan(checker, start,
goal)` with a checker built on a prebuilt `CollisionModel` (RRT-Connect, shortcutting, every
edge certified). armkit Python checker: `plan(f, start, goal, limits=...)` with ``f(Q) =
checker.valid(Q)`` (edges sampled every 0.01 rad on the largest joint, shortcut, all in
Python). OMPL: RRTConnect on a RealVectorStateSpace, the same function called per state, at
the same resolution (0.01 rad along the joint-space segment), then `simplifySolution`.
Columns: solved within the limit, median and 90th percentile time of the whole call (planning
and shortcutting / simplification, from Python), states checked, path length (joint space,
rad), and paths found in collision by the independent checker of benchmarks/mbm.py (Pinocchio's
forward kinematics, states 0.005 rad apart).

The machine is shared: every time is printed with a reference measured in the same run, and the
load average beside it.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import mbm

import armkit
from armkit.jit import set_mode
from armkit.planning import Box, CollisionChecker, CollisionModel, Scene, default_geometry, plan
from armkit.planning.collision import states_kernel

TIME_LIMIT = 1.0
USER_STEP = 0.01        # rad: the user checker's edges (armkit's default) and OMPL's resolution
MM = 1e-3
SHELF = (np.array([0.5567789, -1.5882119, 1.3545770, -2.3713940, 2.2182614, -2.4618970]),
         np.array([-0.8764912, -0.4068011, -1.3528886, 1.6921273, -0.9314323, 2.2978917]))
VAMP = ("VAMP (published: Thomason, Kingston, Kavraki, ICRA 2024; the median of 61 us on "
        "these MotionBenchMaker Panda problems is issue 28's measurement on this machine)")


def shelf() -> Scene:
    """Issue 15's shelf: three plates and a back wall (inspection_6dof)."""
    def box(lo, hi):
        return Box.from_bounds(np.array(lo) * MM, np.array(hi) * MM)
    return Scene([box([650, -500, z0], [1100, 500, z1]) for z0, z1 in
                  ((200, 240), (560, 600), (920, 960))] + [box([1100, -500, 0],
                                                               [1140, 500, 1000])])


def numpy_sphere_clearance(robot, geometry, scene, Q):
    """A plain NumPy reference for a sphere model: every sphere placed by `fk_frames`, every
    box and cylinder by closed forms, every tested pair; (k,)."""
    F = armkit.fk_frames(robot, Q)[:, geometry.link]
    P = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.a) + F[..., :3, 3]
    best = np.full(len(Q), np.inf)
    for o in scene:
        x = (P - o.pose[:3, 3]) @ o.pose[:3, :3]
        if isinstance(o, Box):
            d = np.linalg.norm(np.maximum(np.abs(x) - o.size / 2, 0), axis=-1)
        else:
            d = np.hypot(np.maximum(np.hypot(x[..., 0], x[..., 1]) - o.radius, 0),
                         np.maximum(np.abs(x[..., 2]) - o.length / 2, 0))
        best = np.minimum(best, (d - geometry.radius).min(axis=1))
    pairs = geometry.self_pairs()
    i, j = pairs[:, 0], pairs[:, 1]
    gap = np.linalg.norm(P[:, i] - P[:, j], axis=-1) - geometry.radius[i] - geometry.radius[j]
    return np.minimum(best, gap.min(axis=1) / 2)


def median_time(f, rounds):
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


# --- the checker per state ---------------------------------------------------------------------

def checker_figures(arm: str, problem, model, quick: bool) -> None:
    robot = model.robot
    checker = CollisionChecker(model, problem.scene)
    Q = np.random.default_rng(0).uniform(*robot.chain.sampling_limits,
                                          (20_000 if quick else 100_000, robot.n))
    out = np.empty(len(Q))
    states_kernel(Q[:10], checker.arrays, 0.0, 1e-12, out[:10])
    rounds = 3 if quick else 5
    verdict = median_time(lambda: states_kernel(Q, checker.arrays, 0.0, 1e-12, out), rounds)
    exact = median_time(lambda: states_kernel(Q, checker.arrays, -np.inf, np.inf, out), rounds)
    Qn = Q[:5000]
    ref = numpy_sphere_clearance(robot, model.geometry, problem.scene, Qn)
    agree = np.abs(np.minimum(ref, 1) - np.minimum(checker.clearance(Qn), 1)).max()
    numpy_t = median_time(lambda: numpy_sphere_clearance(robot, model.geometry, problem.scene,
                                                        Qn), 3)
    k = robot.chain.kernel
    fk_out = np.empty((len(Q), 4, 4))
    from armkit.kinematics.core import poses
    poses(Q[:10], k.floats, k.ints, fk_out[:10])
    fk_t = median_time(lambda: poses(Q, k.floats, k.ints, fk_out), rounds)
    print(f"\n## Checker per state: {arm}, {len(model.geometry)} spheres on "
          f"{len(set(model.geometry.names))} links ({model.link_pairs} link pairs, "
          f"{model.part_pairs} sphere pairs tested), {problem.family} with "
          f"{len(problem.scene)} obstacles; {len(Q):,} random states, one thread")
    print(f"verdict (clearance > 0): {verdict / len(Q) * 1e6:.3f} us/state "
          f"({np.mean(out > 0) * 100:.0f} % valid)")
    print(f"exact clearance:         {exact / len(Q) * 1e6:.3f} us/state")
    print(f"reference, the tool pose alone (armkit.kinematics.core.poses): "
          f"{fk_t / len(Q) * 1e6:.3f} us/state -> verdict / pose {verdict / fk_t:.2f}")
    print(f"reference, plain NumPy sphere checker: {numpy_t / len(Qn) * 1e6:.2f} us/state -> "
          f"{numpy_t / len(Qn) / (exact / len(Q)):.0f}x the exact clearance (largest "
          f"difference {agree:.1e} m)")


BEFORE = r"""
import sys, time, numpy as np, armkit
from armkit.jit import set_mode
set_mode("compiled")
from armkit.planning import Box, CollisionChecker, Scene
from armkit.kinematics.core import poses
robot = armkit.load_robot(sys.argv[1], tip=sys.argv[2])
boxes = np.load(sys.argv[3])
scene = Scene([Box(b[:3], b[3:].reshape(4, 4)) for b in boxes])
Q = np.random.default_rng(0).uniform(*robot.chain.sampling_limits, (20000, robot.n))
c = CollisionChecker(robot, scene, resolution=1e-9)
c.valid(Q[:10]); c.clearance(Q[:10])
k = robot.chain.kernel; out = np.empty((len(Q), 4, 4)); poses(Q[:5], k.floats, k.ints, out[:5])
def t(f):
    ts = []
    for _ in range(5):
        s = time.perf_counter(); f(); ts.append(time.perf_counter() - s)
    return float(np.median(ts)) / len(Q) * 1e6
armkit.set_num_threads(1)
print(t(lambda: c.valid(Q)), t(lambda: c.clearance(Q)), t(lambda: poses(Q, k.floats, k.ints, out)))
"""


def before_figures(before: str, arm: str, problem, urdf, tip) -> None:
    """The per-state figure of the code in `before` (a checkout), on the same spheres (read as
    URDF sphere primitives, no SRDF: its pairs are armkit's old rule) and obstacles (boxes)."""
    boxes = np.array([np.r_[o.size, o.pose.reshape(-1)] for o in problem.scene
                      if isinstance(o, Box)])
    with tempfile.TemporaryDirectory() as tmp:
        np.save(os.path.join(tmp, "boxes.npy"), boxes)
        env = dict(os.environ, PYTHONPATH=os.path.join(before, "src"))
        run = subprocess.run([sys.executable, "-c", BEFORE, str(urdf), tip,
                              os.path.join(tmp, "boxes.npy")], env=env, capture_output=True,
                             text=True)
    if run.returncode:
        print(f"before: failed ({run.stderr.strip().splitlines()[-1]})")
        return
    valid, exact, pose = (float(x) for x in run.stdout.split())
    print(f"before ({before}, its boxes only: {len(boxes)}): verdict {valid:.3f} us/state, exact "
          f"{exact:.3f} us/state, pose {pose:.3f} us/state -> verdict / pose {valid / pose:.2f}")


# --- the problems --------------------------------------------------------------------------------

def armkit_native(checker, p):
    res = plan(checker, p.start, p.goal, time_limit=TIME_LIMIT, seed=p.index)
    return res.success, res.total_time, res.states_checked, res.length, res.path, res.reason


def armkit_python(checker, p):
    calls = [0]

    def valid(Q):
        calls[0] += len(Q)
        return checker.valid(Q)

    res = plan(valid, p.start, p.goal, limits=(checker.lower, checker.upper),
               time_limit=TIME_LIMIT, seed=p.index, resolution=USER_STEP)
    return res.success, res.total_time, calls[0], res.length, res.path, res.reason


def ompl_run(checker, p):
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(int(p.index) + 1)
    n = checker.n
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(checker.lower[i]))
        bounds.setHigh(i, float(checker.upper[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    calls = [0]
    q = np.empty(n)

    def valid(state):
        calls[0] += 1
        for i in range(n):
            q[i] = state[i]
        return bool(checker.valid(q))

    ss.setStateValidityChecker(valid)
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(USER_STEP / space.getMaximumExtent())
    a, b = space.allocState(), space.allocState()
    for i in range(n):
        a[i], b[i] = float(p.start[i]), float(p.goal[i])
    ss.setStartAndGoalStates(a, b)
    ss.setPlanner(og.RRTConnect(si))
    ss.setup()
    t = time.perf_counter()
    solved = ss.solve(TIME_LIMIT)
    if not (bool(solved) and ss.haveExactSolutionPath()):
        return False, time.perf_counter() - t, calls[0], math.nan, None, "no exact path"
    ss.simplifySolution()
    dt = time.perf_counter() - t
    path = ss.getSolutionPath()
    Q = np.array([[path.getState(k)[i] for i in range(n)] for k in range(path.getStateCount())])
    return True, dt, calls[0], path.length(), Q, "ok"


def row(name, runs, independent, problems):
    ok = np.array([r[0] for r in runs])
    t = np.array([r[1] for r in runs]) * 1e3
    states = np.array([r[2] for r in runs])
    length = np.array([r[3] for r in runs])
    bad = sum(independent.path_collides(p.scene, r[4]) for r, p in zip(runs, problems) if r[0])
    if ok.any():
        print(f"| {name} | {ok.sum()}/{len(ok)} | {np.median(t[ok]):.3g} | "
              f"{np.percentile(t[ok], 90):.3g} | {np.median(states[ok]):.0f} | "
              f"{np.median(length[ok]):.3g} | {bad} |")
    else:
        print(f"| {name} | 0/{len(ok)} | | | | | |")
    reasons = {r[5] for r in runs if not r[0]}
    if reasons:
        print(f"|   (unsolved: {'; '.join(sorted(reasons))[:150]}) | | | | | | |")


def arm_table(arm: str, per_family: int, args) -> None:
    t = time.perf_counter()
    robot, problems = mbm.problems(arm, per_family)
    generated = time.perf_counter() - t
    urdf, srdf, tip = mbm.spherized_urdf(arm)
    independent = mbm.IndependentChecker(urdf, srdf, robot.n)
    t = time.perf_counter()
    model = CollisionModel(armkit.load_robot(urdf, tip=tip, srdf=srdf))
    build = time.perf_counter() - t
    t = time.perf_counter()
    CollisionModel(model.robot)
    model_time = time.perf_counter() - t
    checkers = [CollisionChecker(model, p.scene) for p in problems]
    scene_time = median_time(lambda: CollisionChecker(model, problems[0].scene), 20)
    for c, p in zip(checkers, problems[:3]):
        plan(c, p.start, p.goal, time_limit=60)             # compiled before timing
    print(f"\n## {arm}: {len(problems)} problems ({per_family} per family, generated in "
          f"{generated:.1f} s); {len(model.geometry)} spheres, {model.link_pairs} link pairs, "
          f"{model.part_pairs} sphere pairs; {os.getloadavg()[0]:.1f} load")
    print(f"model build: spherized URDF and SRDF read and the model built {build * 1e3:.1f} ms "
          f"(the CollisionModel alone {model_time * 1e3:.1f} ms); a checker for a new scene "
          f"{scene_time * 1e6:.0f} us")
    # plan()'s overhead: a problem whose direct edge is free and short, against the kernel
    # work it does (the same edge certified by one call).
    p0, c0 = problems[0], checkers[0]
    q_near = p0.start + 1e-3 * (p0.goal - p0.start) / np.linalg.norm(p0.goal - p0.start)
    edge = np.vstack([p0.start, q_near])
    total = median_time(lambda: plan(c0, p0.start, q_near), 200)
    kernel_only = median_time(lambda: c0.polyline_free(edge), 200)
    print(f"plan() with a prebuilt model, direct edge: {total * 1e6:.1f} us, of which "
          f"{kernel_only * 1e6:.1f} us the edge's certification -> overhead "
          f"{(total - kernel_only) * 1e6:.1f} us")
    print("\n| planner | solved | median ms | p90 ms | states checked | length (rad) | "
          "in collision (0.005 rad) |")
    print("|---|---|---|---|---|---|---|")
    runs = [armkit_native(c, p) for c, p in zip(checkers, problems)]
    row("armkit native (RRT-Connect, certified)", runs, independent, problems)
    by_family = {}
    for r, p in zip(runs, problems):
        by_family.setdefault(p.family, []).append(r[1] * 1e3)
    print("|   per family, median ms: " + ", ".join(f"{f} {np.median(v):.3g}" for f, v in
                                                     by_family.items()) + " | | | | | | |")
    runs = [armkit_python(c, p) for c, p in zip(checkers, problems)]
    row(f"armkit, Python checker ({USER_STEP} rad)", runs, independent, problems)
    if not args.armkit_only:
        runs = [ompl_run(c, p) for c, p in zip(checkers, problems)]
        row(f"OMPL RRTConnect, Python checker ({USER_STEP} rad)", runs, independent, problems)
    if arm == "panda":
        print(f"| {VAMP} | | 0.061 | | | | |")
    checker_figures(arm, next(p for p in problems if p.family == "bookshelf_tall"), model,
                    args.quick)
    if args.before:
        before_figures(args.before, arm,
                       next(p for p in problems if p.family == "bookshelf_tall"), urdf, tip)


# --- the time limit from a fresh process ---------------------------------------------------------

FRESH = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np, armkit, mbm
from armkit.planning import CollisionChecker, CollisionModel, plan
robot, problems = mbm.problems(sys.argv[3], 1)
model = CollisionModel(robot)
times = []
for p in problems:
    checker = CollisionChecker(model, p.scene)
    t = time.perf_counter()
    r = plan(checker, p.start, p.goal, time_limit=float(sys.argv[2]))
    times.append(time.perf_counter() - t)
    if len(times) == 1:
        first = (times[0], r.reason.replace(" ", "_"))
print(first[0], first[1], max(times), len(times))
"""


def fresh_process(limit: float, arm: str) -> None:
    """plan(time_limit=limit) on one problem of each family, in a fresh process: the first
    call's time and the longest."""
    here = os.path.dirname(os.path.abspath(__file__))
    print(f"\n## The time limit from a fresh process: plan(time_limit={limit}) on one {arm} "
          f"problem of each family, in turn")
    for label, empty in (("empty numba cache (the loops run as Python)", True),
                         ("warm cache", False)):
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ)
            if empty:
                env["NUMBA_CACHE_DIR"] = cache
            out = subprocess.run([sys.executable, "-c", FRESH, here, str(limit), arm], env=env,
                                 capture_output=True, text=True)
        if out.returncode:
            print(f"{label}: failed: {out.stderr.strip().splitlines()[-1]}")
            continue
        first, reason, longest, count = out.stdout.split()
        print(f"{label}: the first call returned after {float(first):.4f} s "
              f"({reason.replace('_', ' ')}); the longest of {count} "
              f"{float(longest):.4f} s (overrun {(float(longest) - limit) * 1e3:.1f} ms)")


# --- the shelf -----------------------------------------------------------------------------------

def shelf_row(seeds) -> None:
    robot = armkit.robot("inspection_6dof")
    checker = CollisionChecker(robot, shelf(), default_geometry(robot, 0.04), resolution=0.005)
    plan(checker, *SHELF, seed=0)
    rows = [plan(checker, *SHELF, seed=s) for s in seeds]
    ok = [r for r in rows if r.success]
    t = np.array([r.planning_time for r in ok]) * 1e3
    total = np.array([r.total_time for r in ok]) * 1e3
    print(f"\n## The shelf (inspection_6dof, 40 mm capsules, resolution 5 mm): RRT-Connect, "
          f"{len(rows)} seeds: {len(ok)} solved; planning median {np.median(t):.3g} ms, p90 "
          f"{np.percentile(t, 90):.3g} ms; whole call median {np.median(total):.3g} ms; states "
          f"{np.median([r.states_checked for r in ok]):.0f}; length "
          f"{np.median([r.length for r in ok]):.3g} rad")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 problems per family")
    parser.add_argument("--per-family", type=int, default=None)
    parser.add_argument("--armkit-only", action="store_true", help="no OMPL rows")
    parser.add_argument("--arms", default="ur5,panda")
    parser.add_argument("--before", default=None,
                        help="a checkout of the code before, for the per-state figure")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()}")
    fresh_process(0.2, "panda")
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    per_family = args.per_family or (3 if args.quick else 15)
    for arm in args.arms.split(","):
        arm_table(arm, per_family, args)
    shelf_row(range(20 if args.quick else 100))
    print(f"\nload average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
