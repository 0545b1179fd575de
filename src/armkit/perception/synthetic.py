"""Synthetic LiDAR scans of a train's side with a water inlet, and their ground truth.

The sensor sits at the origin of its frame (x forward, y left, z up, as LiDARs report). The
train's side is a plane at `distance` along x, turned by `yaw` about z and `pitch` about y. The
inlet is either a pipe (a thin-walled open cylinder of `radius`, standing `length` out of the
wall along its normal) or a round hole in the wall (with, optionally, a back surface `depth`
behind it that the rays through the hole reach). Every point is a ray cast from the origin: the
nearest surface it meets, then moved along the ray by Gaussian range noise. Outliers are points
drawn uniformly in the scene's bounding box. Rays form a regular azimuth-elevation grid, or, with
`rings`, a few elevation rings densely sampled in azimuth, as a spinning multi-beam LiDAR scans.

By default the inside of the pipe is dark (no returns), so only its sensor-facing side is seen.

Ground truth: for a pipe, the target frame's origin is the centre of the pipe's mouth (its open
end); for a hole, the hole's centre on the wall. Its z axis is the inlet's axis, the wall's
normal pointing out of the wall toward the sensor; its y axis is the sensor's z (up) projected on
the wall (the sensor's y where up is normal to the wall); x = y cross z.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.spatial import roty, rotz


@dataclass(frozen=True)
class SyntheticScene:
    """A synthetic scan and its ground truth; lengths in m, frames in the sensor frame.

    Attributes
    ----------
    points : ndarray, shape (N, 3)
        The scan, m, in the sensor frame.
    T_sensor_target : ndarray, shape (4, 4)
        The inlet's true pose (see the module's docstring for the frame).
    kind : {"pipe", "hole"}
    radius : float
        Inlet radius, m.
    plane_normal : ndarray, shape (3,)
        Unit normal of the wall, pointing toward the sensor.
    plane_offset : float
        d of the wall's plane ``n . x + d = 0``, m.
    outlier : ndarray, shape (N,), bool
        Which points are outliers.
    noise : float
        Standard deviation of the range noise, m.
    seed : int or None
    labels : ndarray, shape (N,), int, or None
        What each point hit: 0 the wall, 1 the inlet (or the hole's back surface), 2 + i the
        i-th clutter object, -1 an outlier (`cluttered_scene`; None for `synthetic_scene`).
    objects : tuple of Clutter
        The clutter objects (`cluttered_scene`).
    """

    points: NDArray
    T_sensor_target: NDArray
    kind: str
    radius: float
    plane_normal: NDArray
    plane_offset: float
    outlier: NDArray
    noise: float
    seed: int | None
    labels: NDArray | None = field(default=None, repr=False)
    objects: tuple = ()


def _target_frame(normal: NDArray, origin: NDArray) -> NDArray:
    """Pose whose z is `normal` and whose y is the sensor's up (z) projected on the plane."""
    z = normal / np.linalg.norm(normal)
    up = np.array([0.0, 0.0, 1.0])
    y = up - z * (up @ z)
    if np.linalg.norm(y) < 1e-6:                 # the wall faces straight up or down
        y = np.array([0.0, 1.0, 0.0]) - z * z[1]
    y /= np.linalg.norm(y)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = np.cross(y, z), y, z, origin
    return T


def target_frame(normal: NDArray, origin: NDArray) -> NDArray:
    """The inlet frame convention (see module docstring): z along `normal`, origin `origin`.

    Parameters
    ----------
    normal : array_like, shape (3,)
        The inlet's axis (need not be unit length).
    origin : array_like, shape (3,)
        The frame's origin, m.

    Returns
    -------
    T : ndarray, shape (4, 4)
    """
    return _target_frame(np.asarray(normal, float), np.asarray(origin, float))


def _ray_directions(n_rays: int, half_az: float, half_el: float, rings: int | None,
                    rng: np.random.Generator) -> NDArray:
    """Unit ray directions (M, 3) covering +-half_az in azimuth and +-half_el in elevation."""
    if rings:
        n_az = max(round(n_rays / rings), 2)
        el = np.linspace(-half_el, half_el, rings)
        az = np.linspace(-half_az, half_az, n_az)
        az = az + rng.uniform(0, az[1] - az[0])   # the scan's start varies from turn to turn
        A, E = np.meshgrid(az, el)
    else:
        n_side = max(int(round(np.sqrt(n_rays * half_az / half_el))), 2)
        n_el = max(round(n_rays / n_side), 2)
        A, E = np.meshgrid(np.linspace(-half_az, half_az, n_side),
                           np.linspace(-half_el, half_el, n_el))
    A, E = A.ravel(), E.ravel()
    return np.stack([np.cos(E) * np.cos(A), np.cos(E) * np.sin(A), np.sin(E)], axis=1)


def _cylinder_hits(d: NDArray, centre: NDArray, axis: NDArray, radius: float,
                   length: float) -> tuple[NDArray, NDArray, NDArray]:
    """Rays d (M, 3) from the origin against a thin-walled open cylinder.

    The cylinder's axis runs from `centre` (on the wall) along `axis` for `length`. Returns the
    range to the outer surface (inf where the ray misses it), which rays enter the open mouth,
    and their range to the inner far side.
    """
    o = -centre                                   # ray origin relative to the cylinder base
    d_perp = d - np.outer(d @ axis, axis)
    o_perp = o - (o @ axis) * axis
    a = np.einsum("ij,ij->i", d_perp, d_perp)
    b = 2.0 * (d_perp @ o_perp)
    c = o_perp @ o_perp - radius**2
    disc = b * b - 4 * a * c
    ok = (disc >= 0) & (a > 1e-15)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    denom = np.where(ok, 2 * a, 1.0)
    s0, s1 = o @ axis, d @ axis
    t_near, t_far = (-b - sq) / denom, (-b + sq) / denom

    def valid(t: NDArray) -> NDArray:
        s = s0 + t * s1
        return ok & (t > 0) & (s >= 0) & (s <= length)

    near_ok, far_ok = valid(t_near), valid(t_far)
    return np.where(near_ok, t_near, np.inf), far_ok & ~near_ok, np.where(far_ok, t_far, np.inf)


def synthetic_scene(kind: Literal["pipe", "hole"] = "pipe", *, noise: float = 0.002,
                    n_points: int = 20_000, distance: float = 1.5, yaw: float = 0.5,
                    pitch: float = 0.1, offset: tuple[float, float] = (0.05, -0.03),
                    radius: float = 0.04, length: float = 0.10, depth: float | None = 0.15,
                    window: float = 0.8, outliers: float = 0.01, rings: int | None = None,
                    interior: bool = False, seed: int | None = 0) -> SyntheticScene:
    """A scan of a train wall with a pipe inlet or a hole, and its ground truth.

    Parameters
    ----------
    kind : {"pipe", "hole"}
    noise : float
        Standard deviation of the range noise along each ray, m.
    n_points : int
        Number of rays cast (the scan has about this many points).
    distance : float
        Distance of the wall from the sensor along x, m.
    yaw, pitch : float
        Turn of the wall about the sensor's z and y axes, rad.
    offset : (float, float)
        The inlet's place on the wall from the point straight ahead, along the wall's horizontal
        and vertical directions, m.
    radius, length : float
        Pipe or hole radius, and how far the pipe stands out of the wall, m.
    depth : float or None
        For a hole, the back surface's distance behind the wall (m); None for no returns through
        the hole.
    window : float
        Width and height of the scanned part of the wall, m.
    outliers : float
        Fraction of points replaced by uniform outliers, 0 .. 1.
    rings : int or None
        Number of scan rings (elevation lines); None for a regular grid.
    interior : bool
        Whether rays entering the pipe's open mouth return from its inner far side; by default
        the inside is dark (no return), so only the sensor-facing side of the pipe is seen.
    seed : int or None

    Returns
    -------
    SyntheticScene
    """
    if kind not in ("pipe", "hole"):
        raise InputError(f"kind: expected 'pipe' or 'hole', found {kind!r}")
    if not (n_points >= 100 and noise >= 0 and radius > 0 and distance > 0 and 0 <= outliers < 1):
        raise InputError("synthetic_scene: expected n_points >= 100, noise >= 0, radius > 0, "
                         f"distance > 0 and 0 <= outliers < 1, found n_points={n_points}, "
                         f"noise={noise}, radius={radius}, distance={distance}, "
                         f"outliers={outliers}")
    rng = np.random.default_rng(seed)
    R = rotz(yaw) @ roty(pitch)
    normal = R @ np.array([-1.0, 0.0, 0.0])
    horizontal, vertical = R @ np.array([0.0, 1.0, 0.0]), R @ np.array([0.0, 0.0, 1.0])
    wall_point = np.array([distance, 0.0, 0.0])
    centre = wall_point + offset[0] * horizontal + offset[1] * vertical
    d_plane = -normal @ wall_point

    half = np.arctan2(window / 2, distance)
    n_rays = int(round(n_points / (1 - outliers)))
    dirs = _ray_directions(n_rays, half, half, rings, rng)
    t = -d_plane / (dirs @ normal)                # every ray meets the (infinite) wall
    if kind == "pipe":
        outer, into_mouth, inner = _cylinder_hits(dirs, centre, normal, radius, length)
        t = np.minimum(t, outer)
        if interior:
            t = np.where(into_mouth, inner, t)
        else:                                     # a dark inside: no return
            t, dirs = t[~into_mouth], dirs[~into_mouth]
    else:
        on_wall = dirs * t[:, None]
        in_hole = np.linalg.norm(on_wall - centre, axis=1) < radius
        if depth is None:
            t, dirs = t[~in_hole], dirs[~in_hole]
        else:
            t_back = -(d_plane + depth) / (dirs @ normal)
            t = np.where(in_hole, t_back, t)
    t = t + rng.normal(0.0, noise, len(t))
    points = dirs * t[:, None]

    n_out = int(round(outliers * len(points)))
    outlier = np.zeros(len(points), bool)
    if n_out:
        idx = rng.choice(len(points), n_out, replace=False)
        lo, hi = points.min(axis=0), points.max(axis=0)
        pad = 0.1 * (hi - lo)
        points[idx] = rng.uniform(lo - pad, hi + pad, (n_out, 3))
        outlier[idx] = True
    origin = centre + length * normal if kind == "pipe" else centre
    return SyntheticScene(points=points, T_sensor_target=_target_frame(normal, origin),
                          kind=kind, radius=float(radius), plane_normal=normal,
                          plane_offset=float(d_plane), outlier=outlier, noise=float(noise),
                          seed=seed)


def random_scene(seed: int, kind: Literal["pipe", "hole"] = "pipe", *, noise: float = 0.002,
                 n_points: int = 20_000, **kwargs) -> SyntheticScene:
    """A scene with its pose drawn from `seed`: the wall turned 15 .. 40 deg either way about
    the vertical (the sensor looks at the train's side at an angle, so that it sees the side of
    the pipe), pitch +-10 deg, distance 1.2 .. 2.0 m, the inlet within +-0.15 m of the point
    straight ahead.

    Other keyword arguments go to `synthetic_scene`.
    """
    rng = np.random.default_rng([seed, 18])
    yaw = np.deg2rad(rng.uniform(15, 40)) * rng.choice([-1.0, 1.0])
    pitch = np.deg2rad(rng.uniform(-10, 10))
    params = dict(distance=float(rng.uniform(1.2, 2.0)), yaw=float(yaw), pitch=float(pitch),
                  offset=tuple(rng.uniform(-0.15, 0.15, 2)))
    params.update(kwargs)
    return synthetic_scene(kind, noise=noise, n_points=n_points, seed=seed, **params)


# --- clutter: what stands on a wall and is not an inlet -------------------------------------

CLUTTER = ("dome", "box", "small_box", "bar", "bolt", "handle")


@dataclass(frozen=True)
class Clutter:
    """An object on the wall that is not the inlet.

    Attributes
    ----------
    kind : {"dome", "box", "small_box", "bar", "bolt", "handle"}
    centre : ndarray, shape (3,)
        Where it stands on the wall (its foot's centre), sensor frame, m.
    size : float
        Radius of the smallest circle about `centre` in the wall's plane that holds it, m.
    parts : tuple
        Its surfaces: ("sphere", centre, radius), ("box", T, size), ("cylinder", a, b, radius)
        (capped), in the sensor frame.
    """

    kind: str
    centre: NDArray
    size: float
    parts: tuple


def _sphere_ranges(d: NDArray, centre: NDArray, radius: float) -> NDArray:
    """Range along rays d (M, 3) from the origin to a sphere's near side (inf: a miss)."""
    b = d @ centre
    c = centre @ centre - radius**2
    disc = b * b - c
    t = b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc >= 0) & (t > 0), t, np.inf)


