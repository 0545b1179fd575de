"""The water inlet in a scan of the train's side (paper 1): its centre and axis, sensor and base,
reported only with evidence.

Pipeline (each step a public function of `armkit.perception`):

1. optional voxel down-sampling (`voxel_downsample`);
2. the scan measured on itself (`measure_scan`): the wall by adaptive RANSAC and least-squares
   refits in a band of 3.5 robust standard deviations of the wall's own residuals, the range
   noise along the rays, the point spacing and the scan's rows (a LiDAR's rings);
3. candidates: points standing off the wall on the sensor's side, beyond the band and 4
   robust standard deviations;
4. optional statistical outlier removal among the candidates (`statistical_outliers`; off by
   default, see `detect_target`);
5. clusters: `dbscan` on a k-d tree, its radius from the scan (4 point spacings, 1.5 ring gaps:
   an object's points are linked across the rings of a sparse LiDAR);
6. every cluster weighed as a pipe standing square to the wall, seen from the side: a circle
   fitted in the wall's plane to its points projected on it (`fit_circle`), and the evidence
   (below); or, for a hole, every opening in the wall weighed (`armkit.perception.holes`);
7. the target among the candidates that pass, by the rule `choose`; the runner-up and the rule
   in the result. None passing is "no target", with the reason of the candidate that came
   nearest;
8. for a pipe, the wall refitted without the points around the inlet and the circle fitted
   again.

A pipe's evidence, in terms of the range noise σ measured on the wall: range noise moves a
point along its ray, so in the wall's plane by σ sin θ (θ the ray's angle to the wall's normal,
the pipe's axis). The circle's RMS over the cluster's points is at most 3 times the RMS of
σ sin θ over them, plus 0.5 mm and 1 % of the radius (a pipe a little off square to the wall);
at least 90 % of the points lie within that band of the circle (a box's faces and a dome's cap
do not); at most 5 % lie inside it (a pipe's mouth is open: a bolt's head, a box's front face, a
dome fill the circle); the points span at least 60 deg of it, on the far side of the points from
the sensor (the sensor sees the pipe's near side); its radius is at most `max_extent` (or the
known one). Only the sensor-facing side of a pipe (and the inside of its far side) is seen, so
the cluster's centroid lies off the axis (by about 2r/pi on the seen side); it is reported for
comparison only.

The target frame (see `armkit.perception.synthetic`): z the inlet's axis (the wall's normal,
pointing out of the wall toward the sensor), y the sensor's z projected on the wall, origin the
pipe's mouth (its centre at the height of the cluster's 99th percentile above the wall) or the
hole's centre on the wall.

Rule among the candidates that pass (`choose`): the one with the most points (a pipe) or the
largest radius (a hole) ("largest", the default), the one nearest the sensor ("nearest"), or
the one standing highest off the wall (a pipe) or highest up in the sensor's frame (a hole)
("highest").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.perception.cloud import Cloud, check_scale
from armkit.perception.circles import Circle, fit_circle
from armkit.perception.clusters import dbscan
from armkit.perception.filters import statistical_outliers, voxel_downsample
from armkit.perception.holes import Opening, grid_openings, row_openings
from armkit.perception.plane import Plane, fit_plane_lsq, points_array
from armkit.perception.scan import BAND_SIGMAS, START_BAND, Scan, measure_scan
from armkit.perception.synthetic import target_frame
from armkit.spatial import as_transform

CHOICES = ("largest", "nearest", "highest")
MIN_ARC = np.deg2rad(60.0)      # rad: a shorter arc does not pin a circle's centre down
FIT_SIGMAS = 3.0                # a pipe's fit RMS, in RMS of the in-plane noise sigma sin(theta)
FIT_FLOOR = 5e-4                # m: added to the fit's limit (a pipe a little off square)
FIT_RADIUS_SHARE = 0.01         # of the radius: added to the fit's limit
MIN_ON_CIRCLE = 0.90            # share of a pipe's points within the band of its circle
MAX_INSIDE = 0.05               # share of a pipe's points inside its circle (an open mouth)
MAX_CLUSTERS = 64               # clusters weighed at most, the largest first


@dataclass(frozen=True, eq=False)
class Candidate:
    """A cluster (pipe) or an opening (hole) weighed as the inlet; lengths in m, sensor frame.

    Attributes
    ----------
    kind : {"pipe", "hole"}
    size : int
        Points of the cluster, or rim estimates of the opening.
    centre : ndarray, shape (3,)
        The circle's centre on the wall (NaN if none was fitted).
    centroid : ndarray, shape (3,)
        Where its points are: the cluster's, or the rim estimates' centroid on the wall.
    radius, fit_rms, rms_limit : float
        The fitted circle's radius and RMS, and the largest RMS the scan's noise allows.
    coverage : float
        Arc (rad) its points span around the circle.
    standoff : float
        How far it stands off the wall (99th percentile height; 0 for a hole), m.
    distance : float
        The centre's distance from the sensor, m.
    reason : str
        "ok", or why it is not the inlet.
    """

    kind: str
    size: int
    centre: NDArray
    centroid: NDArray
    radius: float
    fit_rms: float
    rms_limit: float
    coverage: float
    standoff: float
    distance: float
    reason: str

    @property
    def passed(self) -> bool:
        """Whether the evidence shows it is an inlet."""
        return self.reason == "ok"

    def describe(self, file_scale: float = 1e3, unit: str = "mm") -> str:
        """One phrase: what and where it is, in `unit` (file_scale per m)."""
        where = ", ".join(f"{x * file_scale:.4g}" for x in self.centroid) \
            if np.isfinite(self.centroid).all() else "nowhere"
        what = "points" if self.kind == "pipe" else "rim estimates"
        return f"{self.size} {what} at ({where}) {unit}"

@dataclass(frozen=True)
class TargetResult:
    """What `detect_target` found, in the sensor frame and (if given) the robot's base frame.

    Lengths in m. On failure `success` is False, `reason` says why, and the poses are NaN.

    Attributes
    ----------
    success : bool
    reason : str
        "ok", or why there is no target: no wall, nothing off it, or each candidate's want of
        evidence (e.g. "no pipe among 3 cluster(s) off the wall: the largest, 412 points
        ..., fits a circle with an RMS of 6.2 mm where the range noise allows 2.9 mm").
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
    file_units : str
        The cloud file's length unit ("m" or "mm"; "m" for an array): how to show the
        results in the file's terms. Every length here is in m.
    range_noise : float
        The range noise measured on the wall (robust standard deviation along the rays), m.
    plane_band : float
        Half-width of the wall's band (m): points within it are the wall.
    eps : float
        The clustering radius used, m.
    rows : int
        Rows (rings) of the scan crossing the wall; 0 for a cloud without rows.
    rule : str
        How the target was chosen among the candidates that passed, and what else passed.
    considered : tuple of Candidate
        Every cluster (pipe) or opening (hole) weighed, with why it is or is not the inlet.
    runner_up : Candidate or None
        The candidate the rule placed second, among those that passed.
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
    file_units: str = "m"
    range_noise: float = float("nan")
    plane_band: float = float("nan")
    eps: float = float("nan")
    rows: int = 0
    rule: str = ""
    considered: tuple = ()
    runner_up: "Candidate | None" = None

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
    scan = info.get("scan")
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
        file_units=info.get("file_units", "m"),
        range_noise=scan.range_noise if scan else float("nan"),
        plane_band=scan.band if scan else float("nan"), eps=info.get("eps", float("nan")),
        rows=scan.ring_count if scan else 0, considered=tuple(info.get("considered", ())))


