"""After planning: shortcutting, path length, and resampling to N waypoints by arc length.

Lengths are joint-space Euclidean (rad, and m for prismatic joints), the metric the planners
steer by. Shortcuts are accepted only through the same validity object the planners use, so a
certified path stays certified.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.planning.clock import timer
from armkit.planning.collision import CollisionChecker
from armkit.planning.compiled import shortcut_compiled


def _path(path: ArrayLike) -> NDArray:
    p = np.asarray(path, dtype=float)
    if p.ndim != 2 or p.shape[0] < 1 or not np.isfinite(p).all():
        raise InputError(f"path: expected finite waypoints (k, n) with k >= 1, found shape "
                         f"{p.shape}")
    return p


def path_length(path: ArrayLike) -> float:
    """Joint-space length of the polyline through path (k, n): rad (and m)."""
    p = _path(path)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def _drop_repeats(p: NDArray) -> NDArray:
    keep = np.r_[True, np.any(np.diff(p, axis=0) != 0, axis=1)]
    return p[keep]


def _point_at(p: NDArray, cum: NDArray, s: float) -> tuple[int, NDArray]:
    """The segment index i (p[i] -> p[i+1]) holding arc length s, and the point there."""
    i = min(max(int(np.searchsorted(cum, s, side="right")) - 1, 0), len(p) - 2)
    seg = cum[i + 1] - cum[i]
    t = 0.0 if seg == 0 else (s - cum[i]) / seg
    return i, p[i] + t * (p[i + 1] - p[i])


def shortcut(path: ArrayLike, validity, *, seed: int | None = 0, tries: int = 64,
             min_gain: float = 0.01, deadline: NDArray | None = None) -> NDArray:
    """A shorter path through the same free space: random shortcuts, then greedy vertex
    reduction.

    Random shortcuts join two points drawn anywhere along the path (by arc length) by a
    straight edge where it is free; greedy vertex reduction then joins each kept vertex to the
    farthest later vertex it reaches straight. A draw whose shortcut would save less than
    `min_gain` of the path's length is not checked (certifying a long edge near obstacles
    costs many states for little). With a validity other than armkit's certified checker, the
    two pieces of old edges a shortcut keeps (from the vertex before its first point, and to
    the vertex after its last) are checked too: a sampled checker's edges are only as free as
    the states it checked.

    Parameters
    ----------
    path : array_like, (k, n)
        A valid path (its states and edges accepted by `validity`).
    validity
        A checker with ``valid_states`` and ``interior_free`` (see `armkit.planning.rrt`).
    seed : int or None
    tries : int
        Random shortcut attempts.
    min_gain : float
        The least saving worth checking, a fraction of the current path's length.
    deadline : ndarray, optional
        A `armkit.planning.clock.timer`: past it, no more shortcuts (the path so far is
        returned).

    Returns
    -------
    path : ndarray, (k', n)
        Same start and end, no longer than the input.
    """
    p = _drop_repeats(_path(path))
    if not (isinstance(min_gain, (int, float, np.floating)) and 0.0 <= min_gain < 1.0):
        raise InputError(f"min_gain: expected a fraction of the path's length in [0, 1), found "
                         f"{min_gain!r}")
    deadline = timer(math.inf) if deadline is None else deadline
    if isinstance(validity, CollisionChecker):                  # compiled
        return shortcut_compiled(validity, p, seed=seed, tries=tries, min_gain=min_gain,
                                 deadline=deadline)[0]
    late = int(deadline[2])
    ends_in_edge = bool(getattr(validity, "edge_checks_ends", False))
    rng = np.random.default_rng(seed)
    draws = np.sort(rng.random((tries, 2)), axis=1)          # arc-length fractions, drawn once
    cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    for f1, f2 in draws:
        if len(p) < 3 or time.monotonic_ns() >= late:
            break
        i1, a = _point_at(p, cum, f1 * cum[-1])
        i2, b = _point_at(p, cum, f2 * cum[-1])
        if i1 == i2 or (f2 - f1) * cum[-1] - np.linalg.norm(b - a) < min_gain * cum[-1]:
            continue
        if (ends_in_edge or validity.valid_states(np.vstack([a, b])).all()) and \
                all(validity.interior_free(u, v)[0] for u, v in
                    ((a, b), (p[i1], a), (b, p[i2 + 1]))):
            p = _drop_repeats(np.vstack([p[:i1 + 1], a, b, p[i2 + 1:]]))
            cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    out, i = [p[0]], 0
    while i < len(p) - 1:
        for j in range(len(p) - 1, i, -1):
            if j == i + 1 or (time.monotonic_ns() < late and validity.interior_free(p[i], p[j])[0]):
                out.append(p[j])
                i = j
                break
    return np.array(out)


def resample(path: ArrayLike, n: int) -> NDArray:
    """n waypoints along the path, evenly spaced by joint-space arc length, ends included.

    Parameters
    ----------
    path : array_like, (k, n_joints)
    n : int
        Waypoints, >= 2.

    Returns
    -------
    waypoints : ndarray, (n, n_joints)
    """
    p = _path(path)
    if not (isinstance(n, (int, np.integer)) and n >= 2):
        raise InputError(f"waypoints: expected a whole number >= 2, found {n!r}")
    cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    if len(p) == 1 or cum[-1] == 0:
        return np.repeat(p[:1], n, axis=0)
    s = np.linspace(0.0, cum[-1], n)
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(p) - 2)
    seg = cum[i + 1] - cum[i]
    t = np.divide(s - cum[i], seg, out=np.zeros_like(s), where=seg > 0)
    out = p[i] + t[:, None] * (p[i + 1] - p[i])
    out[-1] = p[-1]
    return out


def resample_keeping_vertices(path: ArrayLike, n: int) -> NDArray:
    """n waypoints that include every vertex of the path, the others spread over its segments
    in proportion to their lengths; every waypoint edge lies on the path itself.

    Raises
    ------
    InputError
        If n is smaller than the path's vertices.
    """
    p = _drop_repeats(_path(path))
    if n < len(p):
        raise InputError(f"waypoints: expected at least {len(p)} (the path's corners), found {n}")
    if len(p) == 1:
        return np.repeat(p, n, axis=0)
    lengths = np.linalg.norm(np.diff(p, axis=0), axis=1)
    extra = n - len(p)
    share = extra * lengths / lengths.sum()
    count = np.floor(share).astype(int)
    for k in np.argsort(count - share)[:extra - count.sum()]:        # largest remainders
        count[k] += 1
    out = [p[:1]]
    for i, c in enumerate(count):
        t = np.arange(1, c + 2)[:, None] / (c + 1)
        out.append(p[i] + t * (p[i + 1] - p[i]))
    result = np.vstack(out)
    result[-1] = p[-1]
    return result