def _box_ranges(d: NDArray, T: NDArray, size: NDArray) -> NDArray:
    """Range along rays d (M, 3) from the origin to a box of `size` at pose T (slabs)."""
    R, origin = T[:3, :3], T[:3, 3]
    o = -origin @ R                               # the sensor in the box's frame
    dl = d @ R
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-size / 2 - o) / dl
        t2 = (size / 2 - o) / dl
    lo = np.nanmax(np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2)), axis=1)
    hi = np.nanmin(np.where(np.isnan(t1), np.inf, np.maximum(t1, t2)), axis=1)
    return np.where((lo <= hi) & (lo > 0), lo, np.inf)


def _capped_cylinder_ranges(d: NDArray, a: NDArray, b: NDArray, radius: float) -> NDArray:
    """Range along rays d (M, 3) from the origin to a closed cylinder from a to b."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    axis = axis / length
    side, _, _ = _cylinder_hits(d, a, axis, radius, length)
    t = side
    for centre, normal in ((a, -axis), (b, axis)):
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = (centre @ normal) / (d @ normal)
        hit = d * tc[:, None] - centre
        inside = (tc > 0) & (np.linalg.norm(hit, axis=1) <= radius)
        t = np.minimum(t, np.where(inside, tc, np.inf))
    return t


def _part_ranges(d: NDArray, part: tuple) -> NDArray:
    kind = part[0]
    if kind == "sphere":
        return _sphere_ranges(d, part[1], part[2])
    if kind == "box":
        return _box_ranges(d, part[1], part[2])
    return _capped_cylinder_ranges(d, part[1], part[2], part[3])


def clutter_object(kind: str, foot: NDArray, normal: NDArray, along: NDArray,
                   rng: np.random.Generator) -> Clutter:
    """A clutter object of `kind` with random dimensions standing on the wall at `foot`.

    Parameters
    ----------
    kind : one of CLUTTER
    foot : array_like, shape (3,)
        Its place on the wall, m.
    normal : array_like, shape (3,)
        The wall's unit normal, toward the sensor.
    along : array_like, shape (3,)
        A unit direction in the wall (a bar's or handle's length, a box's edge).
    rng : numpy.random.Generator
    """
    n, u = np.asarray(normal, float), np.asarray(along, float)
    v = np.cross(n, u)
    foot = np.asarray(foot, float)
    if kind == "dome":
        r = rng.uniform(0.03, 0.06)
        return Clutter(kind, foot, r, (("sphere", foot, r),))
    if kind in ("box", "small_box"):
        if kind == "box":
            w, h, depth = rng.uniform(0.06, 0.12), rng.uniform(0.06, 0.12), rng.uniform(0.03, 0.10)
        else:
            w, h = rng.uniform(0.02, 0.05), rng.uniform(0.02, 0.05)
            depth = rng.uniform(0.015, 0.04)
        T = np.eye(4)
        T[:3, 0], T[:3, 1], T[:3, 2] = u, v, n
        T[:3, 3] = foot + n * depth / 2
        return Clutter(kind, foot, float(np.hypot(w, h) / 2),
                       (("box", T, np.array([w, h, depth])),))
    if kind == "bar":
        r, length, off = rng.uniform(0.01, 0.02), rng.uniform(0.15, 0.30), rng.uniform(0.02, 0.06)
        a, b = foot - u * length / 2 + n * (off + r), foot + u * length / 2 + n * (off + r)
        return Clutter(kind, foot, length / 2 + r, (("cylinder", a, b, r),))
    if kind == "bolt":
        r, height = rng.uniform(0.006, 0.012), rng.uniform(0.005, 0.010)
        return Clutter(kind, foot, r, (("cylinder", foot - 0.001 * n, foot + height * n, r),))
    if kind == "handle":
        r, length = rng.uniform(0.008, 0.012), rng.uniform(0.10, 0.20)
        post = rng.uniform(0.04, 0.07)
        ends = (foot - u * length / 2, foot + u * length / 2)
        parts = tuple(("cylinder", e - 0.001 * n, e + post * n, r) for e in ends)
        parts += (("cylinder", ends[0] + post * n, ends[1] + post * n, r),)
        return Clutter(kind, foot, length / 2 + r, parts)
    raise InputError(f"kind: expected one of {', '.join(CLUTTER)}, found {kind!r}")


def cluttered_scene(seed: int, target: Literal["pipe", "hole"] | None = "pipe",
                    clutter: tuple[str, ...] | None = None, *, noise: float = 0.002,
                    n_points: int = 30_000, gap: float = 0.08, rings: int | None = None,
                    outliers: float = 0.0, radius: float = 0.04, length: float = 0.10,
                    depth: float | None = 0.15) -> SyntheticScene:
    """A scan of a wall with clutter (domes, boxes, bars, bolts, handles) and a pipe, a hole or
    no inlet at all, its pose drawn from `seed` as in `random_scene`.

    Parameters
    ----------
    seed : int
    target : {"pipe", "hole"} or None
        None: the wall holds only clutter (no target; `T_sensor_target` is NaN).
    clutter : tuple of str, optional
        The kinds of clutter object (see `CLUTTER`), one object each; default two kinds drawn
        from `seed`.
    noise, n_points, rings, outliers, radius, length, depth
        As for `synthetic_scene`.
    gap : float
        Least clear distance along the wall between any two objects (inlet included), m.

    Returns
    -------
    SyntheticScene
        With `labels` (per point: 0 wall, 1 inlet, 2 + i clutter object i, -1 outlier) and
        `objects`.
    """
    rng = np.random.default_rng([seed, 25])
    if clutter is None:
        clutter = tuple(rng.choice(CLUTTER, 2, replace=False))
    kind = target or "hole"
    base = random_scene(seed, kind, noise=noise, n_points=n_points, rings=rings,
                        outliers=0.0, radius=radius if target else 1e-6, length=length,
                        depth=depth if target else None, window=1.0)
    normal = base.plane_normal
    T = base.T_sensor_target
    centre = T[:3, 3] - (length * normal if target == "pipe" else 0.0)
    u, v = T[:3, 0], T[:3, 1]
    placed = [(centre, radius if target else 0.0)]
    objects = []
    for k in clutter:
        for _ in range(200):
            offset = rng.uniform(-0.35, 0.35, 2)
            foot = centre + offset[0] * u + offset[1] * v
            angle = rng.uniform(0, np.pi)
            along = np.cos(angle) * u + np.sin(angle) * v
            obj = clutter_object(k, foot, normal, along, rng)
            if all(np.linalg.norm(foot - c) > r + obj.size + gap for c, r in placed):
                break
        placed.append((obj.centre, obj.size))
        objects.append(obj)
    # Re-cast every ray of the base scan against the clutter: the nearest surface wins.
    d = base.points / np.linalg.norm(base.points, axis=1, keepdims=True)
    t = np.linalg.norm(base.points, axis=1)
    labels = np.zeros(len(d), np.int64)
    h = base.points @ normal + base.plane_offset
    if target is not None:
        near = np.linalg.norm(np.cross(base.points - centre, normal), axis=1) < radius + 0.01
        labels[near & ((h > 3 * noise + 1e-4) if target == "pipe" else (h < -3 * noise - 1e-4))] = 1
    noise_part = t - _true_ranges(d, base, centre, normal, target, radius, length, depth)
    for i, obj in enumerate(objects):
        for part in obj.parts:
            tp = _part_ranges(d, part)
            closer = tp < t - noise_part
            t = np.where(closer, tp + noise_part, t)
            labels[closer] = 2 + i
    points = d * t[:, None]
    outlier = np.zeros(len(points), bool)
    n_out = int(round(outliers * len(points)))
    if n_out:
        idx = rng.choice(len(points), n_out, replace=False)
        lo, hi = points.min(axis=0), points.max(axis=0)
        points[idx] = rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), (n_out, 3))
        outlier[idx] = True
        labels[idx] = -1
    T_truth = T if target is not None else np.full((4, 4), np.nan)
    return SyntheticScene(points=points, T_sensor_target=T_truth, kind=target or "none",
                          radius=float(radius) if target else float("nan"),
                          plane_normal=normal, plane_offset=base.plane_offset, outlier=outlier,
                          noise=float(noise), seed=seed, labels=labels, objects=tuple(objects))


def _true_ranges(d, base, centre, normal, target, radius, length, depth) -> NDArray:
    """The noise-free range of each ray of `base` (the wall, the pipe, the hole's back)."""
    t = -base.plane_offset / (d @ normal)
    if target == "pipe":
        outer, _, _ = _cylinder_hits(d, centre, normal, radius, length)
        t = np.minimum(t, outer)
    elif target == "hole" and depth is not None:
        on_wall = d * t[:, None]
        in_hole = np.linalg.norm(on_wall - centre, axis=1) < radius
        t = np.where(in_hole, -(base.plane_offset + depth) / (d @ normal), t)
    return t
