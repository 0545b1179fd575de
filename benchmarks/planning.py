"""Collision-free planning: armkit's compiled checker and planners beside a plain NumPy checker
and OMPL's planners (the `ompl` package) given a Python callback to the same checker.

    python benchmarks/planning.py            # 100 seeds per scene and planner
    python benchmarks/planning.py --quick    # 10 seeds, fewer checker rounds
    python benchmarks/planning.py --armkit-only    # without the OMPL rows
    python benchmarks/planning.py --checker-only   # the checker's figures and first call only

Scenes (inspection_6dof, one capsule per link between consecutive DH frame origins, 40 mm):
- shelf: issue 15's shelf (three plates and a back wall), start in the lower compartment, goal
  in the upper one; 28 % of the straight joint line collides.
- window: a wall at x = 600-640 mm with a 340 x 340 mm window; the tool starts low beside the
  wall and must reach through the window to x = 950 mm (a narrow passage: RRT-Connect needs
  hundreds of iterations).
- bookshelf: a UR5 (armkit's built-in ur5, default capsules of 40 mm) among a bookshelf like
  MotionBenchMaker's (examples/bookshelf.scene.yaml: three plates, side walls, a back, four
  cylinders); tool from the lower compartment to the upper one (`--bookshelf-only` runs it alone).

armkit certifies at r = 5 mm (every configuration on a returned path keeps r / 2 from the
obstacles). OMPL checks states with the same verdict (free distance > r) at two resolutions:
its default (1 % of the joint-space extent, "coarse") and "safe", the joint step that keeps
every point of the arm within r between checks (r / |w|_2, w the displacement weights).
Every returned path (after shortcutting / simplification) is densified to 0.002 rad and each
state's exact clearance computed: "dense fails" counts paths found in collision.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import armkit
from armkit.jit import set_mode
from armkit.planning import Box, CollisionChecker, Scene, default_geometry, plan
from armkit.planning.collision import states_kernel

MM = 1e-3
R = 0.005
SHELF = (np.array([0.5567789, -1.5882119, 1.3545770, -2.3713940, 2.2182614, -2.4618970]),
         np.array([-0.8764912, -0.4068011, -1.3528886, 1.6921273, -0.9314323, 2.2978917]))
WINDOW = (np.array([-1.2638286, -0.4424211, -0.8906291, -0.2377461, 1.5707963, 0.3069677]),
          np.array([-0.3398369, -1.7227862, 1.7112577, 0.0115285, -1.2309594, 1.5707963]))


def box(lo, hi) -> Box:
    return Box.from_bounds(np.array(lo) * MM, np.array(hi) * MM)


def shelf() -> Scene:
    return Scene([box([650, -500, z0], [1100, 500, z1]) for z0, z1 in
                  ((200, 240), (560, 600), (920, 960))] + [box([1100, -500, 0], [1140, 500, 1000])])


def window() -> Scene:
    return Scene([box([600, -800, 0], [640, 800, 430]), box([600, -800, 770], [640, 800, 1400]),
                  box([600, -800, 430], [640, -170, 770]), box([600, 170, 430], [640, 800, 770])])


# --- plain NumPy exact checker (boxes and self pairs), vectorised over states ------------------

def numpy_segments(robot, geometry, Q):
    F = armkit.fk_frames(robot, Q)[:, geometry.link]
    A = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.a) + F[..., :3, 3]
    B = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.b) + F[..., :3, 3]
    return A, B


def numpy_segment_box(P, D, h):
    """Exact distance from segments P + t D (..., 3) to the box |x| <= h (3,): the squared
    distance is quadratic between the crossings of the face planes."""
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = np.concatenate([(-h - P) / D, (h - P) / D], axis=-1)
    cross = np.where((cross > 0) & (cross < 1), cross, 1.0)
    ts = np.sort(np.concatenate([np.zeros(P.shape[:-1] + (1,)), cross,
                                 np.ones(P.shape[:-1] + (1,))], axis=-1), axis=-1)
    t0, t1 = ts[..., :-1], ts[..., 1:]                                   # (..., 7)
    x = P[..., None, :] + 0.5 * (t0 + t1)[..., None] * D[..., None, :]   # (..., 7, 3)
    above, below = x > h, x < -h
    alpha = np.where(above, P[..., None, :] - h, np.where(below, -h - P[..., None, :], 0.0))
    beta = np.where(above, D[..., None, :], np.where(below, -D[..., None, :], 0.0))
    qa, qb, qc = (beta ** 2).sum(-1), (2 * alpha * beta).sum(-1), (alpha ** 2).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(qa > 0, np.clip(-qb / (2 * qa), t0, t1), np.where(qb >= 0, t0, t1))
    return np.sqrt(np.maximum(((qa * t + qb) * t + qc).min(-1), 0))


def numpy_segment_segment(a, b, c, e):
    d1, d2, r = b - a, e - c, a - c
    A, E, F = (d1 * d1).sum(-1), (d2 * d2).sum(-1), (d2 * r).sum(-1)
    C, Bd = (d1 * r).sum(-1), (d1 * d2).sum(-1)
    den = A * E - Bd * Bd
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(den > 1e-14 * A * E, np.clip((Bd * F - C * E) / den, 0, 1), 0.0)
        t = (Bd * s + F) / E
        s = np.where(t < 0, np.clip(-C / A, 0, 1), np.where(t > 1, np.clip((Bd - C) / A, 0, 1), s))
    t = np.clip(t, 0, 1)
    return np.linalg.norm(a + d1 * s[..., None] - c - d2 * t[..., None], axis=-1)


def numpy_free_distance(robot, geometry, scene, Q):
    """min(obstacle gaps, self gaps / 2) per state (N,), boxes only."""
    A, B = numpy_segments(robot, geometry, Q)
    best = np.full(len(Q), np.inf)
    for o in scene:
        Rm, p = o.pose[:3, :3], o.pose[:3, 3]
        P, E = (A - p) @ Rm, (B - p) @ Rm
        d = numpy_segment_box(P, E - P, o.size / 2) - geometry.radius
        best = np.minimum(best, d.min(axis=1))
    for i, j in geometry.self_pairs():
        gap = numpy_segment_segment(A[:, i], B[:, i], A[:, j], B[:, j]) - \
            geometry.radius[i] - geometry.radius[j]
        best = np.minimum(best, gap / 2)
    return best


# --- timing helpers ----------------------------------------------------------------------------

def rounds(f, count):
    out = []
    for _ in range(count):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return np.array(out)


def mmm(x, scale=1.0, fmt="{:.3g}"):
    x = np.asarray(x) * scale
    return "/".join(fmt.format(v) for v in (x.min(), np.median(x), x.max()))


def first_call_compile(mode: str) -> str:
    """The checker's first call, then the first plan() on the shelf (RRT-Connect, shortcut),
    then the first batch of 20,000 states on every core (the parallel batch kernel), in a fresh
    process with an empty numba cache, then with the cache filled: wall time and this
    process's CPU time (the machine is shared). mode: `armkit.jit`'s ("auto": the first state
    and plan run as Python; "compiled": what compiling them costs)."""
    code = ("import os, sys, time; import numpy as np, armkit; "
            f"sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r}); "
            "from planning import shelf, SHELF, R; "
            "from armkit.planning import CollisionChecker, default_geometry, plan; "
            "r=armkit.robot('inspection_6dof'); armkit.fk_frames(r, np.zeros((2, 6))); "
            "c=CollisionChecker(r, shelf(), default_geometry(r, 0.04), R); "
            "Q=np.random.default_rng(0).uniform(r.lower, r.upper, (20000, 6)); "
            "t=time.perf_counter(); p=time.process_time(); c.valid(np.zeros(6)); "
            "t1=time.perf_counter(); p1=time.process_time(); plan(c, *SHELF, seed=0); "
            "t2=time.perf_counter(); p2=time.process_time(); "
            "armkit.set_num_threads(os.cpu_count()); c.valid(Q); "
            "print(f'{t1-t:.2f} {p1-p:.2f} {t2-t1:.2f} {p2-p1:.2f} "
            "{time.perf_counter()-t2:.2f} {time.process_time()-p2:.2f}')")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, ARMKIT_JIT=mode)
        cold = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True).stdout.split()
        warm = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True).stdout.split()
    return (f"ARMKIT_JIT={mode}, empty numba cache: checker's first call {cold[0]} s wall, {cold[1]} s CPU; "
            f"then the first plan() {cold[2]} s wall, {cold[3]} s CPU; then the first batch "
            f"on {os.cpu_count()} threads {cold[4]} s wall, {cold[5]} s CPU. From the cache: "
            f"{warm[0]} s / {warm[1]} s, {warm[2]} s / {warm[3]} s and {warm[4]} s / {warm[5]} s")


# --- checker throughput ------------------------------------------------------------------------

def checker_figures(checker, quick):
    robot, geometry, scene = checker.robot, checker.geometry, checker.scene
    Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (200_000, 6))
    out = np.empty(len(Q))
    F, I = checker.model
    flat = Q.reshape(-1)
    cap = R * (1 + 1e-9) + 1e-12
    states_kernel(flat[:60], F, I, R, cap, out[:10])
    batch = rounds(lambda: states_kernel(flat, F, I, R, cap, out), 3 if quick else 5)
    exact = rounds(lambda: states_kernel(flat, F, I, -np.inf, np.inf, out), 3 if quick else 5)
    Qn = Q[:20_000]
    ref = numpy_free_distance(robot, geometry, scene, Qn)
    states_kernel(Qn.reshape(-1), F, I, -np.inf, np.inf, out[:len(Qn)])
    agree = np.abs(ref - out[:len(Qn)]).max()
    numpy_batch = rounds(lambda: numpy_free_distance(robot, geometry, scene, Qn), 3)
    single = Q[:5000]
    t_valid = rounds(lambda: [checker.valid(q) for q in single], 3) / len(single)
    none = np.empty(0)
    t_kernel = rounds(lambda: [states_kernel(q, F, I, R, cap, none) for q in single],
                      3) / len(single)
    t_numpy1 = rounds(lambda: [numpy_free_distance(robot, geometry, scene, q[None])
                               for q in single[:500]], 3) / 500
    auto = armkit.get_num_threads()
    public = rounds(lambda: checker.valid(Q), 3 if quick else 5)
    cores = os.cpu_count()
    armkit.set_num_threads(cores)
    try:
        checker.valid(Q[:20_000])
        spread = rounds(lambda: checker.valid(Q), 3 if quick else 5)
        spread_exact = rounds(lambda: checker.clearance(Q), 3 if quick else 5)
    finally:
        armkit.set_num_threads(None)
    print("\n## Checker: inspection_6dof capsules against the shelf, states per second "
          "(min/median/max over rounds)")
    print(f"compiled batch, verdict at r = 5 mm : {mmm(len(Q) / batch, fmt='{:,.0f}')}"
          "   (the kernel on one thread)")
    print(f"compiled batch, exact free distance : {mmm(len(Q) / exact, fmt='{:,.0f}')}"
          "   (the kernel on one thread)")
    print(f"checker.valid(Q), armkit's threads  : {mmm(len(Q) / public, fmt='{:,.0f}')}"
          f"   (armkit.get_num_threads() {auto} before the rounds)")
    print(f"checker.valid(Q), {cores} threads         : {mmm(len(Q) / spread, fmt='{:,.0f}')}"
          f"   (armkit.set_num_threads({cores}))")
    print(f"checker.clearance(Q), {cores} threads     : "
          f"{mmm(len(Q) / spread_exact, fmt='{:,.0f}')}")
    print(f"plain NumPy exact, batch            : {mmm(len(Qn) / numpy_batch, fmt='{:,.0f}')}"
          f"   (largest difference from compiled {agree:.1e} m)")
    print(f"ratio batch verdict / NumPy         : "
          f"{np.median(len(Q) / batch) / np.median(len(Qn) / numpy_batch):.0f}x (one thread), "
          f"{np.median(len(Q) / spread) / np.median(len(Qn) / numpy_batch):.0f}x "
          f"({cores} threads)")
    print(f"one state from Python, us: checker.valid(q) {mmm(t_valid, 1e6)}; kernel call "
          f"{mmm(t_kernel, 1e6)}; NumPy {mmm(t_numpy1, 1e6)}")


# --- planning ----------------------------------------------------------------------------------

def dense_fails(checker, path) -> bool:
    path = np.asarray(path)
    Q = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        k = max(int(np.ceil(np.abs(b - a).max() / 0.002)), 1)
        Q.append(a + (np.arange(1, k + 1) / k)[:, None] * (b - a))
    return bool((checker.clearance(np.vstack(Q)) <= 0).any())


def ours(checker, start, goal, planner, seeds):
    rows = []
    for s in seeds:
        res = plan(checker, start, goal, planner=planner, seed=s, time_limit=30,
                   max_iterations=300 if planner == "rrtstar" else None)
        rows.append((res.success, res.planning_time, res.states_checked, res.raw_length,
                     res.length, res.shortcut_time,
                     dense_fails(checker, res.path) if res.success else False))
    return rows


def ompl_runs(checker, start, goal, planner, seeds, resolution, time_limit):
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)
    n = checker.n
    rows = []
    for s in seeds:
        ou.RNG.setSeed(int(s) + 1)
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(checker.lower[i]))
            bounds.setHigh(i, float(checker.upper[i]))
        space.setBounds(bounds)
        ss = og.SimpleSetup(space)
        counter = [0]

        def valid(state, counter=counter):
            counter[0] += 1
            q = np.array([state[i] for i in range(n)])
            return bool(checker.valid_states(q[None])[0])

        ss.setStateValidityChecker(valid)
        si = ss.getSpaceInformation()
        if resolution is not None:
            si.setStateValidityCheckingResolution(resolution)
        a, b = space.allocState(), space.allocState()
        for i in range(n):
            a[i], b[i] = float(start[i]), float(goal[i])
        ss.setStartAndGoalStates(a, b)
        ss.setPlanner({"rrtconnect": og.RRTConnect, "rrt": og.RRT,
                       "rrtstar": og.RRTstar}[planner](si))
        ss.setup()
        t = time.perf_counter()
        solved = ss.solve(time_limit)
        dt = time.perf_counter() - t
        exact = bool(solved) and ss.haveExactSolutionPath()
        if not exact:
            rows.append((False, dt, counter[0], np.nan, np.nan, np.nan, False))
            continue
        checked = counter[0]
        raw = ss.getSolutionPath().length()
        t = time.perf_counter()
        ss.simplifySolution()
        ts = time.perf_counter() - t
        p = ss.getSolutionPath()
        path = np.array([[p.getState(k)[i] for i in range(n)] for k in range(p.getStateCount())])
        rows.append((True, dt, checked, raw, p.length(), ts, dense_fails(checker, path)))
    return rows


def report(name, rows):
    a = np.array(rows, dtype=float)
    ok = a[:, 0] > 0
    if not ok.any():
        print(f"| {name} | 0 % | | | | | | | |")
        return
    t = a[ok, 1] * 1e3
    print(f"| {name} | {100 * ok.mean():.0f} % | {np.median(t):.3g} | "
          f"{np.percentile(t, 90):.3g} | {np.median(a[ok, 2]):.0f} | "
          f"{np.median(a[ok, 3]):.3g} | {np.median(a[ok, 4]):.3g} | "
          f"{np.median(a[ok, 5]) * 1e3:.3g} | {int(a[ok, 6].sum())} |")


BOOKSHELF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                         "bookshelf.scene.yaml")


def scene_table(name, checker, start, goal, seeds, args) -> None:
    """The planners' table for one scene: armkit's three planners, OMPL's at the coarse and the
    safe resolution (the joint step keeping every point of the arm within r between checks)."""
    robot = checker.robot
    extent = float(np.linalg.norm(robot.upper - robot.lower))
    safe = R / np.linalg.norm(checker.weights) / extent
    plan(checker, start, goal, seed=0)                           # compiled before timing
    print(f"\n## {name}: {len(seeds)} seeds; times in ms; lengths joint-space rad")
    print("| planner | success | median | p90 | states checked | length | shortcut length |"
          " shortcut ms | dense fails |")
    print("|---|---|---|---|---|---|---|---|---|")
    for planner in ("rrtconnect", "rrt", "rrtstar"):
        report(f"armkit {planner} (certified, r = 5 mm)",
               ours(checker, start, goal, planner, seeds))
    if args.armkit_only:
        return
    report("OMPL RRTConnect, coarse (1 %)",
           ompl_runs(checker, start, goal, "rrtconnect", seeds, None, 10.0))
    if not args.no_ompl_safe:
        report(f"OMPL RRTConnect, safe ({safe:.2g}), 10 s",
               ompl_runs(checker, start, goal, "rrtconnect", seeds, safe, 10.0))
    report("OMPL RRT, coarse (1 %), 2 s", ompl_runs(checker, start, goal, "rrt", seeds,
                                                    None, 2.0))
    report("OMPL RRTstar, coarse (1 %), 1 s", ompl_runs(checker, start, goal, "rrtstar",
                                                       seeds, None, 1.0))


def bookshelf_table(seeds, args) -> None:
    """The UR5 among the bookshelf of examples/bookshelf.scene.yaml (its start and goal)."""
    from armkit.io.scene import read_planning_problem
    from armkit.planning import arm_geometry

    problem = read_planning_problem(BOOKSHELF)
    robot = problem.robot
    checker = CollisionChecker(robot, problem.scene, arm_geometry(robot, problem.radius), R)
    start, goal = problem.start, problem.goal[0]
    line = start + np.linspace(0, 1, 10_001)[:, None] * (goal - start)
    print(f"\nbookshelf: {robot.name}, {len(problem.scene)} obstacles; "
          f"{100 * np.mean(checker.clearance(line) <= 0):.0f} % of the straight joint line "
          f"collides")
    scene_table("bookshelf (UR5)", checker, start, goal, seeds, args)


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10 seeds, fewer rounds")
    parser.add_argument("--seeds", type=int, default=None, help="seeds per planner (100)")
    parser.add_argument("--no-ompl-safe", action="store_true",
                        help="skip OMPL at the safe resolution (slow)")
    parser.add_argument("--bookshelf-only", action="store_true",
                        help="only the UR5 bookshelf scene")
    parser.add_argument("--armkit-only", action="store_true",
                        help="armkit's rows only (no OMPL runs)")
    parser.add_argument("--checker-only", action="store_true",
                        help="the checker's throughput and first call only")
    args = parser.parse_args()
    seeds = range(args.seeds or (10 if args.quick else 100))
    print(f"load average at start: {os.getloadavg()}")
    if args.bookshelf_only:
        bookshelf_table(seeds, args)
        print(f"\nload average at end: {os.getloadavg()}")
        return
    robot = armkit.robot("inspection_6dof")
    geometry = default_geometry(robot, 0.04)
    for mode in ("auto", "compiled"):
        print(first_call_compile(mode))
    checker_figures(CollisionChecker(robot, shelf(), geometry, R), args.quick)
    if args.checker_only:
        print(f"\nload average at end: {os.getloadavg()}")
        return
    for scene_name, scene, (start, goal) in (("shelf", shelf(), SHELF),
                                             ("window", window(), WINDOW)):
        scene_table(scene_name, CollisionChecker(robot, scene, geometry, R), start, goal, seeds,
                    args)
    bookshelf_table(seeds, args)
    print(f"\nload average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
