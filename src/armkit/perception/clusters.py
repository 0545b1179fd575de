"""Clustering of points: DBSCAN and Euclidean clustering on a scipy k-d tree, vectorised.

`dbscan` gives the labels scikit-learn's ``DBSCAN(eps, min_samples).fit(points).labels_`` gives:
neighbourhoods include the point itself and distances equal to eps; clusters are numbered in the
order of their first core point; a border point reached by several clusters takes the first.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from armkit.errors import InputError
from armkit.perception.plane import points_array


def dbscan(points: ArrayLike, eps: float, min_samples: int = 5) -> NDArray:
    """Density-based clusters (Ester et al. 1996), labels as scikit-learn's DBSCAN.

    Parameters
    ----------
    points : array_like, shape (N, 3), m
    eps : float
        Neighbourhood radius, m.
    min_samples : int
        Points within eps (the point included) that make a core point.

    Returns
    -------
    labels : ndarray, shape (N,), int
        0, 1, ... per cluster in the order of each cluster's lowest-index core point; -1 noise.
    """
    p = points_array(points)
    if not (np.isfinite(eps) and eps > 0):
        raise InputError(f"eps: expected a positive radius in m, found {eps}")
    if min_samples < 1:
        raise InputError(f"min_samples: expected at least 1, found {min_samples}")
    n = len(p)
    pairs = cKDTree(p).query_pairs(eps, output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    core = np.bincount(pairs.ravel(), minlength=n) + 1 >= min_samples
    both = core[i] & core[j]
    graph = coo_matrix((np.ones(both.sum(), np.int8), (i[both], j[both])), shape=(n, n))
    _, component = connected_components(graph, directed=False)
    labels = np.full(n, -1, np.int64)
    # Number the components of core points by their lowest index, as sklearn meets them.
    core_idx = np.flatnonzero(core)
    comp = component[core_idx]
    first = np.full(component.max() + 1 if n else 0, n, np.int64)
    np.minimum.at(first, comp, core_idx)
    used = np.flatnonzero(first < n)
    rank = np.empty_like(first)
    rank[used[np.argsort(first[used])]] = np.arange(len(used))
    labels[core_idx] = rank[comp]
    # A border point (not core, a core point within eps) takes the lowest label among them.
    edge_a = np.concatenate([i, j])
    edge_b = np.concatenate([j, i])
    to_border = core[edge_a] & ~core[edge_b]
    if to_border.any():
        border_label = np.full(n, np.iinfo(np.int64).max)
        np.minimum.at(border_label, edge_b[to_border], labels[edge_a[to_border]])
        border = np.flatnonzero(~core & (border_label < np.iinfo(np.int64).max))
        labels[border] = border_label[border]
    return labels


def euclidean_clusters(points: ArrayLike, tolerance: float, min_size: int = 1) -> NDArray:
    """Euclidean clustering (as PCL's): connected sets of points linked within `tolerance`.

    Parameters
    ----------
    points : array_like, shape (N, 3), m
    tolerance : float
        Link distance, m.
    min_size : int
        Clusters smaller than this are labelled -1.

    Returns
    -------
    labels : ndarray, shape (N,), int
        0, 1, ... by decreasing size (ties by lowest index); -1 for points of small clusters.
    """
    labels = dbscan(points, tolerance, 1)
    sizes = np.bincount(labels)
    order = np.lexsort((np.arange(len(sizes)), -sizes))
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    out = rank[labels]
    out[sizes[labels] < min_size] = -1
    return out
