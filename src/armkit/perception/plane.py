"""The dominant plane of a cloud (the train's side): adaptive RANSAC, then a least-squares refit.

A plane is ``n . x + d = 0`` with a unit normal n; ``n . x + d`` is a point's signed distance.
Normals are turned so that the sensor's origin is on the positive side (d >= 0): points on the
sensor's side of the wall have positive heights.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError

SCORE_SAMPLE = 4096         # points a hypothesis is scored on; the refit uses every point
BATCH = 32                  # hypotheses drawn and scored together


@dataclass(frozen=True)
class Plane:
    """A fitted plane and its support.

    Attributes
    ----------
    normal : ndarray, shape (3,)
        Unit normal, pointing to the sensor's side.
    offset : float
        d in ``n . x + d = 0``, m (>= 0: the sensor's origin is on the positive side).
    inliers : ndarray, shape (N,), bool
        Points within the threshold of the final plane.
    rms : float
        Root-mean-square distance of the inliers to the plane, m.
    iterations : int
        RANSAC hypotheses drawn.
    """

    normal: NDArray
    offset: float
    inliers: NDArray
    rms: float
    iterations: int

    def __post_init__(self):
        self.normal.flags.writeable = False
        self.inliers.flags.writeable = False

    def distance(self, points: ArrayLike) -> NDArray:
        """Signed distances (N,) of points (N, 3) to the plane, m; positive on the sensor's side."""
        return np.asarray(points, float) @ self.normal + self.offset


def points_array(points: ArrayLike, name: str = "points") -> NDArray:
    """`points` as a finite float array of shape (N, 3) with N >= 1.

    Raises
    ------
    InputError
        ``points: expected shape (N, 3), found (10, 2)``, an empty cloud or NaN/inf.
    """
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an (N, 3) array of numbers, found "
                         f"{type(points).__name__}") from None
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"{name}: expected shape (N, 3), found {p.shape}")
    if len(p) == 0:
        raise InputError(f"{name}: expected at least one point, found an empty cloud")
    if not np.isfinite(p).all():
        raise InputError(f"{name}: expected finite coordinates, found "
                         f"{int((~np.isfinite(p).all(axis=1)).sum())} point(s) with NaN or inf")
    return p


def fit_plane_lsq(points: ArrayLike, weights: ArrayLike | None = None
                  ) -> tuple[NDArray, float, float]:
    """Least-squares plane through points (orthogonal distances, by the covariance's eigenvector).

    Parameters
    ----------
    points : array_like, shape (N, 3), N >= 3
    weights : array_like, shape (N,), optional

    Returns
    -------
    normal : ndarray, shape (3,)
        Unit normal, turned so that d >= 0.
    offset : float
        d, m.
    rms : float
        RMS orthogonal distance of the points, m.
    """
    p = np.asarray(points, float)
    if weights is None:
        w = None
        # Matrix-vector products rather than mean(axis=0) or p.T @ p: one single-threaded BLAS
        # pass each (OpenBLAS threads an (N, 3) matrix product, which waits on a busy machine).
        # Raw moments lose about 2 log10(|centroid| / spread) digits: 2 of 16 for a wall 1.5 m
        # away and 0.3 m across, harmless to the normal; the RMS comes from the residuals.
        centroid = np.full(len(p), 1.0 / len(p)) @ p
        second = np.stack([p.T @ np.ascontiguousarray(p[:, k]) for k in range(3)]) / len(p)
        cov = second - np.outer(centroid, centroid)
    else:
        w = np.asarray(weights, float)
        centroid = (w @ p) / w.sum()
        q = p - centroid
        cov = (q * w[:, None]).T @ q / w.sum()
    _, vectors = np.linalg.eigh(cov)
    normal = vectors[:, 0]
    offset = -float(normal @ centroid)
    if offset < 0:
        normal, offset = -normal, -offset
    # The residuals themselves, not sqrt of the smallest eigenvalue (which carries an error of
    # about sqrt(eps * largest) ~ 1e-8 m).
    h = p @ normal + offset
    rms = np.sqrt(np.mean(h * h) if w is None else (w @ (h * h)) / w.sum())
    return normal, offset, float(rms)


