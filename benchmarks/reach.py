"""Reachability map and base placement speed: a UR5 map in this process and on a 2-worker Dask
LocalCluster, and a placement with its map, each beside references measured in the same run.

    python benchmarks/reach.py            # UR5, 5 cm x 200 orientations: local, then Dask
    python benchmarks/reach.py --quick    # 10 cm x 200 (a quick look)
    python benchmarks/reach.py --big      # also 2.5 cm x 200 on Dask (tens of millions of IK
                                          # problems: many minutes; with --quick, the local
                                          # map it is compared with is the 10 cm one)
    python benchmarks/reach.py --numeric  # also a Panda map (numeric IK), 10 cm x 50

Map figures: wall time and CPU time of `armkit.reach_map` (two threads, `set_num_threads(2)`),
its IK problems (voxels x orientations) and the time per problem. References, on problems of
the same map:

- "batch IK": the same problems through the public `IKSolver.solutions` (every closed-form
  solution), one call per chunk of the map, on one thread: what the problems cost as IK alone;
  its ratio shows what the map adds (manipulability of every solution, bookkeeping) and what
  its threads win;
- "rtb ik_LM": roboticstoolbox's C++ Levenberg-Marquardt (`ETS.ik_LM`, its defaults), one
  call per problem, on a sample of the map's problems: what a user without closed forms pays.

Every ratio is reference time / armkit time per IK problem. Local and Dask runs (two worker
processes with one thread each, on loopback, started before the clock) then take turns on a
10 cm map, each pair checked bit for bit, with the wall and CPU time per problem of each (the
workers' own CPU for Dask): on a shared machine the CPU time per problem is the steadier
figure. With --big, a 2.5 cm map on Dask, its CPU per problem beside the local map's.
Placement: 10 grasp poses on a 1 m x 1 m floor at 5 cm and 10 deg of yaw (15,876 bases) with the
UR5 map, against the same placement without the map (closed-form IK at every base) and a
Python loop of `IKSolver.solutions` over the bases. The load average is printed before and
after; timings on a shared machine move with it.
"""

from __future__ import annotations

import argparse
import math
import resource
import time

import numpy as np

import armkit
from armkit.jit import set_mode
from armkit.reach import Orientations, base_placement, floor_grid, reach_map
from armkit.reach.maps import voxel_targets
from armkit.spatial import invert, pose_from_xyz_rpy
from common import load

ROBOT = "ur5"


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def worker_cpu(client) -> float:
    """CPU seconds (user + system) the Dask workers have used so far, summed."""
    def used() -> float:
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime
    return sum(client.run(used).values())


def timed(f):
    """(result, wall s, CPU s of this process)."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = f()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def chunks_of(m, count: int) -> list[np.ndarray]:
    """The IK targets of `count` of the map's chunks, evenly spread over its voxels."""
    size = m.settings["chunk"]
    starts = np.linspace(0, len(m.voxels) - size, count).astype(int)
    return [voxel_targets(m.robot, m.centers[s:s + size], m.orientations) for s in starts]


def batch_ik_reference(m, chunks: int) -> float:
    """Per-problem time (s) of `IKSolver.solutions` over `chunks` of the map's chunks, one
    thread."""
    solver = armkit.IKSolver(m.robot, threads=1)
    targets = chunks_of(m, chunks)
    solver.solutions(targets[0][:64])
    start = time.perf_counter()
    for T in targets:
        solver.solutions(T)
    return (time.perf_counter() - start) / sum(len(T) for T in targets)


def rtb_reference(m, count: int) -> float:
    """Per-problem time (s) of roboticstoolbox's C++ ik_LM over `count` of the map's problems."""
    import roboticstoolbox as rtb

    ets = rtb.models.DH.UR5().ets()
    T = np.concatenate(chunks_of(m, 8))
    T = T[np.random.default_rng(0).choice(len(T), count, replace=False)]
    ets.ik_LM(T[0])
    start = time.perf_counter()
    for target in T:
        ets.ik_LM(target)
    return (time.perf_counter() - start) / count


