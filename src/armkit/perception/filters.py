"""Cloud filters: voxel down-sampling and statistical outlier removal, vectorised."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from armkit.errors import InputError
from armkit.perception.plane import points_array


def voxel_downsample(points: ArrayLike, voxel: float) -> NDArray:
    """One point per occupied voxel: the centroid of the points inside it.

    Parameters
    ----------
    points : array_like, shape (N, 3), m
    voxel : float
        Voxel edge, m; voxels are aligned with the origin.

    Returns
    -------
    ndarray, shape (M, 3)
        Centroids, ordered by voxel index (M <= N).
    """
    p = points_array(points)
    if not (np.isfinite(voxel) and voxel > 0):
        raise InputError(f"voxel: expected a positive edge in m, found {voxel}")
    ijk = np.floor(p / voxel).astype(np.int64)
    ijk -= ijk.min(axis=0)
    span = ijk.max(axis=0) + 1
    key = (ijk[:, 0] * span[1] + ijk[:, 1]) * span[2] + ijk[:, 2]
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    sums = np.zeros((len(counts), 3))
    for axis in range(3):
        sums[:, axis] = np.bincount(inverse, weights=p[:, axis], minlength=len(counts))
    return sums / counts[:, None]


def statistical_outliers(points: ArrayLike, k: int = 8, std_ratio: float = 2.0) -> NDArray:
    """Which points are statistical outliers (as PCL's StatisticalOutlierRemoval).

    A point is an outlier when its mean distance to its `k` nearest neighbours exceeds the mean
    of that figure over the cloud by more than `std_ratio` standard deviations.

    Parameters
    ----------
    points : array_like, shape (N, 3), m
    k : int
        Neighbours per point (>= 1).
    std_ratio : float

    Returns
    -------
    ndarray, shape (N,), bool
        True for outliers.
    """
    p = points_array(points)
    if k < 1:
        raise InputError(f"k: expected at least 1 neighbour, found {k}")
    if len(p) <= k:
        return np.zeros(len(p), bool)
    dist, _ = cKDTree(p).query(p, k=k + 1)
    mean = dist[:, 1:].mean(axis=1)
    return mean > mean.mean() + std_ratio * mean.std()


def remove_statistical_outliers(points: ArrayLike, k: int = 8, std_ratio: float = 2.0) -> NDArray:
    """The points (M, 3) that are not statistical outliers (see `statistical_outliers`)."""
    p = points_array(points)
    return p[~statistical_outliers(p, k, std_ratio)]