def ransac_plane(points: ArrayLike, threshold: float = 0.01, *, probability: float = 0.999,
                 max_iterations: int = 1000, refits: int = 2,
                 seed: int | None = 0) -> Plane:
    """The dominant plane by adaptive RANSAC, then least-squares refits on its inliers.

    Hypotheses (planes through 3 random points) are drawn in batches of 32 and scored on at most
    4096 points drawn once (with replacement); the number of hypotheses needed is updated from the best inlier
    ratio w as ``log(1 - probability) / log(1 - w^3)`` (Fischler and Bolles; Hartley and
    Zisserman, Alg. 4.5). The winner is refitted by least squares on every point within
    `threshold`, `refits` times.

    Parameters
    ----------
    points : array_like, shape (N, 3), m
    threshold : float
        Inlier distance, m.
    probability : float
        Wanted probability that one hypothesis is drawn from inliers only.
    max_iterations : int
        Cap on hypotheses.
    refits : int
        Least-squares refits (each takes the inliers of the previous plane).
    seed : int or None

    Returns
    -------
    Plane
        With ``inliers.sum() == 0`` only if no hypothesis had support (fewer than 3 points or
        all points on a line).

    Raises
    ------
    InputError
        If points are not (N, 3) finite or `threshold` is not positive.
    """
    p = points_array(points)
    if not (np.isfinite(threshold) and threshold > 0):
        raise InputError(f"threshold: expected a positive distance in m, found {threshold}")
    rng = np.random.default_rng(seed)
    n = len(p)
    if n < 3:
        return Plane(np.array([0.0, 0.0, 1.0]), 0.0, np.zeros(n, bool), float("nan"), 0)
    sample = p if n <= SCORE_SAMPLE else p[rng.integers(0, n, SCORE_SAMPLE)]
    best_count, best_normal, best_offset = -1, None, 0.0
    needed, drawn = max_iterations, 0
    while drawn < min(needed, max_iterations):
        idx = rng.integers(0, n, (BATCH, 3))
        a, b, c = p[idx[:, 0]], p[idx[:, 1]], p[idx[:, 2]]
        normals = np.cross(b - a, c - a)
        norms = np.linalg.norm(normals, axis=1)
        good = norms > 1e-12
        drawn += BATCH
        if not good.any():
            continue
        normals = normals[good] / norms[good, None]
        offsets = -np.einsum("ij,ij->i", normals, a[good])
        counts = (np.abs(sample @ normals.T + offsets) < threshold).sum(axis=0)
        k = int(np.argmax(counts))
        if counts[k] > best_count:
            best_count, best_normal, best_offset = int(counts[k]), normals[k], float(offsets[k])
            w = best_count / len(sample)
            if w >= 1.0:
                needed = drawn
            elif w > 0:
                needed = int(np.ceil(np.log(1 - probability) / np.log1p(-w**3)))
    if best_normal is None:
        return Plane(np.array([0.0, 0.0, 1.0]), 0.0, np.zeros(n, bool), float("nan"), drawn)
    normal, offset = best_normal, best_offset
    h = p @ normal + offset
    inliers = np.abs(h) < threshold
    for _ in range(refits):
        if inliers.sum() < 3:
            break
        normal, offset, _ = fit_plane_lsq(np.compress(inliers, p, axis=0))
        h = p @ normal + offset
        inliers = np.abs(h) < threshold
    if offset < 0:
        normal, offset = -normal, -offset
    h = h[inliers]
    rms = float(np.sqrt(np.mean(h * h))) if inliers.any() else float("nan")
    return Plane(normal, float(offset), inliers, rms, drawn)