def _in_plane_noise(points: NDArray, normal: NDArray, range_noise: float) -> float:
    """RMS (m) of range noise carried into the wall's plane for points seen along their rays:
    sigma sin(theta), theta the ray's angle to the wall's normal."""
    d = points / np.maximum(np.linalg.norm(points, axis=1, keepdims=True), 1e-12)
    sin2 = np.maximum(1.0 - (d @ normal) ** 2, 0.0)
    return float(range_noise * np.sqrt(np.mean(sin2)))


def _pipe_circle(xy: NDArray, radius: float | None) -> tuple[Circle, str]:
    """The pipe's circle fitted to its points along the wall (u, v), on the far side of them
    from the sensor's foot (0, 0): the sensor sees the pipe's near side. On a short arc a known
    radius also fits the mirror image: then start again from the other side."""
    circle = fit_circle(xy, radius)
    middle = xy[circle.used].mean(axis=0)
    if np.linalg.norm(circle.centre) < np.linalg.norm(middle):
        mirrored = fit_circle(xy, radius, start=2 * middle - circle.centre)
        if np.linalg.norm(mirrored.centre) < np.linalg.norm(xy[mirrored.used].mean(axis=0)):
            return circle, ("the fitted circle lies on the sensor's side of its points, from "
                            "either side (not a pipe seen from the side)")
        circle = mirrored
    return circle, "ok"


