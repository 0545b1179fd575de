"""The target from a point cloud: detection time on 100k points and accuracy over seeded scenes,
beside scikit-learn's DBSCAN measured in the same run.

    python benchmarks/perception.py            # 20 scenes per case, 15 timing rounds
    python benchmarks/perception.py --quick    # 5 scenes, 5 rounds
    python benchmarks/perception.py --pcl DIR --rings DIR    # and files nobody here wrote

The evidence table: walls with clutter (`armkit.perception.cluttered_scene`: domes, boxes,
small boxes, bars, bolts, handles) and no inlet, where any target reported is made up, and a
pipe beside three clutter objects, where a target more than 10 mm from the pipe's axis is the
wrong object. Reading: armkit's LZF decoder beside liblzf (python-lzf) on the same stream.
`--pcl` reads every PCD of a folder (PCL's test/ data: binary_compressed, organised clouds
with NaN); `--rings` looks for holes in ring-LiDAR scans (a ``ring`` field) of a board with
round holes, cropped to `--crop`.

Scenes: `armkit.perception.random_scene(seed)` for seeds 0..19, 100,000 rays each: a train wall
1.2-2.0 m away turned 15-40 deg about the vertical and +-10 deg in pitch, a pipe inlet of
radius 40 mm standing 100 mm out (its dark inside gives no returns, so only the sensor-facing
side is seen), range noise along the rays, 1 % uniform outliers. Errors are measured against
the scene's ground truth: the lateral centre error is the distance from the true axis, the axis
error the angle between the axes.

Reference: the same pipeline with scikit-learn's DBSCAN in place of armkit's (same eps and
min_samples, same labels). Open3D's plane segmentation and DBSCAN would be the second reference:
the open3d-cpu wheel installs here but does not import (libusb-1.0.so.0 is missing), so the
script says so and carries on.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from sklearn.cluster import DBSCAN

import armkit.perception.target as target_module
from armkit.jit import set_mode
from armkit.perception import (CLUTTER, cluttered_scene, dbscan, detect_target, random_scene,
                               ransac_plane)

N_POINTS, RADIUS = 100_000, 0.04


def rounds(f, repeat: int) -> np.ndarray:
    """Wall times (s) of `repeat` calls, after one warm-up call."""
    f()
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return np.array(out)


def cpu_rounds(f, repeat: int) -> np.ndarray:
    """CPU times (s) of this process over `repeat` calls: on a machine shared with other jobs,
    close to what the wall time would be on a quiet one (the pipeline runs on one thread)."""
    f()
    out = []
    for _ in range(repeat):
        t = time.process_time()
        f()
        out.append(time.process_time() - t)
    return np.array(out)


def mmm(t: np.ndarray, scale: float = 1e3) -> str:
    return f"{t.min() * scale:.1f} / {np.median(t) * scale:.1f} / {t.max() * scale:.1f}"


def sklearn_dbscan(points, eps, min_samples=5):
    return DBSCAN(eps=eps, min_samples=min_samples).fit(points).labels_


def with_sklearn(call):
    """Run `call` with scikit-learn's DBSCAN in the pipeline in place of armkit's."""
    own = target_module.dbscan
    target_module.dbscan = sklearn_dbscan
    try:
        return call()
    finally:
        target_module.dbscan = own


def errors(result, scene):
    T = scene.T_sensor_target
    z = T[:3, 2]
    d, c = result.centre - T[:3, 3], result.centroid - T[:3, 3]
    return (np.linalg.norm(d - (d @ z) * z), np.degrees(np.arccos(min(1.0, result.axis @ z))),
            np.linalg.norm(c - (c @ z) * z))


def timing(repeat: int) -> None:
    scene = random_scene(0, noise=0.002, n_points=N_POINTS)
    p = scene.points
    print(f"detection on {len(p):,} points (scene seed 0, 2 mm noise), ms, "
          f"min / median / max of {repeat} rounds")
    ours = rounds(lambda: detect_target(p, radius=RADIUS), repeat)
    theirs = rounds(lambda: with_sklearn(lambda: detect_target(p, radius=RADIUS)), repeat)
    plane = rounds(lambda: ransac_plane(p, 0.05, refits=1), repeat)
    print(f"  armkit detect_target (known radius)          {mmm(ours)}")
    cpu = cpu_rounds(lambda: detect_target(p, radius=RADIUS), repeat)
    print(f"    its CPU time (process_time)                {mmm(cpu)}")
    print(f"  same pipeline, scikit-learn DBSCAN           {mmm(theirs)}   "
          f"ratio {np.median(theirs) / np.median(ours):.2f}x")
    print(f"  of which the first wall (RANSAC + 1 refit)   {mmm(plane)}")
    free = rounds(lambda: detect_target(p), repeat)
    print(f"  armkit detect_target (radius fitted)         {mmm(free)}")
    # Clustering alone, on a dense set: every point of the cloud within 50 mm of the inlet,
    # and on the whole cloud.
    near = p[np.linalg.norm(p - scene.T_sensor_target[:3, 3], axis=1) < 0.3]
    for name, pts, eps in (("points within 0.3 m of the inlet", near, 0.01),
                           ("the whole cloud", p, 0.01)):
        a = rounds(lambda: dbscan(pts, eps, 5), max(repeat // 3, 2))
        b = rounds(lambda: sklearn_dbscan(pts, eps, 5), max(repeat // 3, 2))
        same = np.array_equal(dbscan(pts, eps, 5), sklearn_dbscan(pts, eps, 5))
        print(f"  DBSCAN eps 10 mm on {name} ({len(pts):,}): armkit {mmm(a)}, "
              f"scikit-learn {mmm(b)}, ratio {np.median(b) / np.median(a):.2f}x, "
              f"labels identical: {same}")


def accuracy(n_scenes: int) -> None:
    print(f"\naccuracy over {n_scenes} seeded scenes of {N_POINTS:,} points (mm; deg)")
    print("| noise | radius | pipeline | failures | lateral median | p95 | max | axis median "
          "| p95 | max | centroid's lateral error, median |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for noise in (0.002, 0.005):
        scenes = [random_scene(s, noise=noise, n_points=N_POINTS) for s in range(n_scenes)]
        for radius in (RADIUS, None):
            for name in ("armkit", "scikit-learn DBSCAN"):
                call = (lambda s: detect_target(s.points, radius=radius))
                results = [call(s) if name == "armkit" else with_sklearn(lambda: call(s))
                           for s in scenes]
                ok = [(r, s) for r, s in zip(results, scenes) if r.success]
                e = np.array([errors(r, s) for r, s in ok]) if ok else np.full((1, 3), np.nan)
                lat, ax, cen = e[:, 0] * 1e3, e[:, 1], e[:, 2] * 1e3
                print(f"| {noise * 1e3:g} mm | {'known' if radius else 'fitted'} | {name} | "
                      f"{len(scenes) - len(ok)} | {np.median(lat):.3f} | "
                      f"{np.percentile(lat, 95):.3f} | {lat.max():.3f} | {np.median(ax):.4f} | "
                      f"{np.percentile(ax, 95):.4f} | {ax.max():.4f} | {np.median(cen):.1f} |")


def numba_check(repeat: int) -> None:
    """Would numba pay on the one pass over every point (the wall's least-squares refit)?"""
    import numba

    @numba.njit(cache=False)
    def fused(p, n, d, thr):
        s = np.zeros(3)
        S = np.zeros((3, 3))
        k = 0
        for i in range(p.shape[0]):
            h = p[i, 0] * n[0] + p[i, 1] * n[1] + p[i, 2] * n[2] + d
            if abs(h) < thr:
                k += 1
                for a in range(3):
                    s[a] += p[i, a]
                    for b in range(3):
                        S[a, b] += p[i, a] * p[i, b]
        return s, S, k

    def vectorised(p, n, d, thr):
        q = np.compress(np.abs(p @ n + d) < thr, p, axis=0)
        return q.sum(axis=0), q.T @ q, len(q)

    scene = random_scene(0, noise=0.002, n_points=N_POINTS)
    p, n, d = scene.points, scene.plane_normal, scene.plane_offset
    t0 = time.perf_counter()
    fused(p, n, d, 0.01)
    compile_s = time.perf_counter() - t0
    a = rounds(lambda: fused(p, n, d, 0.01), repeat * 3)
    b = rounds(lambda: vectorised(p, n, d, 0.01), repeat * 3)
    print(f"\nnumba check, inliers and moments of the wall in one pass over {len(p):,} points: "
          f"numba {mmm(a)} ms (compile {compile_s:.2f} s), NumPy {mmm(b)} ms")


def evidence(n_seeds: int) -> None:
    """The detector's table: made-up targets on walls with clutter and no inlet, the wrong
    object beside clutter, and the time a cluttered scan takes beside a clean one."""
    print(f"\nevidence: walls with clutter ({', '.join(CLUTTER)}), 30,000 rays, 2 mm noise")
    made_up, total = {}, 0
    for seed in range(n_seeds):
        for kinds in [(k,) for k in CLUTTER] + [tuple(CLUTTER)]:
            scene = cluttered_scene(seed, None, kinds)
            for radius in (None, RADIUS):
                total += 1
                if detect_target(scene.points, radius=radius).success:
                    name = "+".join(kinds) if len(kinds) == 1 else "all six"
                    made_up[name] = made_up.get(name, 0) + 1
    print(f"| scans without an inlet | made-up targets |\n|---|---|\n| {total} | "
          f"{sum(made_up.values())} {made_up or ''} |")
    lateral, wrong, missed = [], 0, 0
    for seed in range(n_seeds * 3):
        kinds = tuple(np.random.default_rng(seed).choice(CLUTTER, 3, replace=False))
        scene = cluttered_scene(seed, "pipe", kinds)
        for radius in (None, RADIUS):
            result = detect_target(scene.points, radius=radius)
            if not result.success:
                missed += 1
                continue
            e = errors(result, scene)[0]
            wrong += e > 0.01
            lateral.append(e * 1e3)
    lateral = np.array(lateral)
    print(f"| scans with a pipe beside 3 clutter objects | right object | wrong object | no "
          f"target | lateral error median / max (mm) |\n|---|---|---|---|---|\n"
          f"| {n_seeds * 6} | {len(lateral) - wrong} | {wrong} | {missed} | "
          f"{np.median(lateral):.3f} / {lateral.max():.3f} |")
    clean = random_scene(0, noise=0.002, n_points=30_000).points
    busy = cluttered_scene(0, "pipe", tuple(CLUTTER)).points
    a = rounds(lambda: detect_target(busy, radius=RADIUS), 7)
    b = rounds(lambda: detect_target(clean, radius=RADIUS), 7)
    print(f"detect_target on a cluttered scan (6 objects) {mmm(a)} ms, on a clean one "
          f"{mmm(b)} ms: ratio {np.median(a) / np.median(b):.2f}x")


def reading(repeat: int) -> None:
    """Reading a PCL binary_compressed PCD: armkit's own LZF decoder beside liblzf (python-lzf)
    on the same stream, and the whole read beside an uncompressed binary file."""
    import tempfile
    from pathlib import Path

    import lzf

    from armkit.io.clouds import lzf_decompress, read_cloud, write_pcd
    scene = random_scene(0, noise=0.002, n_points=N_POINTS)
    ring = (np.arange(len(scene.points)) % 64).astype("u2")
    with tempfile.TemporaryDirectory() as folder:
        packed = write_pcd(Path(folder) / "c.pcd", scene.points, "m", fields={"ring": ring})
        plain = write_pcd(Path(folder) / "b.pcd", scene.points, "m", data="binary",
                          fields={"ring": ring})
        raw = (scene.points.astype("<f4").T.tobytes() + ring.tobytes())
        stream = lzf.compress(raw)
        ours = rounds(lambda: lzf_decompress(stream, len(raw)), repeat)
        theirs = rounds(lambda: lzf.decompress(stream, len(raw) + 1), repeat)
        a = rounds(lambda: read_cloud(packed), repeat)
        b = rounds(lambda: read_cloud(plain), repeat)
    print(f"\nreading {len(scene.points):,} points with a ring field (ms):")
    print(f"  LZF decode of {len(stream):,} bytes: armkit {mmm(ours)}, liblzf {mmm(theirs)}, "
          f"ratio {np.median(ours) / np.median(theirs):.2f}x")
    print(f"  read_cloud binary_compressed {mmm(a)}, binary {mmm(b)}, ratio "
          f"{np.median(a) / np.median(b):.2f}x")


def real_files(pcl: str | None, rings: str | None, crop: list[float] | None) -> None:
    """Files nobody here wrote: every PCD in a folder (PCL's test data), and ring-LiDAR scans
    of a board with round holes (kind hole, cropped to the board's surroundings)."""
    from pathlib import Path

    from armkit.errors import ArmkitError
    from armkit.io.clouds import read_cloud
    if pcl:
        read, refused = 0, []
        for path in sorted(Path(pcl).glob("*.pcd")):
            try:
                read_cloud(path, "m")
                read += 1
            except ArmkitError as err:
                refused.append(f"{path.name}: {str(err).split(': ', 2)[-1][:80]}")
        print(f"\n{pcl}: {read} PCD files read, {len(refused)} refused")
        for line in refused:
            print(f"  refused {line}")
    if rings:
        lo, hi = np.array(crop[0::2]), np.array(crop[1::2])
        print(f"\nring-LiDAR scans in {rings}, cropped to {lo} .. {hi} m, kind hole:")
        for path in sorted(Path(rings).glob("*.pcd")):
            cloud = read_cloud(path, "m")
            keep = ((cloud.points > lo) & (cloud.points < hi)).all(axis=1)
            result = detect_target(cloud.points[keep], kind="hole",
                                   rings=cloud.fields["ring"][keep].astype(np.int64))
            holes = sum(c.passed for c in result.considered)
            print(f"  {path.name}: {result.rows} rings, range noise "
                  f"{result.range_noise * 1e3:.1f} mm, {holes} of {len(result.considered)} "
                  f"openings pass; " + (f"target at {np.round(result.centre * 1e3)} mm, r "
                                        f"{result.radius * 1e3:.1f} mm, rim RMS "
                                        f"{result.fit_rms * 1e3:.2f} mm" if result.success
                                        else f"no target: {result.reason}"))


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--pcl", help="a folder of PCD files to read (PCL's test data)")
    parser.add_argument("--rings", help="a folder of ring-LiDAR PCD scans of a board with "
                                        "holes (with a ring field)")
    parser.add_argument("--crop", type=float, nargs=6, metavar=("X0", "X1", "Y0", "Y1", "Z0",
                                                                "Z1"),
                        default=[2, 14, -0.2, 1.6, -1.0, 0.4],
                        help="the box (m) around the board kept for --rings")
    args = parser.parse_args()
    repeat, n_scenes = (5, 5) if args.quick else (15, 20)
    print(f"load average at start: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    try:
        import open3d  # noqa: F401
        print("Open3D is importable, but this script has no Open3D pipeline yet")
    except ImportError as err:
        print(f"Open3D: not available here ({err}); no Open3D figures")
    timing(repeat)
    numba_check(repeat)
    accuracy(n_scenes)
    evidence(n_scenes * 2 if not args.quick else 3)
    reading(repeat)
    real_files(args.pcl, args.rings, args.crop)
    print(f"load average at end: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
