"""The water inlet in a scan of the train's side (paper 1): its centre and axis, sensor and base.

Pipeline (each step a public function of `armkit.perception`):

1. optional voxel down-sampling (`voxel_downsample`);
2. the wall: `ransac_plane` (adaptive RANSAC, least-squares refits);
3. candidates: points more than `min_height` off the wall on the sensor's side;
4. optional statistical outlier removal among the candidates (`statistical_outliers`; off by
   default, see `detect_target`);
5. clusters: `dbscan` on a k-d tree;
6. the target cluster, by the rule `choose` (below);
7. a pipe: a circle fitted in the wall's plane to the cluster's points projected on it
   (`fit_circle`, radius free or known). Only the sensor-facing side of a pipe and the inside of
   its far side are seen, so the cluster's centroid lies off the axis (by about 2r/pi on the
   seen side); it is reported for comparison only. The wall is then refitted without the points
   around the inlet and the circle fitted again.
   A hole: the empty region of the wall's inliers (an occupancy grid), then its rim: per
   angular sector the innermost wall point and, where rays went through the hole, the outermost
   crossing of those rays with the wall; the circle is fitted to the middle of the two, or,
   without rays through, to the innermost wall points moved in by half the point spacing.

The target frame (see `armkit.perception.synthetic`): z the inlet's axis (the wall's normal,
pointing out of the wall toward the sensor: the pipe is taken to stand square to the wall), y the
sensor's z projected on the wall, origin the pipe's mouth (its centre at the height of the
cluster's 99th percentile above the wall) or the hole's centre on the wall.

Rule for the target cluster (`choose`): among clusters of at least `min_cluster` points whose
extent in the wall's plane fits the inlet (at most 3 radii from their centroid when the radius
is known, else at most `max_extent`), the one with the most points ("largest", the default), the
one nearest the sensor ("nearest"), or the one standing highest off the wall ("highest").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from armkit.errors import InputError
from armkit.io.clouds import Cloud, check_scale, read_cloud
from armkit.perception.clusters import dbscan
from armkit.perception.filters import statistical_outliers, voxel_downsample
from armkit.perception.plane import Plane, fit_plane_lsq, points_array, ransac_plane
from armkit.perception.synthetic import target_frame
from armkit.spatial import as_transform

CHOICES = ("largest", "nearest", "highest")
MIN_ARC = np.deg2rad(60.0)      # rad: a shorter arc does not pin a circle's centre down


@dataclass(frozen=True)
class Circle:
    """A circle fitted to points in a plane.

    Attributes
    ----------
    centre : ndarray, shape (2,)
    radius : float
    rms : float
        RMS of the radial residuals of the points kept, same unit as the points.
    used : ndarray, shape (N,), bool
        The points kept after the robust passes.
    coverage : float
        Angle of the arc the kept points span, rad (2 pi for a full circle).
    """

    centre: NDArray
    radius: float
    rms: float
    used: NDArray
    coverage: float


def _kasa(xy: NDArray) -> tuple[NDArray, float]:
    """Algebraic circle fit (Kasa): centre and radius by linear least squares."""
    mean = xy.mean(axis=0)
    q = xy - mean
    A = np.column_stack([2 * q, np.ones(len(q))])
    sol, *_ = np.linalg.lstsq(A, (q * q).sum(axis=1), rcond=None)
    centre = sol[:2]
    return centre + mean, float(np.sqrt(max(sol[2] + centre @ centre, 0.0)))


def _geometric(xy: NDArray, centre: NDArray, radius: float, known: bool,
               iterations: int = 20) -> tuple[NDArray, float]:
    """Gauss-Newton on the geometric residuals |p - c| - r (r fixed when `known`)."""
    c, r = centre.astype(float).copy(), float(radius)
    for _ in range(iterations):
        diff = xy - c
        dist = np.maximum(np.linalg.norm(diff, axis=1), 1e-12)
        res = dist - r
        J = -diff / dist[:, None]
        if not known:
            J = np.column_stack([J, -np.ones(len(xy))])
        step, *_ = np.linalg.lstsq(J, -res, rcond=None)
        c += step[:2]
        if not known:
            r += step[2]
        if np.abs(step).max() < 1e-10:
            break
    return c, r


def _coverage(angles: NDArray) -> float:
    """Span of the arc covered by `angles` (rad): 2 pi minus the largest gap between them."""
    if len(angles) < 2:
        return 0.0
    a = np.sort(np.mod(angles, 2 * np.pi))
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]]))
    return float(2 * np.pi - gaps.max())


def fit_circle(xy: ArrayLike, radius: float | None = None, *, passes: int = 2,
               cut: float = 3.0, start: ArrayLike | None = None) -> Circle:
    """Circle through 2-D points: algebraic start, geometric least squares, robust passes.

    Parameters
    ----------
    xy : array_like, shape (N, 2), N >= 3
    radius : float or None
        The known radius (same unit as xy), or None to fit it.
    passes : int
        Times points with a residual beyond `cut` robust standard deviations (1.4826 MAD, at
        least 1e-4 of the radius) are set aside and the fit redone.
    cut : float
    start : array_like, shape (2,), optional
        Where the iterations start from, instead of the algebraic fit's centre (on a short arc
        a known radius fits on either side of it).

    Returns
    -------
    Circle

    Raises
    ------
    InputError
        If xy is not (N, 2) finite with N >= 3, or radius is not positive.
    """
    p = np.asarray(xy, float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3 or not np.isfinite(p).all():
        raise InputError(f"xy: expected at least 3 finite points of shape (N, 2), found "
                         f"{p.shape}")
    known = radius is not None
    if known and not (np.isfinite(radius) and radius > 0):
        raise InputError(f"radius: expected a positive radius, found {radius}")
    centre, r = _kasa(p)
    if start is not None:
        centre = np.asarray(start, float)
        r = float(radius) if known else float(np.linalg.norm(p - centre, axis=1).mean())
    elif known:
        # Start from the algebraic centre moved so that the known radius fits the arc: on a
        # short arc the algebraic radius is off, the direction to the arc is not.
        mean = p.mean(axis=0)
        towards = centre - mean
        norm = np.linalg.norm(towards)
        if norm > 1e-12 and np.isfinite(r):
            spread = np.linalg.norm(p - mean, axis=1).mean()
            centre = mean + towards / norm * np.sqrt(max(radius**2 - spread**2, 0.0))
        r = float(radius)
    used = np.ones(len(p), bool)
    centre, r = _geometric(p, centre, r, known)
    for _ in range(passes):
        res = np.linalg.norm(p - centre, axis=1) - r
        mad = 1.4826 * np.median(np.abs(res[used] - np.median(res[used])))
        keep = np.abs(res) <= cut * max(mad, 1e-4 * abs(r))
        if keep.sum() < 3 or (keep == used).all():
            break
        used = keep
        centre, r = _geometric(p[used], centre, r, known)
    res = np.linalg.norm(p[used] - centre, axis=1) - r
    angles = np.arctan2(p[used, 1] - centre[1], p[used, 0] - centre[0])
    return Circle(centre, float(r), float(np.sqrt(np.mean(res * res))), used, _coverage(angles))


@dataclass(frozen=True)
class TargetResult:
    """What `detect_target` found, in the sensor frame and (if given) the robot's base frame.

    Lengths in m. On failure `success` is False, `reason` says why, and the poses are NaN.

    Attributes
    ----------
    success : bool
    reason : str
        "ok" or what failed, e.g. "no cluster of at least 30 points off the wall".
    kind : {"pipe", "hole"}
    T_sensor_target : ndarray, shape (4, 4)
        The inlet's pose in the sensor frame, z its axis (out of the wall).
    T_base_target : ndarray, shape (4, 4) or None
        The same in the robot's base frame, when a sensor-to-base transform was given.
    radius : float
        Fitted radius (the known one when given).
    radius_known : bool
    plane : Plane or None
        The wall (after the final refit), over `points`; None when no plane holds enough
        points to be the wall.
    plane_inliers : int
    plane_rms : float
    candidates : int
        Points off the wall on the sensor's side (after the outlier filter).
    clusters : int
        Clusters found among the candidates.
    cluster_size : int
        Points of the target cluster (for a hole: rim points).
    fit_points : int
        Points the circle fit kept.
    fit_rms : float
        RMS radial residual of the circle fit.
    coverage : float
        Arc (rad) the kept points span around the fitted centre.
    centroid : ndarray, shape (3,)
        The target cluster's plain centroid in the sensor frame (biased for a pipe; for
        comparison only); NaN if no cluster.
    points : ndarray, shape (M, 3)
        The cloud the detection worked on (after down-sampling), sensor frame.
    cluster_mask : ndarray, shape (M,), bool
        The target cluster's points (a hole: the rim's wall points).
    candidate_mask : ndarray, shape (M,), bool
    dropped : int
        Points with NaN or inf dropped when the cloud was read.
    source : str or None
        The cloud's file, if read from one.
    units : str
        The cloud file's length unit ("m" or "mm"); "m" for an array.
    """

    success: bool
    reason: str
    kind: str
    T_sensor_target: NDArray
    T_base_target: NDArray | None
    radius: float
    radius_known: bool
    plane: Plane | None
    plane_inliers: int
    plane_rms: float
    candidates: int
    clusters: int
    cluster_size: int
    fit_points: int
    fit_rms: float
    coverage: float
    centroid: NDArray
    points: NDArray = field(repr=False)
    cluster_mask: NDArray = field(repr=False)
    candidate_mask: NDArray = field(repr=False)
    dropped: int = 0
    source: str | None = None
    units: str = "m"

    def __post_init__(self):
        # Read-only views: the caller's own arrays (points given in) stay writeable.
        for name, value in list(vars(self).items()):
            if isinstance(value, np.ndarray):
                view = value.view()
                view.flags.writeable = False
                object.__setattr__(self, name, view)

    @property
    def centre(self) -> NDArray:
        """The inlet's centre in the sensor frame (3,), m."""
        return self.T_sensor_target[:3, 3]

    @property
    def axis(self) -> NDArray:
        """The inlet's axis in the sensor frame (3,), unit, out of the wall."""
        return self.T_sensor_target[:3, 2]