def _weigh_pipe(points: NDArray, xy: NDArray, h: NDArray, normal: NDArray, scan: Scan,
                radius: float | None, extent: float, origin: NDArray, u: NDArray,
                v: NDArray) -> tuple[Candidate, Circle | None]:
    """A cluster weighed as a pipe (see the module's note): its Candidate and circle."""
    circle, why = _pipe_circle(xy, radius)
    res = np.linalg.norm(xy - circle.centre, axis=1) - circle.radius
    rms = float(np.sqrt(np.mean(res * res)))
    sigma = _in_plane_noise(points, normal, scan.range_noise)
    r = circle.radius if np.isfinite(circle.radius) else 0.0
    limit = FIT_SIGMAS * sigma + FIT_FLOOR + FIT_RADIUS_SHARE * abs(r)
    on_circle = float(np.mean(np.abs(res) <= limit))
    inside = float(np.mean(res < -limit))
    centre = origin + circle.centre[0] * u + circle.centre[1] * v
    if why == "ok":
        why = _pipe_evidence(circle, rms, limit, inside, on_circle, extent, scan.range_noise)
    standoff = float(np.percentile(h, 99))
    candidate = Candidate("pipe", len(points), centre, points.mean(axis=0),
                          float(circle.radius), rms, limit, circle.coverage, standoff,
                          float(np.linalg.norm(centre)), why)
    return candidate, circle


def _pipe_evidence(circle: Circle, rms: float, limit: float, inside: float, on_circle: float,
                   extent: float, range_noise: float) -> str:
    """"ok", or the first piece of evidence against a cluster being a pipe."""
    mm = 1e3
    if not (np.isfinite(circle.radius) and 0 < circle.radius <= extent):
        return (f"it fits a circle of radius {circle.radius * mm:.4g} mm, not within 0 .. "
                f"{extent * mm:.0f} mm")
    if rms > limit:
        return (f"it fits a circle with an RMS of {rms * mm:.3g} mm where the range noise "
                f"({range_noise * mm:.3g} mm) allows {limit * mm:.3g} mm (not a pipe's side)")
    if inside > MAX_INSIDE:
        return (f"{inside:.0%} of its points lie inside its circle (a closed face: a box, a "
                "dome, a bolt, not a pipe's open mouth)")
    if on_circle < MIN_ON_CIRCLE:
        return (f"only {on_circle:.0%} of its points lie on its circle (within "
                f"{limit * mm:.3g} mm; a pipe's side puts at least {MIN_ON_CIRCLE:.0%} there)")
    if circle.coverage < MIN_ARC:
        return (f"its points span {np.degrees(circle.coverage):.0f} deg of the circle, fewer "
                f"than {np.degrees(MIN_ARC):.0f}: too short an arc to fit")
    return "ok"


def _ranked(candidates: list[Candidate], choose: str) -> list[Candidate]:
    """The candidates in the rule's order, best first."""
    if choose == "largest":
        key = [-(c.size if c.kind == "pipe" else c.radius) for c in candidates]
    elif choose == "nearest":
        key = [c.distance for c in candidates]
    else:
        key = [-(c.standoff if c.kind == "pipe" else c.centre[2]) for c in candidates]
    return [candidates[i] for i in np.argsort(key, kind="stable")]


def _rule_text(kind: str, choose: str, passed: list[Candidate], k: float, unit: str) -> str:
    what = {"largest": "the most points" if kind == "pipe" else "the largest radius",
            "nearest": "the nearest to the sensor",
            "highest": "the highest off the wall" if kind == "pipe" else "the highest up"}[choose]
    if len(passed) == 1:
        return f"the only {kind} that passed"
    return (f"{what} of {len(passed)} {kind}s that passed; runner-up "
            f"{passed[1].describe(k, unit)}")


def _no_target(kind: str, considered: list[Candidate], k: float, unit: str) -> str:
    if not considered:
        return f"no {kind} candidate"
    best = max(considered, key=lambda c: c.size)
    where = "cluster(s) off the wall" if kind == "pipe" else "opening(s) in the wall"
    return (f"no {kind} among {len(considered)} {where}: the largest, "
            f"{best.describe(k, unit)}, is not one: {best.reason}")


