"""Plain-NumPy references for the planning tests, written apart from the compiled checker:
capsule segments from `armkit.fk_frames`, point distances in closed form, and the distance from
a segment to an obstacle by minimising the point distance along it (scipy, bounded)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from armkit import fk_frames
from armkit.planning import Box, Cylinder, Sphere


def local(T: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Points p (..., 3) in the frame whose pose is T (4, 4)."""
    return (p - T[:3, 3]) @ T[:3, :3]


def point_distance(obstacle, p: np.ndarray) -> np.ndarray:
    """Distance (m) from points p (..., 3) to the obstacle; 0 inside boxes and cylinders,
    minus the depth inside spheres and capsules."""
    if isinstance(obstacle, Box):
        x = np.abs(local(obstacle.pose, p)) - obstacle.size / 2
        return np.linalg.norm(np.maximum(x, 0), axis=-1)
    if isinstance(obstacle, Sphere):
        return np.linalg.norm(p - obstacle.center, axis=-1) - obstacle.radius
    if isinstance(obstacle, Cylinder):
        x = local(obstacle.pose, p)
        dr = np.maximum(np.hypot(x[..., 0], x[..., 1]) - obstacle.radius, 0)
        dz = np.maximum(np.abs(x[..., 2]) - obstacle.length / 2, 0)
        return np.hypot(dr, dz)
    d = obstacle.b - obstacle.a
    t = np.clip(((p - obstacle.a) @ d) / (d @ d), 0, 1)
    return np.linalg.norm(p - (obstacle.a + t[..., None] * d), axis=-1) - obstacle.radius


def segment_obstacle(obstacle, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from the segment a-b to the obstacle: the convex point distance minimised along
    the segment from a grid's best point (bounded Brent)."""
    t = np.linspace(0, 1, 201)
    values = point_distance(obstacle, a + t[:, None] * (b - a))
    k = int(np.argmin(values))
    lo, hi = t[max(k - 1, 0)], t[min(k + 1, 200)]
    res = minimize_scalar(lambda s: float(point_distance(obstacle, a + s * (b - a))),
                          bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    return float(min(values.min(), res.fun))


def segment_segment(a, b, c, e) -> float:
    """Distance between segments a-b and c-e: the convex distance minimised over (s, t) on a
    grid and then along each parameter (alternating, exact per step)."""
    s = np.linspace(0, 1, 101)
    P, R = a + s[:, None] * (b - a), c + s[:, None] * (e - c)
    D = np.linalg.norm(P[:, None] - R[None], axis=-1)
    i, j = np.unravel_index(np.argmin(D), D.shape)
    si, tj = s[i], s[j]

    def closest(p, q0, q1):
        d = q1 - q0
        dd = d @ d
        return 0.0 if dd == 0 else float(np.clip((p - q0) @ d / dd, 0, 1))

    for _ in range(200):
        tj = closest(a + si * (b - a), c, e)
        si = closest(c + tj * (e - c), a, b)
    return float(min(D.min(), np.linalg.norm(a + si * (b - a) - c - tj * (e - c))))


def capsules(robot, geometry, q):
    """World segments (m, 3), (m, 3) of the arm's capsules at q (n,), from fk_frames."""
    F = fk_frames(robot, q)[geometry.link]
    a = np.einsum("mij,mj->mi", F[:, :3, :3], geometry.a) + F[:, :3, 3]
    b = np.einsum("mij,mj->mi", F[:, :3, :3], geometry.b) + F[:, :3, 3]
    return a, b


def free_distance(robot, geometry, scene, q) -> float:
    """min(obstacle gaps, self gaps / 2), as the checker defines it, by the references."""
    a, b = capsules(robot, geometry, q)
    best = np.inf
    for k in range(len(geometry)):
        for o in scene:
            best = min(best, segment_obstacle(o, a[k], b[k]) - geometry.radius[k])
    for i, j in geometry.self_pairs():
        gap = segment_segment(a[i], b[i], a[j], b[j]) - geometry.radius[i] - geometry.radius[j]
        best = min(best, gap / 2)
    return best


def dense_gaps(robot, geometry, scene, path, step: float = 0.002, points: int = 400):
    """The smallest obstacle gap and self gap (m) along the polyline path (k, n), checked at
    configurations no more than `step` (rad or m, any joint) apart, each capsule's axis sampled
    at `points` points (the gap found is then an upper bound within half their spacing)."""
    path = np.asarray(path, float)
    Q = [path[:1]]
    for qa, qb in zip(path[:-1], path[1:]):
        k = max(int(np.ceil(np.abs(qb - qa).max() / step)), 1)
        Q.append(qa + (np.arange(1, k + 1) / k)[:, None] * (qb - qa))
    Q = np.vstack(Q)
    obstacle_gap, self_gap = np.inf, np.inf
    t = np.linspace(0, 1, points)[:, None, None, None]
    u = np.linspace(0, 1, points // 5)[:, None, None]
    for chunk in np.array_split(Q, max(len(Q) // 200, 1)):
        F = fk_frames(robot, chunk)[:, geometry.link]                   # (S, m, 4, 4)
        A = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.a) + F[..., :3, 3]
        B = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.b) + F[..., :3, 3]
        P = A[None] + t * (B - A)[None]                                 # (points, S, m, 3)
        for o in scene:
            d = point_distance(o, P).min(axis=0) - geometry.radius       # (S, m)
            obstacle_gap = min(obstacle_gap, float(d.min()))
        for i, j in geometry.self_pairs():
            Pi = A[None, :, i] + u * (B - A)[None, :, i]                # (points/5, S, 3)
            Pj = A[None, :, j] + u * (B - A)[None, :, j]
            D = np.linalg.norm(Pi[:, None] - Pj[None], axis=-1).min()
            self_gap = min(self_gap, float(D - geometry.radius[i] - geometry.radius[j]))
    return obstacle_gap, self_gap, len(Q)


def dense_ok(checker, path, step: float = 0.002, points: int = 60) -> bool:
    """The independent check of a planned path: every `step` rad along it, each sampled
    configuration keeps more than the checker's padding from every obstacle, and twice it
    between the arm's tested parts (what certification promises)."""
    obstacle_gap, self_gap, _ = dense_gaps(checker.robot, checker.geometry, checker.scene, path,
                                           step=step, points=points)
    return obstacle_gap > checker.padding and self_gap > 2 * checker.padding