def _plane_basis(normal: NDArray) -> tuple[NDArray, NDArray]:
    """Two unit vectors (u, v) spanning the plane, u x v = normal; v follows the sensor's up."""
    T = target_frame(normal, np.zeros(3))
    return T[:3, 0], T[:3, 1]


def _fail(reason: str, kind: str, radius: float | None, points: NDArray, plane: Plane | None,
          info: dict) -> TargetResult:
    nan = np.full((4, 4), np.nan)
    n = len(points)
    return TargetResult(
        success=False, reason=reason, kind=kind, T_sensor_target=nan,
        T_base_target=None if info.get("T_base_sensor") is None else nan.copy(),
        radius=float("nan") if radius is None else float(radius),
        radius_known=radius is not None, plane=plane,
        plane_inliers=int(plane.inliers.sum()) if plane is not None else 0,
        plane_rms=plane.rms if plane is not None else float("nan"),
        candidates=int(info.get("candidates", 0)), clusters=int(info.get("clusters", 0)),
        cluster_size=0, fit_points=0, fit_rms=float("nan"), coverage=0.0,
        centroid=np.full(3, np.nan), points=points,
        cluster_mask=info.get("cluster_mask", np.zeros(n, bool)),
        candidate_mask=info.get("candidate_mask", np.zeros(n, bool)),
        dropped=int(info.get("dropped", 0)), source=info.get("source"),
        units=info.get("units", "m"))