def detect_target(cloud: ArrayLike | Cloud, *, kind: Literal["pipe", "hole"] = "pipe",
                  radius: float | None = None, T_base_sensor: ArrayLike | None = None, plane_threshold: float | None = None,
                  min_height: float | None = None, eps: float | None = None,
                  min_samples: int = 5, min_cluster: int = 30, max_extent: float = 0.3,
                  choose: Literal["largest", "nearest", "highest"] = "largest",
                  voxel: float | None = None, outlier_filter: bool = False,
                  rings: ArrayLike | None = None, seed: int | None = 0) -> TargetResult:
    """Find the water inlet (a pipe or a hole in the wall) in a scan of the train's side, and
    report it only with evidence (see the module's note); "no target" otherwise.

    Parameters
    ----------
    cloud : array_like (N, 3) in m, or a `Cloud` (a file's: `armkit.io.clouds.read_cloud`)
        A cloud's ``ring`` field, if it has one, gives the rows.
    kind : {"pipe", "hole"}
    radius : float or None
        The inlet's known radius (m), or None to fit it.
    T_base_sensor : array_like (4, 4) or None
        The sensor's pose in the robot's base frame (m); gives `T_base_target`.
    plane_threshold : float or None
        Half-width of the wall's band (m); default: 3.5 robust standard deviations of the
        wall's own residuals (`armkit.perception.scan`).
    min_height : float or None
        Candidates stand at least this far off the wall (m); default the band, and at least
        4 robust standard deviations of the wall.
    eps : float or None
        DBSCAN radius (m); default 4 point spacings, 1.5 ring gaps, at least 5 mm.
    min_samples : int
        DBSCAN core size.
    min_cluster : int
        Smallest target cluster (points).
    max_extent : float
        Largest distance (m) of a cluster's point from its centroid along the wall, and the
        largest radius, when the radius is not known (else 3 radii).
    choose : {"largest", "nearest", "highest"}
        The rule that picks the target among the candidates that pass (module docstring).
    voxel : float or None
        Voxel down-sampling edge (m), None for none (rows are then inferred again).
    outlier_filter : bool
        Remove statistical outliers among the candidates (k = 8, 2 standard deviations) before
        clustering. Off by default: DBSCAN leaves isolated points out already, and the filter
        judges by the candidates' mean density, so a dense object beside the inlet can make
        the inlet's own points look like outliers.
    rings : array_like (N,) of int, optional
        Each point's ring (row) for points given as an array; default: a cloud's ``ring``
        field, else rows inferred from the elevations.
    seed : int or None
        RANSAC's seed.

    Returns
    -------
    TargetResult
        "No target" is a result with `success` False and a reason, not an exception.

    Raises
    ------
    InputError
        Bad arguments, an empty cloud, NaN/inf in an array, points not in metres.
    """
    info: dict = {}
    if isinstance(cloud, (str, Path)):
        raise InputError(f"cloud: expected points (N, 3) in m or a Cloud (a file's: "
                         f"armkit.io.clouds.read_cloud), found the path {str(cloud)[:200]!r}")
    if isinstance(cloud, Cloud):
        info.update(dropped=cloud.dropped, source=cloud.path, file_units=cloud.file_units)
        p = cloud.points
        if rings is None and "ring" in cloud.fields:
            rings = cloud.fields["ring"]
    else:
        p = points_array(cloud)
        check_scale(p, "points", file=False)
    if kind not in ("pipe", "hole"):
        raise InputError(f"kind: expected 'pipe' or 'hole', found {kind!r}")
    if choose not in CHOICES:
        raise InputError(f"choose: expected one of {', '.join(CHOICES)}, found {choose!r}")
    for name, value in (("radius", radius), ("min_height", min_height), ("eps", eps),
                        ("voxel", voxel), ("plane_threshold", plane_threshold),
                        ("max_extent", max_extent)):
        if value is not None and not (np.isfinite(value) and 0 < value <= 1e3):
            raise InputError(f"{name}: expected a positive length of at most 1000 m, "
                             f"found {value}")
    if not (isinstance(min_cluster, (int, np.integer)) and 3 <= min_cluster <= 10**7):
        raise InputError(f"min_cluster: expected a whole number from 3 to 1e7, found "
                         f"{min_cluster!r}")
    if rings is not None:
        rings = np.asarray(rings)
        if rings.shape != (len(p),) or not np.issubdtype(rings.dtype, np.integer):
            raise InputError(f"rings: expected {len(p)} whole numbers (one per point), found "
                             f"{rings.dtype} of shape {rings.shape}")
    if T_base_sensor is not None:
        T_base_sensor = as_transform(T_base_sensor, "T_base_sensor")
        if T_base_sensor.shape != (4, 4):
            raise InputError(f"T_base_sensor: expected shape (4, 4), found {T_base_sensor.shape}")
    info["T_base_sensor"] = T_base_sensor
    if voxel is not None:
        p, rings = voxel_downsample(p, voxel), None
    n = len(p)
    k_file = 1e3 if info.get("file_units", "m") == "mm" else 1.0
    unit = info.get("file_units", "m")

    scan = measure_scan(p, rings, plane_threshold, seed, labels=kind == "hole")
    if scan is None or scan.plane.inliers.sum() < max(50, 0.05 * n):
        held = 0 if scan is None else int(scan.plane.inliers.sum())
        return _fail(f"no wall: the best plane holds {held} of {n} points", kind, radius, p,
                     None, info)
    info["scan"] = scan
    if plane_threshold is None and BAND_SIGMAS * scan.wall_sigma > START_BAND:
        return _fail(f"no wall: the best plane's {int(scan.plane.inliers.sum())} points spread "
                     f"evenly through its band of +-{START_BAND * 1e3:.0f} mm (a wall's points "
                     f"crowd near its plane; this is noise of "
                     f"{scan.wall_sigma * 1e3:.0f} mm or more, or no plane)", kind, radius, p,
                     None, info)
    plane = scan.plane
    u, v = _plane_basis(plane.normal)
    origin = -plane.offset * plane.normal            # the sensor's foot on the wall
    # (n, 2) coordinates along the wall. Two matrix-vector products, not one (n, 3) @ (3, 2)
    # product: OpenBLAS runs that one threaded, and on a busy machine its threads wait for a
    # core (measured: 0.2 ms alone, 120 ms median under load).
    xy_all = np.column_stack([p @ u, p @ v])
    extent = 3 * radius if radius is not None else max_extent

    if kind == "hole":
        find = row_openings if scan.ring_count else grid_openings
        openings = find(p, scan, u, v, radius, extent)
        considered = [_hole_candidate(o, origin, u, v) for o in openings]
        info["considered"] = considered
        passed = _ranked([c for c in considered if c.passed], choose)
        if not passed:
            return _fail(_no_target("hole", considered, k_file, unit), kind, radius, p, plane,
                         info)
        chosen = openings[next(i for i, c in enumerate(considered) if c is passed[0])]
        circle = chosen.circle
        info.update(cluster_mask=chosen.rim_mask)
        centre = origin + circle.centre[0] * u + circle.centre[1] * v
        T = target_frame(plane.normal, centre)
        centroid = p[chosen.rim_mask].mean(axis=0) if chosen.rim_mask.any() else centre
        size, cand_mask, n_clusters = len(chosen.rim), np.zeros(n, bool), len(openings)
        fit_points, fit_rms = len(chosen.rim), circle.rms
    else:
        h = p @ plane.normal + plane.offset
        floor = min_height if min_height is not None else max(scan.band, 4 * scan.wall_sigma)
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
        radius_eps = eps if eps is not None else scan.eps
        info["eps"] = radius_eps
        labels = dbscan(p[cand_idx], radius_eps, min_samples)
        info["clusters"] = int(labels.max() + 1)
        sizes = np.bincount(labels[labels >= 0], minlength=max(info["clusters"], 0))
        big = [int(c) for c in np.argsort(-sizes, kind="stable")[:MAX_CLUSTERS]
               if sizes[c] >= min_cluster]
        if not big:
            return _fail(f"no cluster of at least {min_cluster} points off the wall (largest: "
                         f"{int(sizes.max()) if len(sizes) else 0})", kind, radius, p, plane,
                         info)
        considered, circles, members_of = [], [], []
        for c in big:                              # clusters: a handful, not points
            members = cand_idx[labels == c]
            spread = np.linalg.norm(xy_all[members] - xy_all[members].mean(axis=0),
                                    axis=1).max()
            if spread > extent:
                centre = p[members].mean(axis=0)
                considered.append(Candidate(
                    "pipe", len(members), np.full(3, np.nan), centre, float("nan"),
                    float("nan"), float("nan"), 0.0,
                    float(np.percentile(h[members], 99)), float(np.linalg.norm(centre)),
                    f"it reaches {spread * 1e3:.0f} mm from its centre along the wall, more "
                    f"than {extent * 1e3:.0f} mm (larger than the inlet)"))
                circles.append(None)
            else:
                candidate, circle = _weigh_pipe(p[members], xy_all[members], h[members],
                                                plane.normal, scan, radius, extent, origin, u, v)
                considered.append(candidate)
                circles.append(circle)
            members_of.append(members)
        info["considered"] = considered
        passed = _ranked([c for c in considered if c.passed], choose)
        if not passed:
            return _fail(_no_target("pipe", considered, k_file, unit), kind, radius, p, plane,
                         info)
        index = next(i for i, c in enumerate(considered) if c is passed[0])
        members = members_of[index]
        cluster_mask = np.zeros(n, bool)
        cluster_mask[members] = True
        info["cluster_mask"] = cluster_mask
        plane, circle, h_members, origin, u, v = _refit(p, members, plane, circles[index],
                                                        radius, radius_eps, scan, xy_all)
        mouth = float(np.percentile(h_members[circle.used], 99))
        centre = (origin + circle.centre[0] * u + circle.centre[1] * v + mouth * plane.normal)
        T = target_frame(plane.normal, centre)
        centroid = p[members].mean(axis=0)
        size, n_clusters = len(members), info["clusters"]
        fit_points, fit_rms = int(circle.used.sum()), circle.rms
    T_base = None if T_base_sensor is None else T_base_sensor @ T
    return TargetResult(
        success=True, reason="ok", kind=kind, T_sensor_target=T, T_base_target=T_base,
        radius=float(circle.radius), radius_known=radius is not None, plane=plane,
        plane_inliers=int(plane.inliers.sum()), plane_rms=plane.rms,
        candidates=int(cand_mask.sum()), clusters=n_clusters, cluster_size=size,
        fit_points=fit_points, fit_rms=fit_rms, coverage=circle.coverage,
        centroid=centroid, points=p, cluster_mask=info.get("cluster_mask"),
        candidate_mask=cand_mask, dropped=int(info.get("dropped", 0)),
        source=info.get("source"), file_units=unit, range_noise=scan.range_noise,
        plane_band=scan.band, eps=info.get("eps", float("nan")), rows=scan.ring_count,
        rule=_rule_text(kind, choose, passed, k_file, unit), considered=tuple(considered),
        runner_up=passed[1] if len(passed) > 1 else None)


