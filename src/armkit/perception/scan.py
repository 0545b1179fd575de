"""What a scan is like, measured on the scan itself: the wall, its range noise, its point
spacing and its rings.

A detector's thresholds follow from these rather than from fixed numbers: a wall 5 m away seen
by a LiDAR with 12 mm of range noise needs a plane band of centimetres, one 1.5 m away with
2 mm of noise a band of millimetres; a spinning LiDAR's rings lie centimetres apart while its
points along a ring lie millimetres apart, so clustering must bridge the rings, and a gap
between two rings is not an opening in the wall.

- The wall: adaptive RANSAC with a wide band (`START_BAND`), then least-squares refits whose
  band is `BAND_SIGMAS` robust standard deviations (1.4826 MAD) of the wall's own residuals.
- Range noise: LiDAR noise lies along the rays, so a wall point's distance from the plane is the
  range error times the cosine of its incidence; the range noise is the robust deviation of
  the distances divided by those cosines.
- Rows: a ``ring`` field of the file, or rows of equal elevation inferred from the points (a
  spinning LiDAR's rings, a scanner's or a depth camera's rows). Spacings on the wall come
  from the scan's angular steps and the wall's geometry: along a row, and between rows (the
  ring gap, far larger than the step along them on a ring LiDAR).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.perception.plane import Plane, fit_plane_lsq, ransac_plane

START_BAND = 0.08       # m: RANSAC's first band and the widest: a wall with 23 mm of noise
BAND_SIGMAS = 3.5       # the wall's band in robust standard deviations of its residuals
MIN_BAND = 5e-4         # m: the narrowest band (noise-free synthetic data, float32 files)
MAD_TO_SIGMA = 1.4826   # a normal distribution's standard deviation per median absolute deviation
SAMPLE = 20_000         # points a robust deviation or a typical spacing is measured on


def robust_sigma(x: NDArray) -> float:
    """1.4826 x the median absolute deviation of x from its median (0 for fewer than 2), on
    at most `SAMPLE` of them (evenly spaced: a robust deviation needs no more)."""
    if len(x) < 2:
        return 0.0
    x = x[::max(len(x) // SAMPLE, 1)]
    return float(MAD_TO_SIGMA * np.median(np.abs(x - np.median(x))))


@dataclass(frozen=True)
class Scan:
    """A scan's wall and structure, as measured on it.

    Attributes
    ----------
    plane : Plane
        The wall: the least-squares plane of the points within `band` of it.
    band : float
        Half-width of the wall's band (m): points within it are the wall.
    wall_sigma : float
        Robust standard deviation of the wall points' distances from the plane, m.
    range_noise : float
        Robust standard deviation of the range error along the rays, m.
    spacing : float
        Typical distance between neighbouring wall points (m); along a ring for a ring scan.
    ring_gap : float
        Typical distance between neighbouring rows (rings) on the wall (m), 0 for no rows.
    rings : ndarray, shape (N,), int, or None
        Each point's row (ring; -1: none), when the scan has rows and they were asked for.
    ring_count : int
        Rows crossing the wall, 0 for a cloud without rows.
    """

    plane: Plane
    band: float
    wall_sigma: float
    range_noise: float
    spacing: float
    ring_gap: float
    rings: NDArray | None
    ring_count: int

    @property
    def eps(self) -> float:
        """A clustering radius (m) that links an object's points across its rings and along
        them: 4 point spacings, 1.5 ring gaps, at least 5 mm."""
        return float(max(4 * self.spacing, 1.5 * self.ring_gap, 0.005))


def wall_plane(p: NDArray, band: float | None = None, seed: int | None = 0) -> tuple[Plane,
                                                                                    float, float]:
    """The dominant plane, its band (m) and the robust deviation of its points (m).

    With `band` None the band adapts to the wall's own residuals (see the module's note);
    a given band is kept, as RANSAC's threshold and the refits' band.
    """
    plane = ransac_plane(p, band or START_BAND, refits=1, seed=seed)
    if not plane.inliers.any():
        return plane, band or START_BAND, float("nan")
    normal, offset = plane.normal, plane.offset
    width = band or START_BAND
    # The band adapts on a sample of the points (a band needs no more); the last fit uses all.
    sample = p[::max(len(p) // SAMPLE, 1)]
    for _ in range(4 if band is None else 0):
        h = sample @ normal + offset
        inliers = np.abs(h) < width
        if inliers.sum() < 3:
            break
        normal, offset, _ = fit_plane_lsq(np.compress(inliers, sample, axis=0))
        h = sample @ normal + offset
        new = float(np.clip(BAND_SIGMAS * robust_sigma(h[np.abs(h) < width]), MIN_BAND,
                            START_BAND))
        converged = abs(new - width) < 0.02 * width
        width = new
        if converged:
            break
    inliers = np.abs(p @ normal + offset) < width
    if inliers.sum() >= 3:
        normal, offset, _ = fit_plane_lsq(np.compress(inliers, p, axis=0))
    h = p @ normal + offset
    inliers = np.abs(h) < width
    sigma = robust_sigma(h[inliers])
    rms = float(np.sqrt(np.mean(h[inliers] ** 2))) if inliers.any() else float("nan")
    return Plane(normal, float(offset), inliers, rms, plane.iterations), width, sigma


def _elevation_azimuth(p: NDArray) -> tuple[NDArray, NDArray]:
    return np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1])), np.arctan2(p[:, 1], p[:, 0])


def _rows(elevation: NDArray) -> tuple[NDArray, float] | None:
    """Rows of (nearly) equal elevation among `elevation` values (a sample of at most
    `SAMPLE` of them: every row of a scan has many points): their centres and the typical
    angular gap between neighbouring rows, or None if there are none."""
    e = np.sort(elevation[::max(len(elevation) // SAMPLE, 1)])
    d = np.diff(e)
    if len(d) < 10:
        return None
    split = d > max(20 * np.median(d), 2e-4)       # rad: 0.01 deg, far above float noise
    if split.sum() < 1:
        return None
    starts = np.concatenate([[0], np.flatnonzero(split) + 1])
    ends = np.concatenate([np.flatnonzero(split) + 1, [len(e)]])
    counts = ends - starts
    centres = np.add.reduceat(e, starts) / counts
    if np.median(counts) < 8:
        return None
    centres = centres[counts >= max(3, 0.1 * np.median(counts))]   # not stray points' rows
    if len(centres) < 2:
        return None
    return centres, float(np.median(np.diff(centres)))


def _step_along(row_of: NDArray, azimuth: NDArray, rows: int = 8) -> float:
    """Median azimuth step (rad) between neighbouring points of the same row, measured on
    the `rows` rows with the most points."""
    counts = np.bincount(row_of)
    chosen = np.isin(row_of, np.argsort(counts)[-rows:])
    r, az = row_of[chosen], azimuth[chosen]
    order = np.lexsort((az, r))
    same = r[order][1:] == r[order][:-1]
    steps = np.diff(az[order])[same]
    steps = steps[steps > 0]
    return float(np.median(steps)) if len(steps) else 0.0


def _wall_scale(p: NDArray, e: NDArray, a: NDArray, plane: Plane) -> tuple[float, float]:
    """Typical metres on the wall per radian of elevation and of azimuth (the derivative of
    where a ray meets the wall), the medians over points `p` (k, 3) at elevations `e` and
    azimuths `a`."""
    d = p / np.maximum(np.linalg.norm(p, axis=1), 1e-12)[:, None]
    de = np.stack([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)], axis=1)
    da = np.stack([-np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.zeros_like(e)], axis=1)
    dn = d @ plane.normal
    dn = np.where(np.abs(dn) < 1e-6, 1e-6, dn)
    t = -plane.offset / dn

    def scale(dd):
        return float(np.median(np.linalg.norm(
            t[:, None] * (dd - d * ((dd @ plane.normal) / dn)[:, None]), axis=1)))

    return scale(de), scale(da)


def measure_scan(p: NDArray, rings: NDArray | None = None, band: float | None = None,
                 seed: int | None = 0, *, labels: bool = True) -> Scan | None:
    """The wall and structure of scan `p` (N, 3), m; None when no plane holds 3 points.

    Parameters
    ----------
    p : ndarray, shape (N, 3), m, sensor frame (the sensor at the origin)
    rings : ndarray, shape (N,), int, optional
        Each point's ring as the file gives it; None to infer rings from the elevations.
    band : float, optional
        The wall's band (m); None to adapt it.
    seed : int or None
        RANSAC's seed.
    labels : bool
        Whether to give every point its row (`Scan.rings`, for an opening's search); without,
        only the spacings are measured.
    """
    plane, width, sigma = wall_plane(p, band, seed)
    inl = plane.inliers
    if inl.sum() < 3:
        return None
    q = np.compress(inl, p, axis=0)
    sample = q[::max(len(q) // SAMPLE, 1)]
    cos = np.abs(sample @ plane.normal) / np.maximum(np.linalg.norm(sample, axis=1), 1e-12)
    noise = robust_sigma((sample @ plane.normal + plane.offset) / np.maximum(cos, 0.05))
    e, a = _elevation_azimuth(q)
    row_of = None
    if rings is not None:
        ids, row_of = np.unique(np.asarray(rings)[inl], return_inverse=True)
        centres = (np.bincount(row_of, weights=e) / np.bincount(row_of)) \
            if len(ids) >= 2 else None
        found = None if centres is None else \
            (np.sort(centres), float(np.median(np.diff(np.sort(centres)))))
    else:
        found = _rows(e)
    if found is not None:
        centres, gap_angle = found
        if row_of is None:
            row_of = np.clip(np.searchsorted(centres, e - gap_angle / 2), 0, len(centres) - 1)
        step = _step_along(row_of, a)
        if step > 0:
            every = max(len(q) // 4000, 1)
            per_e, per_a = _wall_scale(q[::every], e[::every], a[::every], plane)
            point_rings = (None if not labels else np.asarray(rings).astype(np.int64)
                           if rings is not None
                           else _ring_labels(_elevation_azimuth(p)[0], centres, gap_angle))
            return Scan(plane, width, sigma, noise, per_a * step, per_e * gap_angle,
                        point_rings, int(len(centres)))
    return Scan(plane, width, sigma, noise, _spacing(q, plane), 0.0, None, 0)


def _ring_labels(e: NDArray, centres: NDArray, gap: float) -> NDArray:
    """Each point's row from its elevation `e`: the nearest row within a third of a gap (else
    -1)."""
    k = np.clip(np.searchsorted(centres, e), 1, len(centres) - 1)
    nearer = np.where(np.abs(e - centres[k - 1]) < np.abs(e - centres[k]), k - 1, k)
    return np.where(np.abs(e - centres[nearer]) < gap / 3, nearer, -1)


def _spacing(q: NDArray, plane: Plane) -> float:
    """Typical point spacing (m) of wall points: sqrt(area / count), the area being the
    bounding box of the middle 98 % along the wall's two directions (of at most 10,000)."""
    z = plane.normal
    x = np.cross([0.0, 0.0, 1.0], z)
    if np.linalg.norm(x) < 1e-6:
        x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    sample = q[::max(len(q) // 10_000, 1)]
    xy = np.column_stack([sample @ x, sample @ y])
    lo, hi = np.percentile(xy, [1, 99], axis=0)
    area = float(np.prod(np.maximum(hi - lo, 1e-9))) / 0.98**2
    return float(np.sqrt(area / max(len(q), 1)))
