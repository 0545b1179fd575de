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
equality-constrained least squares is solved through its KKT system, banded, one LU for all
joints). Counted for m = 3:

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

The "auto" rule counts freedom over the whole pattern, not where it sits: in a long chain of
cubics ending in one quintic, zero acceleration at the start turns the cubics into an initial
value problem whose solution grows from knot to knot. Such a pattern is solved as asked, but it
is better given free end accelerations or higher degrees at the ends.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.trajectory.piecewise import Trajectory, falling_factorial

PAPER_PATTERNS = ("3-3-3", "4-5-5", "5-5-5")
DENSE_UP_TO = 300       # unknowns a system may have for a dense LU (NumPy); scipy's banded above
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
    >>> tr.sample([0, 1, 5]).qd[:, 0].round(6) + 0.0      # rad/s; zero at both ends
    array([ 0.      , -0.078518,  0.      ])
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
    label = "-".join(str(d) for d in deg)
    system = _System(t, deg, continuity)
    A, b, keys = system.conditions(q, given)
    return Trajectory(t, system.to_time(system.solve(A, b, keys, label, given)), knots=t,
                      label=label)


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
    """The linear conditions on the coefficients of all segments, built segment-vectorised.

    Segment i is written in its own normalised time ``u = (t - t_i) / h_i`` in [0, 1], with
    coefficients ``a[off_i + k]`` of ``u**k``; a condition on derivative r at an end of the
    segment is ``d^r/du^r`` divided by ``h_i**r``. Rows are scaled to order one: a boundary row
    by ``h**r``, a continuity row by the shorter neighbour's ``h**r``.
    """

    def __init__(self, t: NDArray, deg: NDArray, continuity: int):
        self.h, self.deg, self.continuity = np.diff(t), deg, continuity
        self.off = np.r_[0, np.cumsum(deg + 1)]
        self.K = int(deg.max()) + 1
        top = max(self.K, continuity + 1)
        self.fall = np.array([[falling_factorial(k, r) for k in range(top)] for r in range(top)])

    def _ends(self, seg: NDArray, side: int, r: int, weight: NDArray):
        """One row per segment in seg: ``weight * h**r * d^r q/dt^r`` at u = side.

        Returns (row within the block, column, value) triplets.
        """
        k = np.arange(self.K)
        use = (k[None, :] <= self.deg[seg, None]) & ((k >= r) if side else (k == r))[None, :]
        rows, ks = np.nonzero(use)
        return rows, self.off[seg][rows] + ks, (self.fall[r, ks] * weight[rows])

    def conditions(self, q: NDArray, given: Mapping) -> tuple[tuple, NDArray, NDArray]:
        """The conditions A a = b: through the points, continuity, the given end values.

        Returns
        -------
        (rows, cols, vals) : the nonzero entries of A (R, U)
        b : ndarray, shape (R, n)
        keys : ndarray, shape (R,)
            Where each row sits in the segment order `solve` bands the system by: 3 i for
            continuity at knot i, 3 i + 1.5 for a row on segment i alone (its coefficients sit
            at 3 i + 1).
        """
        m, n = self.h.shape[0], q.shape[1]
        seg, inner = np.arange(m), np.arange(1, m)
        ones = np.ones(m)
        blocks = [(self._ends(seg, 0, 0, ones), q[:-1], 3.0 * seg + 1.5),
                  (self._ends(seg, 1, 0, ones), q[1:], 3.0 * seg + 1.5)]
        for r in range(1, self.continuity + 1):
            scale = np.minimum(self.h[:-1], self.h[1:]) ** r
            left = self._ends(inner - 1, 1, r, scale / self.h[:-1] ** r)
            right = self._ends(inner, 0, r, -scale / self.h[1:] ** r)
            merged = tuple(np.concatenate(pair) for pair in zip(left, right))
            blocks.append((merged, np.zeros((m - 1, n)), 3.0 * inner))
        for (side, r), value in given.items():
            if value is not None:
                i = np.array([0 if side == 0 else m - 1])
                blocks.append((self._ends(i, side, r, np.ones(1)),
                               (value * self.h[i] ** r)[None, :], 3.0 * i + 1.5))
        rows, cols, vals, rhs, keys, start = [], [], [], [], [], 0
        for (r, c, v), b, key in blocks:
            rows.append(r + start)
            cols.append(c)
            vals.append(v)
            rhs.append(b)
            keys.append(key)
            start += b.shape[0]
        entries = tuple(np.concatenate(x) for x in (rows, cols, vals))
        return entries, np.concatenate(rhs), np.concatenate(keys)

    def jerk_weights(self) -> tuple[NDArray, NDArray, NDArray]:
        """Entries (rows, cols, vals) of H with ``a^T H a = int sum q'''(t)^2 dt`` (block
        diagonal, scaled to a largest entry of one; the scale does not move the minimum).

        On segment i, ``int_0^h_i (q''')^2 dt = h_i**-5 int_0^1 (d^3 q/du^3)^2 du`` and
        ``int_0^1 u^(k-3) u^(l-3) du = 1 / (k + l - 5)``.
        """
        k = np.arange(self.K)
        f3 = np.array([falling_factorial(j, 3) for j in k])
        use = (k[None, :, None] >= 3) & (k[None, None, :] >= 3) & \
            (k[None, :, None] <= self.deg[:, None, None]) & \
            (k[None, None, :] <= self.deg[:, None, None])
        i, a, b = np.nonzero(use)
        vals = f3[a] * f3[b] / (a + b - 5) / self.h[i] ** 5
        return self.off[i] + a, self.off[i] + b, vals / max(1.0, vals.max(initial=0.0))

    def solve(self, A: tuple, b: NDArray, keys: NDArray, label: str,
              given: Mapping) -> NDArray:
        """Coefficients (U, n): the conditions, and least squared jerk for what they leave.

        With free coefficients, the KKT system ``[H A^T; A 0] [a; l] = [0; b]``; with none,
        ``A a = b`` (H plays no part, and its multipliers would only swamp the residual where
        short segments meet long ones). Unknowns and conditions ordered segment by segment make
        either banded (a condition touches one segment, or two at a knot), so a banded LU with
        partial pivoting solves it in time linear in the number of segments. A system of up
        to `DENSE_UP_TO` unknowns is solved dense (the same pivots: none can lie outside the
        band), which takes less than importing scipy.
        """
        rows, cols, vals = A
        U, R, n = int(self.off[-1]), b.shape[0], b.shape[1]
        if R > U:
            names = ("start velocity", "end velocity", "start acceleration", "end acceleration")
            ends = [name for key, name in zip(given, names) if given[key] is not None]
            raise InputError(
                f"degrees: pattern {label} has {U} coefficients per joint but {R} conditions "
                f"(through {len(self.h) + 1} points, derivatives 1..{self.continuity} continuous "
                f"at {len(self.h) - 1} knots, {', '.join(ends) or 'no end values'}); "
                "raise a degree or leave an end value free")
        segment = np.repeat(np.arange(len(self.deg)), self.deg + 1)
        power = np.arange(U) - self.off[segment]
        unknown_keys = 3.0 * segment + 1 + power / (2 * self.K)
        if R == U:                        # nothing left to choose: A a = b, banded the same way
            row_at, back = _place(keys), _place(unknown_keys)
            i, j, v = row_at[rows], back[cols], vals
            rhs = np.zeros((U, n))
            rhs[row_at] = b
        else:
            at = _place(np.r_[unknown_keys, keys])
            hr, hc, hv = self.jerk_weights()
            i, j = at[np.r_[hr, U + rows, cols]], at[np.r_[hc, cols, U + rows]]
            v = np.r_[hv, vals, vals]
            rhs = np.zeros((U + R, n))
            rhs[at[U:]] = b
            back = at[:U]
        try:
            x = _solve(i, j, v, rhs)[back]
        except np.linalg.LinAlgError:
            x = None
        if x is not None:
            residual = np.zeros((R, n))
            np.add.at(residual, rows, vals[:, None] * x[cols])
        # Backward error: a pattern can be badly conditioned (zero acceleration imposed at the
        # start of a chain of cubics grows like an unstable recurrence), so the residual is
        # weighed against |A| |x| as well as |b|.
        if x is None or not np.isfinite(x).all() or np.abs(residual - b).max() > \
                1e-9 * (1.0 + np.abs(b).max() + np.abs(vals).max() * np.abs(x).max()):
            raise InputError(f"degrees: pattern {label} cannot meet its conditions (they "
                             "contradict or leave the motion undetermined); change a degree "
                             "or an end value")
        return x

    def to_time(self, a: NDArray) -> NDArray:
        """Coefficients in powers of (t - t_i), zero padded: shape (m, max degree + 1, n)."""
        k = np.arange(self.K)
        use = k[None, :] <= self.deg[:, None]
        index = np.where(use, self.off[:-1, None] + k[None, :], 0)
        return np.where(use[..., None], a[index], 0.0) / self.h[:, None, None] ** k[:, None]


def _solve(i: NDArray, j: NDArray, v: NDArray, rhs: NDArray) -> NDArray:
    """x with M x = rhs (size, n), M the square matrix with the entries v at (i, j) (repeats
    add up); LinAlgError if it is exactly singular."""
    size = rhs.shape[0]
    if size <= DENSE_UP_TO:
        dense = np.zeros((size, size))
        np.add.at(dense, (i, j), v)
        return np.linalg.solve(dense, rhs)
    from scipy.linalg import solve_banded

    lower, upper = int(max(0, (i - j).max())), int(max(0, (j - i).max()))
    banded = np.zeros((lower + upper + 1, size))
    np.add.at(banded, (upper + i - j, j), v)
    return solve_banded((lower, upper), banded, rhs, check_finite=False)


def _place(keys: NDArray) -> NDArray:
    """Position of each item when the items are sorted by key (stable)."""
    at = np.empty(keys.shape[0], dtype=int)
    at[np.argsort(keys, kind="stable")] = np.arange(keys.shape[0])
    return at
