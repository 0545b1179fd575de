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


def robust_sigma(x: NDArray) -> float:
    """1.4826 x the median absolute deviation of x from its median (0 for fewer than 2)."""
    if len(x) < 2:
        return 0.0
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
        Each point's row (ring; -1: none), when the scan has rows.
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
    for _ in range(4):
        h = p @ normal + offset
        inliers = np.abs(h) < width
        if inliers.sum() < 3:
            break
        normal, offset, _ = fit_plane_lsq(np.compress(inliers, p, axis=0))
        h = p @ normal + offset
        sigma = robust_sigma(h[np.abs(h) < width])
        if band is not None:
            break
        new = float(np.clip(BAND_SIGMAS * sigma, MIN_BAND, START_BAND))
        if abs(new - width) < 0.02 * width:
            width = new
            break
        width = new
    h = p @ normal + offset
    inliers = np.abs(h) < width
    sigma = robust_sigma(h[inliers])
    rms = float(np.sqrt(np.mean(h[inliers] ** 2))) if inliers.any() else float("nan")
    return Plane(normal, float(offset), inliers, rms, plane.iterations), width, sigma


def _elevation_azimuth(p: NDArray) -> tuple[NDArray, NDArray]:
    return np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1])), np.arctan2(p[:, 1], p[:, 0])


def _rows(elevation: NDArray) -> tuple[NDArray, float] | None:
    """Rows of (nearly) equal elevation among sorted-able `elevation` values: their centres
    and the typical angular gap between neighbouring rows, or None if there are none."""
    e = np.sort(elevation)
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


def _step_along(elevation_row: NDArray, azimuth: NDArray) -> float:
    """Median azimuth step (rad) between neighbouring points of the same row."""
    order = np.lexsort((azimuth, elevation_row))
    same = elevation_row[order][1:] == elevation_row[order][:-1]
    steps = np.diff(azimuth[order])[same]
    steps = steps[steps > 0]
    return float(np.median(steps)) if len(steps) else 0.0


def _wall_scale(p: NDArray, plane: Plane) -> tuple[NDArray, NDArray]:
    """Per point, metres on the wall per radian of elevation and of azimuth (the derivative
    of where a ray meets the wall)."""
    r = np.linalg.norm(p, axis=1)
    d = p / np.maximum(r, 1e-12)[:, None]
    e, a = _elevation_azimuth(p)
    de = np.stack([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)], axis=1)
    da = np.stack([-np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.zeros_like(e)], axis=1)
    dn = d @ plane.normal
    dn = np.where(np.abs(dn) < 1e-6, 1e-6, dn)
    t = -plane.offset / dn

    def scale(dd):
        return np.linalg.norm(t[:, None] * (dd - d * ((dd @ plane.normal) / dn)[:, None]),
                              axis=1)

    return scale(de), scale(da)


def measure_scan(p: NDArray, rings: NDArray | None = None, band: float | None = None,
                 seed: int | None = 0) -> Scan | None:
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
    """
    plane, width, sigma = wall_plane(p, band, seed)
    inl = plane.inliers
    if inl.sum() < 3:
        return None
    q = np.compress(inl, p, axis=0)
    cos = np.abs(q @ plane.normal) / np.maximum(np.linalg.norm(q, axis=1), 1e-12)
    h = q @ plane.normal + plane.offset
    noise = robust_sigma(h / np.maximum(cos, 0.05))
    e, a = _elevation_azimuth(q)
    per_e, per_a = _wall_scale(q, plane)
    row_of = None
    if rings is not None:
        labels = np.asarray(rings)[inl]
        ids, row_of = np.unique(labels, return_inverse=True)
        centres = np.array([np.median(e[row_of == k]) for k in range(len(ids))]) \
            if len(ids) <= 4096 else None
        found = None if centres is None or len(ids) < 2 else \
            (np.sort(centres), float(np.median(np.diff(np.sort(centres)))))
    else:
        found = _rows(e)
    if found is not None:
        centres, gap_angle = found
        if row_of is None:
            row_of = np.clip(np.searchsorted(centres, e - gap_angle / 2), 0, len(centres) - 1)
        step = _step_along(row_of.astype(float), a)
        if step > 0:
            along = float(np.median(per_a) * step)
            across = float(np.median(per_e) * gap_angle)
            point_rings = _ring_labels(p, centres, gap_angle, rings)
            return Scan(plane, width, sigma, noise, along, across, point_rings,
                        int(len(centres)))
    xy_span = _spacing(q, plane)
    return Scan(plane, width, sigma, noise, xy_span, 0.0, None, 0)


def _ring_labels(p: NDArray, centres: NDArray, gap: float, rings: NDArray | None) -> NDArray:
    """Each point's ring: the file's, or the nearest row within a third of a gap (else -1)."""
    if rings is not None:
        return np.asarray(rings).astype(np.int64)
    e, _ = _elevation_azimuth(p)
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
