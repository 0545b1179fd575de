"""Helpers the benchmark scripts share: timing, and the plain NumPy forward kinematics baseline."""

from __future__ import annotations

import time

import numpy as np

from armkit.model.dh import DHTable


def best_of(f, repeat: int) -> float:
    """Shortest wall time of `repeat` calls (s): the least disturbed by a shared machine."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def numpy_chain(table: DHTable):
    """Plain NumPy baseline: build every DH matrix of the batch, multiply with einsum."""
    def fk(Q):
        T = np.broadcast_to(np.eye(4), (Q.shape[0], 4, 4))
        for row, q in zip(table.rows, Q.T):
            th = q + row.theta
            ct, st, ca, sa = np.cos(th), np.sin(th), np.cos(row.alpha), np.sin(row.alpha)
            A = np.zeros((Q.shape[0], 4, 4))
            A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = ct, -st * ca, st * sa, row.a * ct
            A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = st, ct * ca, -ct * sa, row.a * st
            A[:, 2, 1], A[:, 2, 2], A[:, 2, 3], A[:, 3, 3] = sa, ca, row.d, 1.0
            T = np.einsum("nij,njk->nik", T, A)
        return T
    return fk
