"""Workspace speed: armkit.workspace in this process and on a 2-worker Dask LocalCluster, each
against a plain NumPy pipeline measured in the same run.

    python benchmarks/workspace.py            # n = 1e6 and 1e7
    python benchmarks/workspace.py --quick    # n = 1e6 only
    python benchmarks/workspace.py --big      # also n = 1e8, locally and on Dask, with memory

Robot: inspection_6dof (6R), voxels of 50 mm, chunks of armkit.workspace.CHUNK samples.
The baseline draws the same samples chunk by chunk, runs forward kinematics as a vectorised
NumPy einsum over the DH matrices (benchmarks/fk.py), and keeps bounds, reach and the set of
occupied voxels (np.unique and np.union1d): no Python loop over samples. Every figure is
min-median-max over rounds in which the baseline, armkit in this process (threads chosen by
armkit, and one thread) and armkit on Dask take turns (benchmarks/common.py); every ratio is
baseline time / armkit time at the same n, the ratio of the medians with the range of the
per-round ratios. The Dask cluster runs on loopback: two worker processes with one thread
each, started before the clock. The load average is printed before and after.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np
from distributed import Client, LocalCluster

import armkit
from armkit.jit import set_mode
from armkit.sampled_workspace import CHUNK
from common import interleaved, load, numpy_chain, ratio

ROBOT, RESOLUTION = "inspection_6dof", 0.05


def numpy_workspace(robot: armkit.Robot, n: int, seed: int = 0) -> tuple:
    """Bounds, reach and voxel volume the plain NumPy way, on armkit's samples."""
    fk = numpy_chain(robot.table)
    lower, upper = robot.sampling_limits
    lo, hi, reach, voxels = np.full(3, np.inf), np.full(3, -np.inf), 0.0, np.empty(0, np.int64)
    for i, start in enumerate(range(0, n, CHUNK)):
        q = np.random.default_rng([seed, i]).uniform(lower, upper, (min(CHUNK, n - start), 6))
        p = fk(q)[:, :3, 3]
        lo, hi = np.minimum(lo, p.min(axis=0)), np.maximum(hi, p.max(axis=0))
        reach = max(reach, float(np.sqrt((p * p).sum(axis=1).max())))
        ijk = np.floor(p / RESOLUTION).astype(np.int64) + 2**20
        voxels = np.union1d(voxels, np.unique((ijk[:, 0] << 42) | (ijk[:, 1] << 21) | ijk[:, 2]))
    return lo, hi, reach, voxels.size * RESOLUTION**3


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024       # ru_maxrss in KiB


def local_memory(n: int) -> None:
    """In a fresh process: peak memory after 1e6 samples, then after n, and n's time (JSON)."""
    robot = armkit.robot(ROBOT)
    armkit.workspace(robot, 1_000_000, resolution=RESOLUTION)
    small = peak_mb()
    t = time.perf_counter()
    ws = armkit.workspace(robot, n, resolution=RESOLUTION)
    seconds = time.perf_counter() - t
    print(json.dumps({"seconds": seconds, "peak_1e6_mb": small, "peak_mb": peak_mb(),
                      "voxels": len(ws.voxels), "volume_change": ws.volume_change}))


def worker_peaks_mb(client: Client) -> list[float]:
    return [v / 1024 for v in client.run(
        lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss).values()]


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="n = 1e6 only")
    parser.add_argument("--big", action="store_true", help="also n = 1e8 (a minute or two)")
    parser.add_argument("--memory-child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.memory_child:
        return local_memory(args.memory_child)
    robot = armkit.robot(ROBOT)
    sizes = [1_000_000] if args.quick else [1_000_000, 10_000_000]
    armkit.workspace(robot, 10_000, resolution=RESOLUTION)             # load the FK kernels
    print(f"{ROBOT}, voxels {RESOLUTION * 1000:g} mm, chunks of {CHUNK} samples; {load()}\n")
    print(f"{'case':24} {'n':>6} {'armkit':>24} {'NumPy':>24} {'ratio [per round]':>24}")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        armkit.workspace(robot, 300_000, resolution=RESOLUTION, scheduler=client)    # warm up
        for n in sizes:
            results = {}

            def run(case, scheduler=None, threads=None):
                def call():
                    armkit.set_num_threads(threads)
                    try:
                        results[case] = armkit.workspace(robot, n, resolution=RESOLUTION,
                                                         scheduler=scheduler)
                    finally:
                        armkit.set_num_threads(None)
                return call

            cases = {"local (this process)": run("local"),
                     "local, 1 thread": run("one", threads=1),
                     "Dask, 2 workers": run("dask", client)}
            times = interleaved({"numpy": lambda: numpy_workspace(robot, n), **cases},
                                3 if n <= 1_000_000 else 1)
            if n <= 1_000_000:                      # same samples: same bounds and volume
                lo, hi, reach, volume = numpy_workspace(robot, n)
                for ws in results.values():
                    assert np.allclose([ws.lower, ws.upper], [lo, hi], atol=1e-12)
                    assert abs(ws.reach - reach) < 1e-12
                    assert abs(ws.volume - volume) <= 2 * RESOLUTION**3
            for case in cases:
                print(f"{case:24} {n:6.0e} {times[case].text('s'):>24} "
                      f"{times['numpy'].text('s'):>24} {ratio(times['numpy'], times[case]):>24}")
        print(load())
        if args.big:
            n = 100_000_000
            before = worker_peaks_mb(client)
            t = time.perf_counter()
            ws = armkit.workspace(robot, n, resolution=RESOLUTION, scheduler=client)
            t = time.perf_counter() - t
            after = worker_peaks_mb(client)
            print(f"\nn = 1e8 on Dask (2 workers): {t:.1f} s ({n / t:.3g} samples/s), "
                  f"{len(ws.voxels)} voxels; worker peak memory "
                  f"{' and '.join(f'{b:.0f}' for b in before)} MB before, "
                  f"{' and '.join(f'{a:.0f}' for a in after)} MB after")
    if args.big:
        done = subprocess.run([sys.executable, __file__, "--memory-child", "100000000"],
                              check=True, capture_output=True, text=True)
        big = json.loads(done.stdout)
        print(f"n = 1e8 locally: {big['seconds']:.1f} s ({1e8 / big['seconds']:.3g} samples/s), "
              f"{big['voxels']} voxels, volume change {100 * big['volume_change']:.2g} % over "
              f"the last doubling; process peak memory {big['peak_1e6_mb']:.0f} MB after 1e6 "
              f"samples, {big['peak_mb']:.0f} MB after 1e8")


if __name__ == "__main__":
    main()
