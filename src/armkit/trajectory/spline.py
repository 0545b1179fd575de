"""Splines through via points with a polynomial degree per segment: 3-3-3, 4-5-5, 5-5-5, any.

The tool-changer paper (SPEC.md, R4) moves its joints through via points with three segment
patterns: 3-3-3 (three cubics), 4-5-5 (a quartic, then two quintics) and 5-5-5. `spline` builds
any such pattern, for every joint at once, from one linear system.

Conditions, per joint (the same matrix for all joints; only the right-hand sides differ):

1. through the points: each segment starts and ends at its via points (2m rows);
2. continuity at each of the m - 1 interior knots of derivatives 1 .. ``continuity``
   (velocity and acceleration by default: 2(m - 1) rows);
3. the boundary values given: velocity (zero by default) and acceleration at start and end.
   Acceleration ``"auto"`` (the default) is zero at both ends when the pattern has the freedom
   for it after 1, 2 and the velocities, and free otherwise.

A segment of degree d has d + 1 coefficients. Whatever freedom remains after these conditions is
fixed by one rule: **least integrated squared jerk**, ``min sum_j int q_j'''(t)^2 dt`` (the
equality-constrained least squares is solved through its KKT system). Counted for m = 3:

=======  ============  ======================================================  =========
pattern  coefficients  conditions                                              left free
=======  ============  ======================================================  =========
3-3-3    12            6 points + 4 continuity + 2 end velocities              0
4-5-5    17            6 + 4 + 2 end velocities + 2 end accelerations          3
5-5-5    18            6 + 4 + 2 + 2                                           4
=======  ============  ======================================================  =========

So 3-3-3 is fully determined and its end accelerations are whatever they come out (not zero:
the acceleration steps at start and end, as the paper shows). For 5-5-5, least jerk is the same
as the highest continuity the degrees allow: the minimiser over piecewise quintics satisfies
``q^(6) = 0`` inside, and its stationarity conditions at each interior knot make the jumps of
jerk and snap vanish, so the result is C4 (a quintic spline). For 4-5-5 the quartic first
segment leaves only one of those two conditions at the first via point: jerk and snap are
continuous at the second via point, and at the first one weighted combination of their jumps is
zero (``6 [q'''] = h_1 [q'''']``, h_1 the quartic's duration; see the tests).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from math import factorial

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.sparse.linalg import splu

from armkit.errors import InputError
from armkit.trajectory.piecewise import Trajectory, _falling

PAPER_PATTERNS = ("3-3-3", "4-5-5", "5-5-5")
Boundary = ArrayLike | str | None


def spline(times: ArrayLike, points: ArrayLike, degrees: int | str | Sequence[int] = 3, *,
           start_velocity: Boundary = 0.0, end_velocity: Boundary = 0.0,
           start_acceleration: Boundary = "auto", end_acceleration: Boundary = "auto",
           continuity: int = 2) -> Trajectory:
    """A piecewise polynomial through via points, one degree per segment, all joints at once.

    Parameters
    ----------
    times : array_like, shape (m + 1,)
        Knot times (s), strictly increasing.
    points : array_like, shape (m + 1, n)
        Joint values at the knots, rad or m (a 1-D array is one joint).
    degrees : int, str or sequence of m ints
        Degree per segment: ``5``, ``"4-5-5"``, ``[4, 5, 5]``.
    start_velocity, end_velocity : float, array_like (n,), or None
        Velocity at the ends (rad/s or m/s); None leaves it free. Zero by default.
    start_acceleration, end_acceleration : float, array_like (n,), None or "auto"
        Acceleration at the ends; ``"auto"``: zero at both ends if the pattern has the freedom
        (see the module notes), else free.
    continuity : int
        Highest derivative continuous at interior knots (2: velocity and acceleration).

    Returns
    -------
    Trajectory
        ``knots`` are the given times; ``label`` the pattern, e.g. ``"4-5-5"``.

    Raises
    ------
    InputError
        For bad shapes or times, or a pattern whose degrees cannot meet the conditions (more
        conditions than coefficients, or conditions that contradict each other).

    Example
    -------
    >>> tr = spline([0, 2, 4, 5], np.deg2rad([[50.4], [43.2], [35], [27]]), "4-5-5")
    >>> tr.sample([0, 1, 5]).qd[:, 0]          # rad/s; zero at both ends
    """
    t, q = _knots(times, points)
    m, n = t.shape[0] - 1, q.shape[1]
    deg = parse_degrees(degrees, m)
    if not (isinstance(continuity, (int, np.integer)) and 0 <= continuity):
        raise InputError(f"continuity: expected an integer >= 0, found {continuity!r}")
    given = {(0, 1): _boundary("start_velocity", start_velocity, n),
             (1, 1): _boundary("end_velocity", end_velocity, n),
             (0, 2): _boundary("start_acceleration", start_acceleration, n),
             (1, 2): _boundary("end_acceleration", end_acceleration, n)}
    unknowns = int(np.sum(deg + 1))
    fixed = 2 * m + continuity * (m - 1) + sum(isinstance(v, np.ndarray) for v in given.values())
    auto = [key for key, v in given.items() if isinstance(v, str)]
    zero_autos = unknowns - fixed >= len(auto)
    for key in auto:
        given[key] = np.zeros(n) if zero_autos else None
    system = _System(t, deg)
    for i in range(m):
        system.add(i, 0, 0, q[i])
        system.add(i, 1, 0, q[i + 1])
    for i in range(1, m):
        for r in range(1, continuity + 1):
            system.add_continuity(i, r)
    for (side, r), value in given.items():
        if value is not None:
            system.add(0 if side == 0 else m - 1, side, r, value)
    label = "-".join(str(d) for d in deg)
    c = system.solve(label, n, continuity, given)
    return Trajectory(t, system.to_time(c), knots=t, label=label)


def patterns(times: ArrayLike, points: ArrayLike,
             which: Sequence[int | str | Sequence[int]] = PAPER_PATTERNS,
             **conditions) -> dict[str, Trajectory]:
    """`spline` for several degree patterns through the same points, by label.

    Parameters
    ----------
    times, points : as for `spline`
    which : sequence of patterns
        Default: the paper's 3-3-3, 4-5-5 and 5-5-5.
    **conditions
        Passed to `spline` (boundary values, continuity).

    Returns
    -------
    dict of str to Trajectory
        Keyed by pattern label, in the order given.
    """
    out = {}
    for pattern in which:
        tr = spline(times, points, pattern, **conditions)
        out[tr.label] = tr
    return out


def parse_degrees(degrees: int | str | Sequence[int], m: int) -> NDArray:
    """Degrees per segment (m,) from ``5``, ``"4-5-5"`` or ``[4, 5, 5]``."""
    if isinstance(degrees, str):
        try:
            deg = [int(d) for d in degrees.split("-")]
        except ValueError:
            raise InputError(f"degrees: expected a pattern such as 4-5-5, found {degrees!r}") \
                from None
    elif isinstance(degrees, (int, np.integer)):
        deg = [int(degrees)] * m
    else:
        deg = list(degrees)
    if len(deg) != m:
        raise InputError(f"degrees: expected {m} segment degrees (one per segment between "
                         f"{m + 1} knots), found {len(deg)}")
    if not all(isinstance(d, (int, np.integer)) and 1 <= d <= 15 for d in deg):
        raise InputError(f"degrees: expected integers from 1 to 15, found {deg}")
    return np.array(deg, dtype=int)


def _knots(times: ArrayLike, points: ArrayLike) -> tuple[NDArray, NDArray]:
    try:
        t = np.asarray(times, dtype=float)
        q = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InputError("times, points: expected numbers") from None
    if t.ndim != 1 or t.shape[0] < 2:
        raise InputError(f"times: expected shape (m + 1,) with at least 2 knots, found {t.shape}")
    if q.ndim == 1:
        q = q[:, None]
    if q.ndim != 2 or q.shape[0] != t.shape[0]:
        raise InputError(f"points: expected shape ({t.shape[0]}, n), one row per knot, "
                         f"found {q.shape}")
    if not (np.isfinite(t).all() and np.isfinite(q).all()):
        raise InputError("times, points: expected finite values, found NaN or inf")
    if not (np.diff(t) > 0).all():
        raise InputError(f"times: expected strictly increasing knot times, found {t.tolist()}")
    return t, q


def _boundary(name: str, value: Boundary, n: int) -> NDArray | str | None:
    if value is None or (isinstance(value, str) and value == "auto"):
        return value
    try:
        v = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a number, {n} numbers, None or 'auto', "
                         f"found {value!r}") from None
    if not np.isfinite(v).all():
        raise InputError(f"{name}: expected finite values, found {value!r}")
    return v


class _System:
    """Rows of the linear conditions on the coefficients of all segments.

    Segment i is written in its own normalised time ``u = (t - t_i) / h_i`` in [0, 1], with
    coefficients ``a[off_i + k]`` of ``u**k``; so a row for derivative r at an end of the
    segment is ``d^r/du^r`` divided by ``h_i**r``. Rows are scaled to order one.
    """

    def __init__(self, t: NDArray, deg: NDArray):
        self.h, self.deg = np.diff(t), deg
        self.off = np.r_[0, np.cumsum(deg + 1)]
        self.rows, self.cols, self.vals, self.rhs = [], [], [], []

    def _entries(self, i: int, side: int, r: int) -> tuple[list[int], list[float]]:
        """Columns and weights of ``h_i**r * d^r q / dt^r`` at u = side of segment i."""
        d = self.deg[i]
        if side == 0:
            return ([self.off[i] + r], [float(factorial(r))]) if r <= d else ([], [])
        ks = range(r, d + 1)
        return [self.off[i] + k for k in ks], [_falling(k, r) for k in ks]

    def _row(self, cols, vals, rhs) -> None:
        row = len(self.rhs)
        self.rows += [row] * len(cols)
        self.cols += cols
        self.vals += vals
        self.rhs.append(rhs)

    def add(self, i: int, side: int, r: int, value: NDArray) -> None:
        """Derivative r of segment i at its start (side 0) or end (side 1) equals value."""
        cols, vals = self._entries(i, side, r)
        self._row(cols, vals, np.asarray(value, dtype=float) * self.h[i] ** r)

    def add_continuity(self, i: int, r: int) -> None:
        """Derivative r continuous at knot i (end of segment i - 1 = start of segment i)."""
        scale = min(self.h[i - 1], self.h[i]) ** r
        left_c, left_v = self._entries(i - 1, 1, r)
        right_c, right_v = self._entries(i, 0, r)
        self._row(left_c + right_c,
                  [v * scale / self.h[i - 1] ** r for v in left_v]
                  + [-v * scale / self.h[i] ** r for v in right_v], 0.0)

    def _jerk_weights(self) -> sp.csc_matrix:
        """H with ``a^T H a = int sum q'''(t)^2 dt`` over all segments (block diagonal).

        On segment i, ``int_0^h_i (q''')^2 dt = h_i**-5 int_0^1 (d^3 q/du^3)^2 du`` and
        ``int_0^1 u^(k-3) u^(l-3) du = 1 / (k + l - 5)``.
        """
        rows, cols, vals = [], [], []
        for i, d in enumerate(self.deg):
            for k in range(3, d + 1):
                for l in range(3, d + 1):
                    rows.append(self.off[i] + k)
                    cols.append(self.off[i] + l)
                    vals.append(_falling(k, 3) * _falling(l, 3) / (k + l - 5) / self.h[i] ** 5)
        U = int(self.off[-1])
        H = sp.csc_matrix((vals, (rows, cols)), shape=(U, U))
        return H / max(1.0, abs(H).max()) if vals else H

    def solve(self, label: str, n: int, continuity: int, given: Mapping) -> NDArray:
        """Coefficients (U, n): the conditions, and least squared jerk for what they leave."""
        U, R = int(self.off[-1]), len(self.rhs)
        b = np.array([np.broadcast_to(v, (n,)) for v in self.rhs])
        A = sp.csc_matrix((self.vals, (self.rows, self.cols)), shape=(R, U))
        if R > U:
            ends = [name for (side, r), name in zip(given, ("start velocity", "end velocity",
                                                            "start acceleration",
                                                            "end acceleration"))
                    if given[(side, r)] is not None]
            raise InputError(
                f"degrees: pattern {label} has {U} coefficients per joint but {R} conditions "
                f"(through {len(self.h) + 1} points, derivatives 1..{continuity} continuous at "
                f"{len(self.h) - 1} knots, {', '.join(ends) or 'no end values'}); "
                "raise a degree or leave an end value free")
        if R == U:
            K, rhs = A, b
        else:
            K = sp.bmat([[self._jerk_weights(), A.T], [A, None]], format="csc")
            rhs = np.vstack([np.zeros((U, n)), b])
        try:
            x = splu(K).solve(rhs)
        except RuntimeError:
            x = None
        if x is None or not np.isfinite(x).all() or \
                np.abs(A @ x[:U] - b).max() > 1e-9 * (1.0 + np.abs(b).max()):
            raise InputError(f"degrees: pattern {label} cannot meet its conditions (they "
                             "contradict or leave the motion undetermined); change a degree "
                             "or an end value")
        return x[:U]

    def to_time(self, a: NDArray) -> NDArray:
        """Coefficients in powers of (t - t_i), zero padded: shape (m, max degree + 1, n)."""
        m, K = self.deg.shape[0], int(self.deg.max()) + 1
        out = np.zeros((m, K, a.shape[1]))
        for i, d in enumerate(self.deg):
            out[i, :d + 1] = a[self.off[i]:self.off[i] + d + 1] / self.h[i] ** \
                np.arange(d + 1)[:, None]
        return out
