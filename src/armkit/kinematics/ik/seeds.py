"""Starts for the numeric solvers: a bank of configurations sampled inside the limits, and the
ones nearest a target.

A start near the target turns most solves into a few Gauss-Newton steps. The bank is derived
from the robot once (by `armkit.kinematics.ik.IKSolver`) and read-only after: its sampled
configurations, their pose features and their tool positions sorted into a grid, so that each
target ranks only the samples in the grid cells around its own position (and further out until
it has enough).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.jit import kernel
from armkit.kinematics import core

_jit = kernel(cache=True, nogil=True, error_model="numpy")


def feature_columns(mask: NDArray) -> NDArray:
    """Columns of `SeedBank.features` that measure a task: the position, and the tool axes
    the mask constrains (two axes fix an orientation; the pointing axis for two flags; for one
    flag an axis that the rotation about it turns)."""
    return _COLUMNS[(bool(mask[3]), bool(mask[4]), bool(mask[5]))]


def _columns(rotation_flags: tuple[bool, bool, bool]) -> NDArray:
    flags = np.flatnonzero(rotation_flags)
    if flags.size == 3:
        axes = [0, 2]
    elif flags.size == 2:
        axes = [3 - flags.sum()]
    elif flags.size == 1:
        axes = [(flags[0] + 1) % 3]
    else:
        axes = []
    return np.array([0, 1, 2] + [3 + 3 * a + c for a in axes for c in range(3)], dtype=np.int64)


# The columns of each of the eight rotation-flag combinations, fixed at import.
_COLUMNS = {(a, b, c): _columns((a, b, c)) for a in (False, True) for b in (False, True)
            for c in (False, True)}


def features(T: NDArray, length: float) -> NDArray:
    """Pose features (..., 12) whose distances approximate task errors: the position, then the
    tool's x, y and z axes times `length` (m per rad)."""
    if T.shape == (1, 4, 4):
        # One pose (a single IK call's): the same products in plain Python, several times
        # cheaper than NumPy's calls on so small an array.
        v = T.ravel().tolist()
        return np.array([[v[3], v[7], v[11]] + [v[4 * r + c] * length for c in range(3)
                                                for r in range(3)]])
    F = np.swapaxes(T[..., :3, (3, 0, 1, 2)], -1, -2).reshape(T.shape[:-2] + (12,))
    F[..., 3:] *= length
    return F


@_jit
def _cell(p, lo, inv, G):
    """Grid cell (i, j, k) of the point p (3,), clipped to the G x G x G grid."""
    return (min(max(int((p[0] - lo[0]) * inv[0]), 0), G - 1),
            min(max(int((p[1] - lo[1]) * inv[1]), 0), G - 1),
            min(max(int((p[2] - lo[2]) * inv[2]), 0), G - 1))


def _grid(P, lo, inv, G):
    """Points P (S, 3) sorted by grid cell: (order (S,), start (G^3 + 1,)); the points of cell
    c are ``order[start[c]:start[c + 1]]``, in their original order (a stable sort)."""
    ijk = np.clip(((P - lo) * inv).astype(np.int64), 0, G - 1)     # as `_cell`
    cells = (ijk[:, 0] * G + ijk[:, 1]) * G + ijk[:, 2]
    order = np.argsort(cells, kind="stable")
    start = np.zeros(G * G * G + 1, dtype=np.int64)
    start[1:] = np.cumsum(np.bincount(cells, minlength=G * G * G))
    return order, start


@_jit
def _nearest(F_targets, F, cols, lo, inv, G, order, start, best):
    """For each target t, the best.shape[1] samples nearest F_targets[t] (columns `cols`) into
    best[t], searched cell shell by cell shell around the target's position until enough are
    found."""
    count = best.shape[1]
    dist = np.empty(count)
    for t in range(F_targets.shape[0]):
        f = F_targets[t]
        for b in range(count):
            dist[b] = np.inf
        found = 0
        ci, cj, ck = _cell(f, lo, inv, G)
        for r in range(G):
            for i in range(max(ci - r, 0), min(ci + r, G - 1) + 1):
                for j in range(max(cj - r, 0), min(cj + r, G - 1) + 1):
                    for k in range(max(ck - r, 0), min(ck + r, G - 1) + 1):
                        if max(abs(i - ci), abs(j - cj), abs(k - ck)) != r:
                            continue                    # scanned in an earlier shell
                        c = (i * G + j) * G + k
                        for a in range(start[c], start[c + 1]):
                            s = order[a]
                            d = 0.0
                            for m in cols:
                                d += (F[s, m] - f[m]) ** 2
                            if d < dist[count - 1]:     # insert into the sorted shortlist
                                b = count - 1
                                while b > 0 and dist[b - 1] > d:
                                    dist[b], best[t, b] = dist[b - 1], best[t, b - 1]
                                    b -= 1
                                dist[b], best[t, b] = d, s
                            found += 1
            if found >= count and r >= 1:
                break


@dataclass(frozen=True)
class SeedBank:
    """Configurations sampled inside the limits and what ranks them against a target.

    Attributes
    ----------
    q : ndarray, shape (S, n)
        The samples.
    features : ndarray, shape (S, 12)
        Their `features` (tool position, tool axes times `length`).
    length : float
        m per rad in the features.
    lo, inv : ndarray, shape (3,)
        Grid origin (m) and cells per m along each axis.
    cells : int
        Grid cells per side.
    order, start : ndarray of int
        Samples sorted by cell (see `_grid`).
    """

    q: NDArray
    features: NDArray
    length: float
    lo: NDArray
    inv: NDArray
    cells: int
    order: NDArray
    start: NDArray

    @classmethod
    def build(cls, robot, samples: int, length: float, seed: int = 0) -> "SeedBank":
        """Draw `samples` configurations uniformly inside `Chain.sampling_limits` (seeded), and
        sort them. About 1 ms for 4096 samples of a 6-DOF arm."""
        rng = np.random.default_rng([seed, 0x5EED])
        Q = rng.uniform(*robot.chain.sampling_limits, (samples, robot.n))
        # The serial batch loop: a bank of a few thousand samples is built in about 1 ms on
        # one thread, and thread start-up on a busy machine would cost ten times that.
        T = np.empty((samples, 4, 4))
        k = robot.chain.kernel
        core.poses.light(Q, k.F, k.I, T)
        P = np.ascontiguousarray(T[:, :3, 3])
        G = max(1, round(samples ** (1 / 3)))
        lo = P.min(axis=0)
        inv = G / np.maximum(P.max(axis=0) - lo, 1e-12)
        order, start = _grid(P, lo, inv, G)
        bank = cls(Q, np.ascontiguousarray(features(T, length)), float(length), lo, inv, G,
                   order, start)
        for a in (Q, bank.features, lo, inv, order, start):
            a.setflags(write=False)
        return bank

    def starts(self, targets: NDArray, mask: NDArray, count: int) -> NDArray:
        """Starts (N, count, n) for targets (N, 4, 4): the `count` samples nearest each target
        by the features the mask uses, nearest first."""
        best = np.empty((targets.shape[0], min(count, self.q.shape[0])), dtype=np.int64)
        wanted = np.ascontiguousarray(features(targets, self.length))
        _nearest.sized(targets.shape[0], wanted, self.features, feature_columns(mask), self.lo,
                       self.inv, self.cells, self.order, self.start, best)
        return self.q.take(best, axis=0)        # as self.q[best], without fancy indexing's cost
