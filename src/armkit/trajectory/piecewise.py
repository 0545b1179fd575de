"""The joint trajectory every builder returns: one polynomial per time interval, all joints.

Point-to-point polynomials, splines through via points, trapezoidal and jerk-limited profiles
and retimed paths all come out as a `Trajectory`: breaks ``t_0 < ... < t_m`` shared by the
joints and, on ``[t_i, t_{i+1}]``, ``q_j(t) = sum_k c[i, k, j] (t - t_i)**k``. Sampling it gives
`Samples` (t, q, qd, qdd, qddd), the form the metrics, the tool motion and the figures read, so
that a trajectory known only by its samples (a Cartesian line through IK) fits in the same place.
"""

from __future__ import annotations

import math
from dataclasses import InitVar, dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model.chain import frozen_array
from armkit.trajectory import _kernels

DERIVATIVES = ("position", "velocity", "acceleration", "jerk")


@dataclass(frozen=True)
class Samples:
    """A joint trajectory at sample times; SI (rad or m per joint, seconds).

    Attributes
    ----------
    t : ndarray, shape (...)
    q, qd, qdd, qddd : ndarray, shape (..., n)
        Position, velocity, acceleration and jerk of every joint at t.
    """

    t: NDArray
    q: NDArray
    qd: NDArray
    qdd: NDArray
    qddd: NDArray

    def derivative(self, order: int) -> NDArray:
        """q (0), qd (1), qdd (2) or qddd (3)."""
        return (self.q, self.qd, self.qdd, self.qddd)[order]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A joint trajectory as a piecewise polynomial in time, SI.

    Parameters
    ----------
    breaks : array_like, shape (m + 1,)
        Strictly increasing times (s) where the pieces meet; ``breaks[0]`` is the start.
    coefficients : array_like, shape (m, K, n)
        On piece i, ``q_j(t) = sum_k coefficients[i, k, j] * (t - breaks[i])**k``; lowest power
        first; rad (revolute) or m (prismatic) per joint.
    knots : array_like, shape (k,), optional
        The times the motion was asked to pass through (via points; start and end for a
        point-to-point motion). Defaults to the start and the end.
    label : str
        What built it: ``"quintic"``, ``"4-5-5"``, ``"jerk-limited"``, ...
    check : bool
        False skips the checks of the values (finite, breaks increasing; the shapes are always
        checked), as scipy's ``check_finite=False``: for arrays right by construction, as a
        builder's kernel makes them from inputs it has checked.

    Raises
    ------
    InputError
        If the shapes disagree, the breaks do not increase or a value is not finite.
    """

    breaks: NDArray
    coefficients: NDArray
    knots: NDArray = None
    label: str = ""
    check: InitVar[bool] = True

    def __post_init__(self, check: bool):
        breaks, coefficients = _frozen(self.breaks), _frozen(self.coefficients)
        if breaks.ndim != 1 or breaks.shape[0] < 2:
            raise InputError(f"breaks: expected shape (m + 1,) with m >= 1, found {breaks.shape}")
        if coefficients.ndim != 3 or coefficients.shape[0] != breaks.shape[0] - 1:
            raise InputError(f"coefficients: expected shape ({breaks.shape[0] - 1}, K, n), "
                             f"found {coefficients.shape}")
        m = breaks.shape[0] - 1
        if check:
            _check_values(breaks, coefficients)
        knots = breaks[::m] if self.knots is None else frozen_array(self.knots)
        object.__setattr__(self, "breaks", breaks)
        object.__setattr__(self, "coefficients", coefficients)
        object.__setattr__(self, "knots", knots)

    @cached_property
    def _table(self) -> NDArray:
        """Per derivative r, the coefficients of d^r q / dt^r: the evaluation kernel's table,
        built at the first evaluation (building a trajectory need not pay for it)."""
        return _derivative_table(self.coefficients, len(DERIVATIVES))

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.coefficients.shape[2]

    @property
    def start(self) -> float:
        return float(self.breaks[0])

    @property
    def end(self) -> float:
        return float(self.breaks[-1])

    @property
    def duration(self) -> float:
        """End minus start time (s)."""
        return self.end - self.start

    @property
    def degree(self) -> int:
        """Highest power stored (some pieces may use fewer)."""
        return self.coefficients.shape[1] - 1

    def evaluate(self, t: ArrayLike, derivative: int = 0) -> NDArray:
        """Derivative ``derivative`` (0 position ... 3 jerk) of every joint at times t.

        Parameters
        ----------
        t : array_like, shape (...)
            Times (s) within [start, end].
        derivative : {0, 1, 2, 3}

        Returns
        -------
        ndarray, shape (..., n)
            rad, rad/s, rad/s^2, rad/s^3 for revolute joints (m... for prismatic ones).
        """
        if derivative not in range(len(DERIVATIVES)):
            raise InputError(f"derivative: expected 0, 1, 2 or 3, found {derivative!r}")
        t, flat = self._times(t)
        out = np.empty((1, flat.shape[0], self.n))
        _kernels.run_evaluate(self.breaks, np.ascontiguousarray(self._table[:, derivative:
                                                                            derivative + 1]),
                              flat, out)
        return out[0].reshape(t.shape + (self.n,))

    def sample(self, t: ArrayLike) -> Samples:
        """Position, velocity, acceleration and jerk of every joint at times t, one pass.

        Parameters
        ----------
        t : array_like, shape (...)
            Times (s) within [start, end]; any order (sorted times run fastest).

        Returns
        -------
        Samples
            ``q, qd, qdd, qddd`` of shape (..., n).

        Raises
        ------
        InputError
            If a time lies outside [start, end] or is not finite.
        """
        t, flat = self._times(t)
        out = np.empty((len(DERIVATIVES), flat.shape[0], self.n))
        _kernels.run_evaluate(self.breaks, self._table, flat, out)
        shape = t.shape + (self.n,)
        return Samples(t, *(out[r].reshape(shape) for r in range(len(DERIVATIVES))))

    def sample_uniform(self, count: int = 500) -> Samples:
        """`sample` at `count` evenly spaced times from start to end."""
        return self.sample(np.linspace(self.start, self.end, count))

    def _times(self, t: ArrayLike) -> tuple[NDArray, NDArray]:
        try:
            t = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"t: expected times (s), found {type(t).__name__}") from None
        flat = np.ascontiguousarray(t.reshape(-1))
        if flat.size:
            lo, hi = flat.min(), flat.max()
            # Rounding in a caller's own time grid may step a hair past the end.
            slack = 1e-12 * max(1.0, abs(self.start), abs(self.end))
            if not (lo >= self.start - slack and hi <= self.end + slack):
                bad = lo if not lo >= self.start - slack else hi
                raise InputError(f"t: expected times within [{self.start:g}, {self.end:g}] s, "
                                 f"found {bad:g}")
        return t, flat

    def scaled(self, factor: float) -> Trajectory:
        """The same path run `factor` times slower (factor > 1) about the start time."""
        k = np.arange(self.coefficients.shape[1])
        breaks = self.start + (self.breaks - self.start) * factor
        return Trajectory(breaks, self.coefficients / factor ** k[:, None],
                          self.start + (self.knots - self.start) * factor, self.label)

    def piece_values(self, tau: ArrayLike, derivative: int = 0) -> NDArray:
        """Derivative of every joint at local times tau into every piece.

        Parameters
        ----------
        tau : array_like, shape (m, S)
            Time (s) since the start of each piece; ``tau = breaks[i+1] - breaks[i]`` gives the
            value at the end of piece i from its own side (the left limit at the next break).

        Returns
        -------
        ndarray, shape (m, S, n)
        """
        return piece_values(self.coefficients, np.asarray(tau, dtype=float), derivative)


def _check_values(breaks: NDArray, coefficients: NDArray) -> None:
    """Raise unless every value is finite and the breaks increase strictly (a motion of zero
    duration, breaks [t, t] and one piece, is the exception: see `at_rest`)."""
    # A finite sum has no NaN or inf in it (the cheap test for a few pieces); a sum that is
    # not finite may still be an overflow of finite values, so look again.
    if not (math.isfinite(breaks.sum()) and math.isfinite(coefficients.sum())) and not (
            np.isfinite(breaks).all() and np.isfinite(coefficients).all()):
        raise InputError("trajectory: expected finite breaks and coefficients, found NaN or inf")
    resting = breaks.shape[0] == 2 and breaks[0] == breaks[1]
    if not ((breaks[1:] > breaks[:-1]).all() or resting):
        raise InputError("breaks: expected strictly increasing times, found "
                         f"{np.array2string(breaks, threshold=8)}")


def _frozen(a: ArrayLike) -> NDArray:
    """`frozen_array`, without its copy for a float array that is read-only and is no view of
    another array or buffer (a builder's fresh kernel output, frozen by the builder: nothing
    else can write to it)."""
    if (type(a) is np.ndarray and a.dtype == np.float64 and not a.flags.writeable
            and not isinstance(a.base, (np.ndarray, memoryview, bytes, bytearray))):
        return a
    return frozen_array(a)


def at_rest(q: ArrayLike, label: str = "") -> Trajectory:
    """The motion of zero duration that stays at q (n,): what a point-to-point builder returns
    for a goal equal to its start. Its breaks are ``[0, 0]``; it samples at t = 0 only."""
    q = np.asarray(q, dtype=float)
    return Trajectory([0.0, 0.0], q.reshape(1, 1, -1), label=label)


def _derivative_table(c: NDArray, count: int) -> NDArray:
    """table[i, r, k, j]: coefficient k of the r-th derivative (zero padded), (m, count, K, n).

    Coefficient k of the r-th derivative is ``c[k + r] (k + r)! / k!``: one gather and one
    product for every r and k at once.
    """
    K = c.shape[1]
    r = np.arange(count)[:, None]
    source = np.arange(K) + r                               # (count, K): k + r
    factor = np.ones((count, K))
    for i in range(1, count):                               # (k + r) (k + r - 1) ... (k + 1)
        factor[i:] *= source[i:] - i + 1
    factor[source >= K] = 0.0
    return c[:, np.minimum(source, K - 1), :] * factor[None, :, :, None]


def falling_factorial(k: int, r: int) -> float:
    """k (k - 1) ... (k - r + 1): the factor d^r/dx^r brings to x^k."""
    out = 1.0
    for i in range(r):
        out *= k - i
    return out


def piece_values(c: NDArray, tau: NDArray, derivative: int = 0) -> NDArray:
    """Derivative of polynomials c (m, K, n) at local times tau (m, S): shape (m, S, n)."""
    K = c.shape[1]
    out = np.zeros(tau.shape + (c.shape[2],))
    for k in range(K - 1, derivative - 1, -1):        # Horner, highest power first
        out = out * tau[..., None] + (c[:, k] * falling_factorial(k, derivative))[:, None, :]
    return out


def peak(tr: Trajectory, derivative: int, per_piece: int = 16, steps: int = 4) -> NDArray:
    """Largest |d^r q / dt^r| of every joint over the whole trajectory, (n,).

    Each piece is sampled at `per_piece` times (both ends included, so steps at breaks count);
    the best sample of each piece and joint is then polished by Newton steps on the next
    derivative (kept between its neighbouring samples), which finds an interior extremum to
    rounding where sampling alone would miss it by the square of the spacing.
    """
    c = tr.coefficients
    h = np.diff(tr.breaks)
    tau = h[:, None] * np.linspace(0.0, 1.0, per_piece)                 # (m, S)
    values = np.abs(piece_values(c, tau, derivative))                   # (m, S, n)
    best = np.argmax(values, axis=1)                                    # (m, n)
    rows = np.arange(len(h))[:, None]
    x = tau[rows, best]
    lo = tau[rows, np.maximum(best - 1, 0)]
    hi = tau[rows, np.minimum(best + 1, per_piece - 1)]
    for _ in range(steps):
        slope, bend = _at(c, x, derivative + 1), _at(c, x, derivative + 2)
        step = np.divide(slope, bend, out=np.zeros_like(x), where=bend != 0)
        x = np.clip(x - step, lo, hi)
    polished = np.abs(_at(c, x, derivative))
    return np.maximum(values.max(axis=(0, 1)), polished.max(axis=0))


def _at(c: NDArray, tau: NDArray, derivative: int) -> NDArray:
    """Derivative of polynomials c (m, K, n) at one local time per piece and joint, (m, n)."""
    out = np.zeros(tau.shape)
    for k in range(c.shape[1] - 1, derivative - 1, -1):
        out = out * tau + c[:, k] * falling_factorial(k, derivative)
    return out


def shift(c: NDArray, delta: ArrayLike) -> NDArray:
    """Re-expand polynomials about a point delta further on (Taylor shift).

    Parameters
    ----------
    c : ndarray, shape (..., K, n)
        Coefficients in powers of x, lowest first.
    delta : array_like, shape (...)

    Returns
    -------
    ndarray, shape (..., K, n)
        Coefficients in powers of (x - delta).
    """
    c = np.array(c, dtype=float)
    d = np.asarray(delta, dtype=float)[..., None]
    K = c.shape[-2]
    for k in range(K - 1):                      # repeated synthetic division by (x - delta)
        for i in range(K - 2, k - 1, -1):
            c[..., i, :] += d * c[..., i + 1, :]
    return c


def merge(times: NDArray, coefficients: NDArray, tol: float = 1e-12) -> tuple[NDArray, NDArray]:
    """One set of breaks for joints that each have their own (time-synchronised profiles).

    Parameters
    ----------
    times : ndarray, shape (n, P + 1)
        Each joint's breaks, all from the same start to the same end; pieces of zero length
        allowed.
    coefficients : ndarray, shape (n, P, K)
        Each joint's pieces, in powers of the time since the piece's start.
    tol : float
        Breaks closer than ``tol * duration`` count as one.

    Returns
    -------
    breaks : ndarray, shape (m + 1,)
    coefficients : ndarray, shape (m, K, n)
        Every joint re-expanded about the start of each merged piece.
    """
    start, end = times[0, 0], times[0, -1]
    eps = tol * (end - start)
    inner = np.sort(times[:, 1:-1].ravel())
    inner = inner[(inner > start + eps) & (inner < end - eps)]
    inner = inner[np.r_[True, np.diff(inner) > eps]] if inner.size else inner
    breaks = np.r_[start, inner, end]
    # Piece of joint j holding each merged piece's start: the last with times[j, p] <= start.
    i = np.sum(times[:, None, 1:-1] <= breaks[None, :-1, None] + eps, axis=-1)     # (n, m)
    n = times.shape[0]
    c = coefficients[np.arange(n)[:, None], i]                                      # (n, m, K)
    delta = breaks[None, :-1] - times[np.arange(n)[:, None], i]                     # (n, m)
    shifted = shift(c.transpose(1, 0, 2)[..., None], delta.T)[..., 0]               # (m, n, K)
    return breaks, np.ascontiguousarray(shifted.transpose(0, 2, 1))