def grasps(count: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.array([pose_from_xyz_rpy([0.6 + 0.1 * rng.standard_normal(),
                                        0.2 * rng.standard_normal(), 0.2],
                                       [math.pi, 0.0, rng.uniform(-1, 1)])
                     for _ in range(count)])


def loop_placement(robot, task, grid) -> np.ndarray:
    """Feasible bases the plain way: one `IKSolver.solutions` call per base."""
    solver = armkit.IKSolver(robot)
    feasible = np.zeros(len(grid), dtype=bool)
    for b, T in enumerate(grid.poses):
        sols = solver.solutions(invert(T) @ task)
        feasible[b] = (sols.valid & sols.within_limits).any(axis=1).all()
    return feasible


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10 cm voxels")
    parser.add_argument("--big", action="store_true", help="also 2.5 cm on Dask")
    parser.add_argument("--orientations", type=int, default=200)
    parser.add_argument("--numeric", action="store_true",
                        help="also a Panda map (numeric IK, no closed form), 10 cm x 50")
    args = parser.parse_args()
    robot = armkit.robot(ROBOT)
    h = 0.1 if args.quick else 0.05
    orientations = Orientations.sphere(args.orientations)
    reach_map(robot, 0.3, orientations, samples=100_000)              # load the kernels
    print(f"{ROBOT}: {h * 100:g} cm voxels x {len(orientations)} orientations "
          f"({orientations.description}); {load()}\n")
    armkit.set_num_threads(2)
    m, wall, cpu = timed(lambda: reach_map(robot, h, orientations))
    armkit.set_num_threads(None)
    problems = len(m.voxels) * len(orientations)
    per = wall / problems
    print(f"map, this process (2 threads): {wall:.1f} s wall, {cpu:.1f} s CPU for "
          f"{len(m.voxels):,} voxels = {problems:,} IK problems: {per * 1e6:.2f} us/problem "
          f"wall, {cpu / problems * 1e6:.2f} us/problem CPU; peak memory {peak_mb():.0f} MB")
    batch = batch_ik_reference(m, 12)
    print(f"  batch IK (IKSolver.solutions, 1 thread): {batch * 1e6:.2f} us/problem; "
          f"ratio {batch / per:.2f}x")
    rtb = rtb_reference(m, 400)
    print(f"  rtb ik_LM (C++, per call):                {rtb * 1e6:.1f} us/problem; "
          f"ratio {rtb / per:.0f}x")
    print(f"  reachable volume {m.volume:.3f} m^3, {int((m.count > 0).sum()):,} voxels reach "
          f"some orientation, {int((m.count == len(orientations)).sum()):,} every one")

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        reach_map(robot, 0.3, orientations, samples=100_000, scheduler=client)   # warm up
        # Local and Dask in turns, on a 10 cm map: each pair sees the same load.
        small = 0.1
        print(f"\nlocal (2 threads) and Dask (2 worker processes) in turns, "
              f"{small * 100:g} cm x {len(orientations)}:")
        for round_ in range(3):
            here, wall_here, cpu_here = timed(lambda: reach_map(robot, small, orientations,
                                                                threads=2))
            before = worker_cpu(client)
            there, wall_there, _ = timed(lambda: reach_map(robot, small, orientations,
                                                           scheduler=client))
            cpu_there = worker_cpu(client) - before
            n = len(here.voxels) * len(orientations)
            same = all(np.array_equal(getattr(here, k), getattr(there, k))
                       for k in ("voxels", "count", "reached", "manipulability"))
            print(f"  round {round_ + 1}: local {wall_here / n * 1e6:.2f} us/problem wall, "
                  f"{cpu_here / n * 1e6:.2f} CPU; Dask {wall_there / n * 1e6:.2f} wall, "
                  f"{cpu_there / n * 1e6:.2f} CPU (workers); Dask/local wall "
                  f"{wall_there / wall_here:.2f}, CPU {cpu_there / cpu_here:.2f}; "
                  f"bit-identical: {same}")
        if args.big:
            before = worker_cpu(client)
            big, wall_big, _ = timed(lambda: reach_map(robot, 0.025, orientations,
                                                       scheduler=client))
            cpu_big = worker_cpu(client) - before
            n_big = len(big.voxels) * len(orientations)
            print(f"map 2.5 cm, Dask: {wall_big:.1f} s for {n_big:,} IK problems: "
                  f"{wall_big / n_big * 1e6:.2f} us/problem wall, {cpu_big / n_big * 1e6:.2f} "
                  f"CPU (workers); the local {h * 100:g} cm map's CPU per problem / this: "
                  f"{(cpu / problems) / (cpu_big / n_big):.2f}")
    print(load())

    if args.numeric:
        panda = armkit.robot("panda")
        armkit.set_num_threads(2)
        pm, wall_p, cpu_p = timed(lambda: reach_map(panda, 0.1, Orientations.sphere(50)))
        armkit.set_num_threads(None)
        n_p = len(pm.voxels) * 50
        print(f"\npanda map 10 cm x 50 (numeric, {pm.settings['restarts']} restarts): "
              f"{wall_p:.1f} s wall, {cpu_p:.1f} s CPU for {n_p:,} IK problems: "
              f"{wall_p / n_p * 1e6:.1f} us/problem wall, {cpu_p / n_p * 1e6:.1f} CPU; "
              f"reachable volume {pm.volume:.3f} m^3")

    task = grasps(10)
    grid = floor_grid((-0.5, 0.5), (-0.5, 0.5), 0.05, yaw_step=math.radians(10))
    placed, t_map, _ = timed(lambda: base_placement(robot, task, grid, reach_map=m))
    plain, t_ik, _ = timed(lambda: base_placement(robot, task, grid))
    looped, t_loop, _ = timed(lambda: loop_placement(robot, task, grid))
    assert np.array_equal(looped, plain.feasible)
    print(f"\nplacement: 10 poses x {len(grid):,} bases (1 m x 1 m at 5 cm, 10 deg): "
          f"{t_map:.2f} s with the map ({int(placed.feasible.sum()):,} feasible); without "
          f"the map {t_ik:.2f} s (ratio {t_ik / t_map:.2f}x); a loop of IKSolver.solutions "
          f"per base {t_loop:.2f} s (ratio {t_loop / t_map:.1f}x)")
    print(f"best base {placed.T_world_base[:3, 3].round(3).tolist()} m, yaw "
          f"{math.degrees(grid.yaws[placed.best]):.0f} deg, margin {placed.margin[placed.best]:.3f}"
          f" m; {load()}")


if __name__ == "__main__":
    main()