def _spacing(xy: NDArray) -> float:
    """Typical point spacing (m) of points spread over a plane: sqrt(area / count), the area
    being the bounding box of the middle 98 % along each axis (of at most 10,000 of them)."""
    step = max(len(xy) // 10_000, 1)
    lo, hi = np.percentile(xy[::step], [1, 99], axis=0)
    area = float(np.prod(np.maximum(hi - lo, 1e-9))) / 0.98**2
    return float(np.sqrt(area / max(len(xy), 1)))


def _choose(labels: NDArray, xy: NDArray, h: NDArray, cand: NDArray, min_cluster: int,
            max_extent: float, choose: str) -> tuple[int | None, str]:
    """The target cluster's label by the stated rule, or None and why."""
    n_labels = labels.max() + 1
    if n_labels <= 0:
        return None, "no cluster among the points off the wall"
    sizes = np.bincount(labels[labels >= 0], minlength=n_labels)
    big = np.flatnonzero(sizes >= min_cluster)
    if len(big) == 0:
        return None, (f"no cluster of at least {min_cluster} points off the wall "
                      f"(largest: {sizes.max()})")
    plausible = []
    for k in big:                                  # a few clusters, not points
        members = labels == k
        spread = np.linalg.norm(xy[members] - xy[members].mean(axis=0), axis=1).max()
        if spread <= max_extent:
            plausible.append(k)
    if not plausible:
        return None, (f"no cluster of the inlet's size: {len(big)} cluster(s) of at least "
                      f"{min_cluster} points, each reaching more than {max_extent * 1e3:.0f} mm "
                      "from its centre along the wall")
    plausible = np.array(plausible)
    if choose == "largest":
        return int(plausible[np.argmax(sizes[plausible])]), "ok"
    score = []
    for k in plausible:
        members = labels == k
        score.append(np.linalg.norm(cand[members], axis=1).mean() if choose == "nearest"
                     else -np.percentile(h[members], 99))
    return int(plausible[int(np.argmin(score))]), "ok"


def _hole(p: NDArray, plane: Plane, u: NDArray, v: NDArray, radius: float | None,
          threshold: float, max_extent: float
          ) -> tuple[Circle | None, str, NDArray, NDArray]:
    """The hole in the wall: its circle in (u, v) coordinates, or None and why.

    Returns the circle, the reason, the rim's wall points (mask over p) and the rim's 2-D
    points the circle was fitted to.
    """
    n = len(p)
    origin = -plane.offset * plane.normal
    inl = plane.inliers
    xy = np.column_stack([p[inl] @ u, p[inl] @ v])
    cell = 2.5 * _spacing(xy)
    lo = xy.min(axis=0)
    ij = np.floor((xy - lo) / cell).astype(np.int64)
    shape = ij.max(axis=0) + 1
    if shape.prod() > 4_000_000:
        return None, "wall too sparse for the hole search", np.zeros(n, bool), np.zeros((0, 2))
    occupied = np.zeros(shape, bool)
    occupied[ij[:, 0], ij[:, 1]] = True
    regions, count = ndimage.label(~occupied)
    if count == 0:
        return None, "no opening in the wall", np.zeros(n, bool), np.zeros((0, 2))
    border = np.unique(np.concatenate([regions[0], regions[-1], regions[:, 0], regions[:, -1]]))
    sizes = np.bincount(regions.ravel(), minlength=count + 1).astype(float)
    sizes[0] = 0
    sizes[border] = 0
    area = sizes * cell * cell
    r_area = np.sqrt(area / np.pi)
    ok = (area > 0) & (r_area <= max_extent) & (r_area >= cell)   # >= about 3 cells across
    if radius is not None:
        ok &= (r_area > 0.5 * radius) & (r_area < 1.5 * radius)
    if not ok.any():
        return None, "no opening of the inlet's size in the wall", np.zeros(n, bool), \
            np.zeros((0, 2))
    best = int(np.argmax(np.where(ok, area, -1)))
    cells = np.argwhere(regions == best)
    rough = lo + (cells.mean(axis=0) + 0.5) * cell
    rho = float(np.sqrt(len(cells) / np.pi) * cell)
    # A gap in the wall can be the shadow of something standing in front of it (a pipe): the
    # rays of such points, carried on to the wall, land in the gap.
    h_all = p @ plane.normal + plane.offset
    front = p[h_all > max(threshold, 4 * plane.rms)]
    landing = front * (-plane.offset / (front @ plane.normal))[:, None]
    xy_front = np.column_stack([landing @ u, landing @ v])
    covering = int((np.linalg.norm(xy_front - rough, axis=1) < 2 * rho + 2 * cell).sum())
    if covering >= 10:
        return None, (f"the gap in the wall lies behind {covering} points standing off it "
                      "(an object, not an opening)"), np.zeros(n, bool), np.zeros((0, 2))

    sectors = 90

    def innermost(points2: NDArray, outer: bool) -> tuple[NDArray, NDArray]:
        d = points2 - rough
        r = np.linalg.norm(d, axis=1)
        s = np.floor((np.arctan2(d[:, 1], d[:, 0]) + np.pi) / (2 * np.pi) * sectors)
        s = np.clip(s.astype(np.int64), 0, sectors - 1)
        order = np.lexsort((-r if outer else r, s))
        first = np.ones(len(order), bool)
        first[1:] = s[order][1:] != s[order][:-1]
        pick = order[first]
        return s[pick], pick

    wall_idx = np.flatnonzero(inl)
    r_wall = np.linalg.norm(xy - rough, axis=1)
    near = r_wall < rho + 4 * cell
    sec_w, pick_w = innermost(xy[near], outer=False)
    rim_wall = np.full((sectors, 2), np.nan)
    rim_wall[sec_w] = xy[near][pick_w]
    rim_mask = np.zeros(n, bool)
    rim_mask[wall_idx[np.flatnonzero(near)[pick_w]]] = True

    # Rays through the hole: returns behind the wall, carried back along their ray to the wall;
    # where a sector has both, the edge is taken midway between the two.
    behind = h_all < -threshold
    # Where no ray went through, the edge lies on average half a spacing inside the innermost
    # wall point (between it and the next sample, which fell into the hole).
    spacing = cell / 2.5
    radial = rim_wall - rough
    radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-12)
    rim = rim_wall - 0.5 * spacing * radial
    if behind.sum() >= 3:
        q = p[behind]
        scale = -plane.offset / (q @ plane.normal)
        cross = q * scale[:, None] - origin
        xy_b = np.column_stack([cross @ u, cross @ v])
        inside = np.linalg.norm(xy_b - rough, axis=1) < rho + 4 * cell
        if inside.sum() >= 3:
            sec_b, pick_b = innermost(xy_b[inside], outer=True)
            through = np.full((sectors, 2), np.nan)
            through[sec_b] = xy_b[inside][pick_b]
            # A return behind the wall whose ray crosses it beyond the innermost wall point
            # went through solid wall: an outlier, left out.
            both = ~np.isnan(rim_wall[:, 0]) & ~np.isnan(through[:, 0])
            both[both] = (np.linalg.norm(through[both] - rough, axis=1)
                          < np.linalg.norm(rim_wall[both] - rough, axis=1))
            rim[both] = 0.5 * (rim_wall[both] + through[both])
    rim = rim[~np.isnan(rim[:, 0])]
    if len(rim) < 3:
        return None, "too few points on the hole's rim", rim_mask, rim
    return fit_circle(rim, radius), "ok", rim_mask, rim