def _hole_candidate(opening: Opening, origin: NDArray, u: NDArray, v: NDArray) -> Candidate:
    c = opening.circle
    rim = opening.rim.mean(axis=0) if len(opening.rim) else np.full(2, np.nan)
    centroid = origin + rim[0] * u + rim[1] * v
    if c is None:
        return Candidate("hole", len(opening.rim), np.full(3, np.nan), centroid, float("nan"),
                         float("nan"), opening.rms_limit, 0.0, 0.0, float("nan"),
                         opening.reason)
    centre = origin + c.centre[0] * u + c.centre[1] * v
    return Candidate("hole", len(opening.rim), centre, centroid, float(c.radius), c.rms,
                     opening.rms_limit, c.coverage, 0.0, float(np.linalg.norm(centre)),
                     opening.reason)


def _refit(p, members, plane, circle, radius, radius_eps, scan, xy_all):
    """Refit the wall without the inlet's surroundings, then the circle in the new plane."""
    du, dv = xy_all[:, 0] - circle.centre[0], xy_all[:, 1] - circle.centre[1]
    keep = plane.inliers & (du * du + dv * dv > (circle.radius + 2 * radius_eps) ** 2)
    u, v = _plane_basis(plane.normal)
    origin = -plane.offset * plane.normal
    if keep.sum() >= 3:
        normal, offset, _ = fit_plane_lsq(np.compress(keep, p, axis=0))
        h = p @ normal + offset
        inliers = np.abs(h) < scan.band
        hin = h[inliers]
        plane = Plane(normal, offset, inliers, float(np.sqrt(np.mean(hin * hin))),
                      plane.iterations)
        u, v = _plane_basis(plane.normal)
        origin = -plane.offset * plane.normal
        q = p[members] - origin
        refitted, why = _pipe_circle(np.column_stack([q @ u, q @ v]), radius)
        if why == "ok":
            circle = refitted
    h_members = p[members] @ plane.normal + plane.offset
    return plane, circle, h_members, origin, u, v
