"""Helpers the benchmark scripts share: timing over interleaved rounds with its spread, the
machine's load, and the plain NumPy forward kinematics baseline.

Every figure is timed over several rounds, and within a round armkit and its references run one
after the other (interleaved), so that a burst of load from other work on a shared machine
slows both alike instead of one alone; a figure is reported as min-median-max over the rounds,
its ratio as the ratio of the medians with the range of the per-round ratios.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

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


@dataclass(frozen=True)
class Spread:
    """Per-call times (s) of one function over the rounds."""

    times: tuple[float, ...]

    @property
    def min(self) -> float:
        return min(self.times)

    @property
    def median(self) -> float:
        return float(np.median(self.times))

    @property
    def max(self) -> float:
        return max(self.times)

    def text(self, unit: str = "us") -> str:
        """``median [min-max] unit``."""
        k = {"s": 1.0, "ms": 1e3, "us": 1e6, "ns": 1e9}[unit]
        digits = 3 if self.median * k < 10 else 1
        return (f"{self.median * k:.{digits}f} [{self.min * k:.{digits}f}-"
                f"{self.max * k:.{digits}f}] {unit}")


def interleaved(functions: dict[str, Callable[[], object]], rounds: int = 7,
                number: int = 1, clock: Callable[[], float] = time.perf_counter
                ) -> dict[str, Spread]:
    """Time each function over `rounds` rounds of `number` calls, the functions taking turns
    within each round; the per-call time of every round, per function. `clock` is wall time
    by default (``time.thread_time``: this thread's CPU time)."""
    times: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(rounds):
        for name, f in functions.items():
            start = clock()
            for _ in range(number):
                f()
            times[name].append((clock() - start) / number)
    return {name: Spread(tuple(t)) for name, t in times.items()}


def ratio(reference: Spread, ours: Spread) -> str:
    """Reference time / armkit time: the ratio of the medians and the range of the per-round
    ratios (the rounds are interleaved, so each round's pair saw the same load)."""
    per_round = [r / o for r, o in zip(reference.times, ours.times)]
    return f"{reference.median / ours.median:.2f}x [{min(per_round):.2f}-{max(per_round):.2f}]"


def load() -> str:
    """The machine's load averages and core count, printed with every run's figures."""
    one, five, fifteen = os.getloadavg()
    return (f"load average {one:.2f} {five:.2f} {fifteen:.2f} (1, 5, 15 min) on "
            f"{os.cpu_count()} cores")


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