def detect_target(cloud_or_path: ArrayLike | str | Path, *, kind: Literal["pipe", "hole"] = "pipe",
                  radius: float | None = None, units: str | None = None,
                  nonfinite: Literal["drop", "refuse"] = "drop",
                  T_base_sensor: ArrayLike | None = None, plane_threshold: float = 0.01,
                  min_height: float | None = None, eps: float | None = None,
                  min_samples: int = 5, min_cluster: int = 30, max_extent: float = 0.3,
                  choose: Literal["largest", "nearest", "highest"] = "largest",
                  voxel: float | None = None, outlier_filter: bool = False,
                  seed: int | None = 0) -> TargetResult:
    """Find the water inlet (a pipe or a hole in the wall) in a scan of the train's side.

    Parameters
    ----------
    cloud_or_path : array_like (N, 3) in m, a `Cloud`, or a cloud file's path
        A file is read with `armkit.io.clouds.read_cloud` (`units` and `nonfinite` apply).
    kind : {"pipe", "hole"}
    radius : float or None
        The inlet's known radius (m), or None to fit it.
    units : {"m", "mm"} or None
        The cloud file's length unit, when the file does not declare it.
    nonfinite : {"drop", "refuse"}
        For a file: drop points with NaN or inf (and count them) or refuse the file.
    T_base_sensor : array_like (4, 4) or None
        The sensor's pose in the robot's base frame (m); gives `T_base_target`.
    plane_threshold : float
        Inlier distance of the wall, m.
    min_height : float or None
        Candidates stand at least this far off the wall (m); default max(plane_threshold,
        4 x the wall's RMS).
    eps : float or None
        DBSCAN radius (m); default 4 x the wall's point spacing, at least 5 mm.
    min_samples : int
        DBSCAN core size.
    min_cluster : int
        Smallest target cluster (points).
    max_extent : float
        Largest distance (m) of a cluster's point from its centroid along the wall, when the
        radius is not known (else 3 radii).
    choose : {"largest", "nearest", "highest"}
        The rule that picks the target among plausible clusters (module docstring).
    voxel : float or None
        Voxel down-sampling edge (m), None for none.
    outlier_filter : bool
        Remove statistical outliers among the candidates (k = 8, 2 standard deviations) before
        clustering. Off by default: DBSCAN leaves isolated points out already, and the filter
        judges by the candidates' mean density, so a dense object beside the inlet can make
        the inlet's own points look like outliers.
    seed : int or None
        RANSAC's seed.

    Returns
    -------
    TargetResult
        "No target" is a result with `success` False and a reason, not an exception.

    Raises
    ------
    InputError, ModelFileError
        Bad arguments, an empty cloud, NaN/inf in an array, an unreadable or implausible file.
    """
    info: dict = {}
    if units is not None and not isinstance(cloud_or_path, (str, Path)):
        raise InputError(f"units: applies to a cloud file; points given as an array are in m, "
                         f"found units={units!r} with an array")
    if isinstance(cloud_or_path, (str, Path)):
        cloud_or_path = read_cloud(cloud_or_path, units=units, nonfinite=nonfinite)
    if isinstance(cloud_or_path, Cloud):
        info.update(dropped=cloud_or_path.dropped, source=cloud_or_path.path,
                    units=cloud_or_path.units)
        p = cloud_or_path.points
    else:
        p = points_array(cloud_or_path)
        check_scale(p, "points", file=False)
    if kind not in ("pipe", "hole"):
        raise InputError(f"kind: expected 'pipe' or 'hole', found {kind!r}")
    if choose not in CHOICES:
        raise InputError(f"choose: expected one of {', '.join(CHOICES)}, found {choose!r}")
    for name, value in (("radius", radius), ("min_height", min_height), ("eps", eps),
                        ("voxel", voxel), ("plane_threshold", plane_threshold),
                        ("max_extent", max_extent)):
        if value is not None and not (np.isfinite(value) and value > 0):
            raise InputError(f"{name}: expected a positive length in m, found {value}")
    if T_base_sensor is not None:
        T_base_sensor = as_transform(T_base_sensor, "T_base_sensor")
        if T_base_sensor.shape != (4, 4):
            raise InputError(f"T_base_sensor: expected shape (4, 4), found {T_base_sensor.shape}")
    info["T_base_sensor"] = T_base_sensor
    if voxel is not None:
        p = voxel_downsample(p, voxel)
    n = len(p)

    plane = ransac_plane(p, plane_threshold, refits=1, seed=seed)
    if plane.inliers.sum() < max(50, 0.05 * n):
        return _fail(f"no wall: the best plane holds {int(plane.inliers.sum())} of {n} points",
                     kind, radius, p, None, info)
    u, v = _plane_basis(plane.normal)
    origin = -plane.offset * plane.normal            # the sensor's foot on the wall
    # (n, 2) coordinates along the wall. Two matrix-vector products, not one (n, 3) @ (3, 2)
    # product: OpenBLAS runs that one threaded, and on a busy machine its threads wait for a
    # core (measured: 0.2 ms alone, 120 ms median under load).
    xy_all = np.column_stack([p @ u, p @ v])
    spacing = _spacing(np.compress(plane.inliers, xy_all, axis=0))
    extent = 3 * radius if radius is not None else max_extent

    if kind == "hole":
        circle, why, rim_mask, _ = _hole(p, plane, u, v, radius, plane_threshold, extent)
        info.update(cluster_mask=rim_mask)
        if circle is None:
            return _fail(why, kind, radius, p, plane, info)
        centre = origin + circle.centre[0] * u + circle.centre[1] * v
        T = target_frame(plane.normal, centre)
        centroid = p[rim_mask].mean(axis=0)
        size, cand_mask, n_clusters = int(rim_mask.sum()), np.zeros(n, bool), 0
    else:
        h = p @ plane.normal + plane.offset
        floor = min_height if min_height is not None else max(plane_threshold, 4 * plane.rms)
        cand_mask = h > floor
        info["candidate_mask"] = cand_mask
        if cand_mask.sum() < min_cluster:
            info["candidates"] = int(cand_mask.sum())
            return _fail(f"only {int(cand_mask.sum())} point(s) stand more than "
                         f"{floor * 1e3:.1f} mm off the wall on the sensor's side (fewer than "
                         f"{min_cluster})", kind, radius, p, plane, info)
        cand_idx = np.flatnonzero(cand_mask)
        if outlier_filter and len(cand_idx) > 8:
            cand_idx = cand_idx[~statistical_outliers(p[cand_idx])]
            cand_mask = np.zeros(n, bool)
            cand_mask[cand_idx] = True
            info["candidate_mask"] = cand_mask
        info["candidates"] = len(cand_idx)
        cand = p[cand_idx]
        radius_eps = eps if eps is not None else max(4 * spacing, 0.005)
        labels = dbscan(cand, radius_eps, min_samples)
        info["clusters"] = int(labels.max() + 1)
        label, why = _choose(labels, xy_all[cand_idx], h[cand_idx], cand, min_cluster, extent,
                             choose)
        if label is None:
            return _fail(why, kind, radius, p, plane, info)
        members = cand_idx[labels == label]
        cluster_mask = np.zeros(n, bool)
        cluster_mask[members] = True
        info["cluster_mask"] = cluster_mask

        # Fit, refit the wall without the inlet's surroundings, fit again in the new plane.
        circle = fit_circle(xy_all[members], radius)
        du, dv = xy_all[:, 0] - circle.centre[0], xy_all[:, 1] - circle.centre[1]
        keep = plane.inliers & (du * du + dv * dv > (circle.radius + 2 * radius_eps) ** 2)
        if keep.sum() >= 3:
            normal, offset, _ = fit_plane_lsq(np.compress(keep, p, axis=0))
            h = p @ normal + offset
            inliers = np.abs(h) < plane_threshold
            hin = h[inliers]
            plane = Plane(normal, offset, inliers, float(np.sqrt(np.mean(hin * hin))),
                          plane.iterations)
            u, v = _plane_basis(plane.normal)
            origin = -plane.offset * plane.normal
            q = p[members] - origin
            circle = fit_circle(np.column_stack([q @ u, q @ v]), radius)
        # Only the side of the pipe facing the sensor is seen, so the centre lies farther
        # from the sensor's foot on the wall (0, 0) than the seen arc does. On a short arc a
        # known radius also fits the mirror image: then start again from the other side.
        arc = np.column_stack([(p[members] - origin) @ u, (p[members] - origin) @ v])
        middle = arc[circle.used].mean(axis=0)
        if np.linalg.norm(circle.centre) < np.linalg.norm(middle):
            mirrored = fit_circle(arc, radius, start=2 * middle - circle.centre)
            if np.linalg.norm(mirrored.centre) < np.linalg.norm(arc[mirrored.used].mean(axis=0)):
                return _fail("the fitted circle lies on the sensor's side of the points it was "
                             "fitted to, from either side (not a pipe seen from the side?)",
                             kind, radius, p, plane, info)
            circle = mirrored
        if circle.coverage < MIN_ARC:
            return _fail(f"the points span {np.degrees(circle.coverage):.0f} deg of the circle, "
                         f"fewer than {np.degrees(MIN_ARC):.0f}: too short an arc to fit "
                         "(a smaller eps may split the cluster; a larger one may join it)",
                         kind, radius, p, plane, info)
        if not (np.isfinite(circle.radius) and 0 < circle.radius <= extent):
            return _fail(f"circle fit failed: radius {circle.radius * 1e3:.1f} mm is not "
                         f"within 0 .. {extent * 1e3:.0f} mm", kind, radius, p, plane, info)
        h_members = h[members] if keep.sum() >= 3 else p[members] @ plane.normal + plane.offset
        mouth = float(np.percentile(h_members[circle.used], 99))
        centre = (origin + circle.centre[0] * u + circle.centre[1] * v + mouth * plane.normal)
        T = target_frame(plane.normal, centre)
        centroid = p[members].mean(axis=0)
        size, n_clusters = len(members), info["clusters"]
    T_base = None if T_base_sensor is None else T_base_sensor @ T
    return TargetResult(
        success=True, reason="ok", kind=kind, T_sensor_target=T, T_base_target=T_base,
        radius=float(circle.radius), radius_known=radius is not None, plane=plane,
        plane_inliers=int(plane.inliers.sum()), plane_rms=plane.rms,
        candidates=int(cand_mask.sum()), clusters=n_clusters, cluster_size=size,
        fit_points=int(circle.used.sum()), fit_rms=circle.rms, coverage=circle.coverage,
        centroid=centroid, points=p, cluster_mask=info.get("cluster_mask"),
        candidate_mask=cand_mask, dropped=int(info.get("dropped", 0)),
        source=info.get("source"), units=info.get("units", "m"))
