"""Retiming: the fastest motion along a joint path within velocity, acceleration and torque
limits.

Time-optimal path parametrisation by reachability analysis, TOPP-RA (H. Pham, Q.-C. Pham, "A
new approach to time-optimal path parameterization based on reachability analysis", IEEE T-RO
34(3), 2018), the algorithm of the toppra package, written here for joint limits and torques:

1. the path q(s) is cut into a grid s_0 < ... < s_N (uniform, plus the path's own breaks); the
   unknowns are x_i = (ds/dt)^2 at each grid point and a constant u_i = d2s/dt2 between;
2. a backward pass computes, for each grid point, the interval of x from which the end can
   still be reached at rest; each step is a two-variable linear programme, solved exactly by
   eliminating u;
3. a forward pass from rest takes the largest u that keeps x inside those intervals.

The motion starts and ends at rest: x = 0 at the ends, except where the path's own derivative
q'(s) is zero there (a spline with zero end velocities), where any x leaves the arm at rest and
the largest one is taken (toppra, given ``sd_start = 0``, keeps x = 0 and is slower there, by
an amount that shrinks only as 1 / grid).

Joint acceleration ``q' u + q'' x`` is held to its limits at both ends of every grid interval
(toppra's "interpolation" discretisation), joint velocity ``q' sqrt(x)`` at the grid points,
with a second-order allowance for the bound's sag between them. Between those points they can
still overshoot by a hair, so the result's peaks are found on every interval (8 samples, then
Newton steps) and, if needed, the motion is slowed uniformly by the factor that brings them
within (of the order of 1e-5 at the default grid).

Torque limits (``torque=``, an `armkit.dynamics.TorqueLimits`) add each joint's torque
``M q' u + (M q'' + C(q, q') q') x + g(q)`` (plus friction) as rows of the same form, held at
both ends of every grid interval. Between the grid points the torque is held by a bound, not
by sampling alone: on an interval it is smooth (without Coulomb friction), and rises beyond
its values at the two ends by at most its bulge over their mean at the interval's middle time
(the parabola through the three, up to a third-order term of 1e-9 of the limit on the default
grid); Coulomb friction steps by twice its value where a joint turns round inside an
interval. Where that rise could take the torque past its limit, the limit at the interval's
ends is lowered by a quarter more than the rise and the path solved again (one or two more
solves, on the tests' paths). Viscous friction, not linear in x, enters by its tangent at the
previous solve's speeds. The result keeps every torque within 1e-6 of its limit on 10,000
samples in time (tests/dynamics/test_retime_torque.py).

The motion is q(s(t)) with s(t) quadratic on each grid interval, so a cubic path gives an
exact piecewise polynomial of degree 6 in time. Jerk is not limited: the acceleration of a
time-optimal motion is bang-bang and steps at the switches; for jerk-limited motion between rest
states use `armkit.trajectory.jerk_limited`.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.trajectory import _kernels
from armkit.trajectory.piecewise import Trajectory, peak, shift
from armkit.trajectory.polynomial import limits
from armkit.trajectory.splines import spline

CHECKS_PER_INTERVAL = 8


@dataclass(frozen=True, eq=False)
class RetimeResult:
    """What `retime` found: the timed motion, or why the path cannot be followed.

    Attributes
    ----------
    success : bool
        True when the whole path is followed within the limits.
    trajectory : Trajectory or None
        The path in time from t = 0, label ``"retimed"`` (its ``knots`` are the times the
        path's knots are passed); None on failure.
    reason : str
        ``"ok"``; ``"exceeds the limits"`` (no speed along the path keeps the joint
        accelerations, or torques, within their limits there, as at a sharp corner followed
        at speed, or where the motors cannot hold the arm against gravity); ``"stops inside
        the path"`` (the only motion within the limits comes to rest at two neighbouring
        grid points: a corner); or ``"torque limits not met between grid points"`` (the
        lowered limits did not settle within `TORQUE_ROUNDS` solves).
    stop : float
        Path parameter s where it failed (the path's own time, or joint-space distance for
        waypoints); NaN on success.
    duration : float
        Of the trajectory (s); NaN on failure.
    """

    success: bool
    trajectory: Trajectory | None
    reason: str
    stop: float

    @property
    def duration(self) -> float:
        return self.trajectory.duration if self.trajectory is not None else float("nan")


def _failed(reason: str, stop: float) -> RetimeResult:
    return RetimeResult(False, None, reason, float(stop))


def waypoint_path(points: ArrayLike) -> Trajectory:
    """A smooth joint path through waypoints, parametrised by joint-space arc length.

    A natural cubic spline (zero second derivative at the ends) with knots at the cumulative
    Euclidean distances between waypoints, so that its "time" is a path parameter s (rad or m
    of joint-space distance), ready for `retime`.

    Parameters
    ----------
    points : array_like, shape (k, n)
        Waypoints, k >= 2, consecutive ones distinct.

    Returns
    -------
    Trajectory
        With s in place of time, label ``"path"``.
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[0] < 2:
        raise InputError(f"points: expected shape (k, n) with k >= 2 waypoints, found {p.shape}")
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    if not (np.diff(s) > 0).all():
        raise InputError("points: expected distinct consecutive waypoints, found a repeat")
    tr = spline(s, p, 3, start_velocity=None, end_velocity=None, start_acceleration=0.0,
                end_acceleration=0.0)
    return Trajectory(tr.breaks, tr.coefficients, tr.knots, "path")


class TorqueModel(Protocol):
    """What `retime` needs of a robot's dynamics to hold its torque limits
    (`armkit.dynamics.TorqueLimits` is one).

    Along a path q(s) followed at ds/dt = sd > 0 and d2s/dt2 = u, a joint's torque is
    ``a u + b sd^2 + c + d sd + f sign(q')``, each (k, n) from `terms` at k path points.
    """

    limits: NDArray
    """(n,) the torque limits (N m, N), finite where they apply (inf elsewhere)."""

    def terms(self, q: NDArray, dq: NDArray, ddq: NDArray) -> tuple[NDArray, ...]:
        """(a, b, c, d, f) at path points q (k, n) with q'(s) and q''(s): a = M q',
        b = M q'' + C(q, q') q', c = g(q), d = viscous q', f = coulomb (>= 0)."""

    def torques(self, q: NDArray, qd: NDArray, qdd: NDArray) -> NDArray:
        """The joint torques (k, n) of the motion (q, qd, qdd), each (k, n)."""


def retime(path: Trajectory | ArrayLike, vmax: ArrayLike, amax: ArrayLike, *,
           torque: TorqueModel | None = None, grid: int = 1000) -> RetimeResult:
    """The time-optimal motion along a path, from rest to rest, within joint limits.

    Parameters
    ----------
    path : Trajectory or array_like (k, n)
        The geometric path: a trajectory whose time is read as the path parameter, or
        waypoints (see `waypoint_path`).
    vmax : float or array_like (n,)
        Velocity limits (rad/s, m/s); inf where none.
    amax : float or array_like (n,)
        Acceleration limits (rad/s^2, m/s^2), finite.
    torque : TorqueModel, optional
        The robot's torque limits and dynamics (``armkit.dynamics.TorqueLimits(robot)``):
        the joint torques are held within them too, between the grid points as at them.
    grid : int
        Number of uniform grid intervals; the path's breaks are added to them.

    Returns
    -------
    RetimeResult
        ``success``, the timed ``trajectory`` (the same path from t = 0, label
        ``"retimed"``), and on failure the ``reason`` and where on the path (``stop``): a
        path the limits cannot follow is a result, not an exception.

    Raises
    ------
    InputError
        For bad limits, grid or waypoints.

    Example
    -------
    >>> import armkit
    >>> r = armkit.robot("inspection_6dof")
    >>> waypoints = np.deg2rad([[0, 0, 0, 0, 0, 0], [30, -20, 40, 0, 10, 0], [60, 0, 0, 0, 0, 0]])
    >>> timed = retime(waypoints, r.velocity_limits, r.acceleration_limits)
    >>> timed.success, timed.reason, round(timed.duration, 2)
    (True, 'ok', 1.89)
    """
    if not isinstance(path, Trajectory):
        path = waypoint_path(path)
    n = path.n
    V, A = limits("vmax", vmax, n), limits("amax", amax, n)
    if not np.isfinite(A).all():
        raise InputError(f"amax: expected finite acceleration limits, found {A.tolist()}")
    if not (isinstance(grid, (int, np.integer)) and grid >= 1):
        raise InputError(f"grid: expected a positive number of intervals, found {grid!r}")
    if torque is not None:
        tau_max = limits("torque.limits", torque.limits, n)
    s = _grid(path, int(grid))
    ds = np.diff(s)
    # The path at the grid points and halfway between (even and odd rows).
    geo = path.sample(np.r_[np.c_[s[:-1], s[:-1] + ds / 2].ravel(), s[-1]])
    # A q' at the level of rounding (a spline's end velocity solved to 1e-17, not 0) is a
    # path standing still: its velocity bound is none, not a finite one of 1e34.
    speed = np.abs(geo.qd)
    speed[speed <= 1e-12 * max(speed.max(), 1e-300)] = 0.0
    qd = np.where(speed == 0.0, 0.0, geo.qd)
    dq, ddq = np.ascontiguousarray(qd[::2]), np.ascontiguousarray(geo.qdd[::2])
    q = np.ascontiguousarray(geo.q[::2])
    with np.errstate(divide="ignore"):
        xv = np.min((V / speed) ** 2, axis=1)                # inf where q' = 0
    # x is linear in s between grid points while the bound V^2 / q'^2 bends: where it sags
    # below its chord, x could cross it mid-interval. Lowering both ends by the sag at the
    # midpoint keeps the line under a quadratic bound; the cost is second order in the step.
    # Where the sag is deeper than the bound itself (a coarse grid), the least of the point's
    # and its midpoints' bounds serves instead.
    ends, mid = xv[::2], xv[1::2]
    with np.errstate(invalid="ignore"):
        sag = np.where(np.isfinite(ends[:-1] + ends[1:] + mid),
                       np.maximum((ends[:-1] + ends[1:]) / 2 - mid, 0.0), 0.0)
    nearest = np.minimum.reduce([ends, np.r_[np.inf, mid], np.r_[mid, np.inf]])
    xv = np.maximum(ends - np.maximum(np.r_[0.0, sag], np.r_[sag, 0.0]), nearest)
    # Rest means q' ds/dt = 0: where the path itself stands still (q'(s) = 0, as at the ends of
    # a spline with zero end velocities) ds/dt need not be zero, and the fastest motion leaves
    # and arrives with ds/dt > 0 (near such an end q ~ q'' s^2 / 2, so a constant acceleration
    # needs s ~ t). Fixing ds/dt = 0 there instead costs a time that shrinks only as 1 / grid.
    still = ~dq[[0, -1]].any(axis=1)
    # Channels: each joint's acceleration q' u + q'' x within amax, then (with torque limits)
    # its torque a u + b x + c + d sd within the torque limit.
    a, b = dq, ddq
    c, bound = np.zeros_like(dq), np.broadcast_to(A, dq.shape)
    if torque is not None:
        terms = [np.asarray(x, dtype=float) for x in torque.terms(q, dq, ddq)]
        held = np.isfinite(tau_max)
        ta, tb, tc, td, tf = (x[:, held] for x in terms)
        tc = tc + tf * np.sign(dq[:, held])     # Coulomb friction opposes the motion
        tau_bound = np.broadcast_to(tau_max[held], ta.shape).copy()
        a = np.hstack([dq, ta])
    sd_before = np.zeros(s.shape[0])
    for _ in range(TORQUE_ROUNDS):
        if torque is not None:
            # Viscous friction d sd is not linear in x = sd^2: it enters as its tangent at the
            # previous round's speed sd0, d (x + sd0^2) / (2 sd0), exact there (none in the
            # first round, nor where the path was at rest); the check below holds the exact
            # torque, and each round's speeds come closer to the last (Newton's steps).
            with np.errstate(divide="ignore"):
                slope = np.where(sd_before > 0, 0.5 / sd_before, 0.0)[:, None]
            b = np.hstack([ddq, tb + td * slope])
            c = np.hstack([np.zeros_like(dq), tc + td * (0.5 * sd_before)[:, None]])
            bound = np.hstack([np.broadcast_to(A, dq.shape), tau_bound])
        channels = [np.ascontiguousarray(x) for x in (a, b, c, bound)]
        end_top = _end_top(*(x[-1] for x in channels), xv[-1]) if still[1] else 0.0
        if end_top < 0:
            return _failed("exceeds the limits", s[-1])
        x = np.empty(s.shape[0])
        stuck = _kernels.topp.light(*channels, xv, ds, end_top, bool(still[0]), x)
        if stuck >= 0:
            return _failed("exceeds the limits", s[stuck])
        sd = np.sqrt(np.maximum(x, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            dt = 2 * ds / (sd[:-1] + sd[1:])
        if not np.isfinite(dt).all():
            return _failed("stops inside the path", s[np.flatnonzero(~np.isfinite(dt))[0]])
        u = (x[1:] - x[:-1]) / (2 * ds)

        def timed():
            t = np.r_[0.0, np.cumsum(dt)]
            return Trajectory(t, _compose(path, s, sd[:-1], u),
                              knots=np.interp(path.knots, s, t), label="retimed")

        if torque is None:
            tr = timed()
            return RetimeResult(True, tr.scaled(_overshoot(tr, V, A)), "ok", float("nan"))

        def overshoot(factor):
            return _torque_excess(torque, held, tau_max[held], path, s, sd / factor,
                                  u / factor ** 2, dt * factor, (ta, tb, tc, td, tf),
                                  np.sign(dq[:, held]))

        # The velocity and acceleration check (a uniform slow-down, by 1e-5 or so) and the
        # motion itself only once the torques are within their limits.
        excess, rise = overshoot(1.0)
        if not (excess > 0).any():
            tr = timed()
            factor = _overshoot(tr, V, A)
            if factor > 1.0:
                excess, rise = overshoot(factor)
            if (excess <= 0).all():
                return RetimeResult(True, tr.scaled(factor), "ok", float("nan"))
        # Where the torque comes within its rise between grid points of the limit, the
        # interval's ends get the limit less a quarter more than that rise (the next round's
        # speeds differ a little). An overshoot at the grid points themselves comes from the
        # friction's tangent, which the next round takes at this round's speeds.
        cap = np.where(excess > -rise, tau_max[held] - 1.25 * rise, np.inf)
        tau_bound[:-1] = np.minimum(tau_bound[:-1], cap)
        tau_bound[1:] = np.minimum(tau_bound[1:], cap)
        if not (tau_bound > 0).all():
            break
        sd_before = sd
    return _failed("torque limits not met between grid points", s[0])


TORQUE_ROUNDS = 12
"""Solves of a torque-limited retiming at most: each lowers the limits where the torque
overshoots between grid points (one or two suffice on the paths of the tests)."""


def _end_top(a, b, c, bound, xv_end) -> float:
    """The largest x at a still end (a = 0 there) with every channel's |b x + c| <= bound;
    -1 if none, not even rest (a torque beyond its limit just to hold the arm there)."""
    lo, hi = _kernels.narrow_all(0.0, xv_end, np.r_[b, -b][None],
                                 np.r_[bound - c, bound + c][None], 1)
    return float(hi[0]) if lo[0] <= hi[0] else -1.0


def _torque_excess(torque: TorqueModel, held: NDArray, tau_max: NDArray, path: Trajectory,
                   s: NDArray, sd: NDArray, u: NDArray, dt: NDArray, terms, sign: NDArray
                   ) -> tuple[NDArray, NDArray]:
    """How far (N m, N) each grid interval's torque goes beyond its limit (negative: how far
    it stays within), and how far it can rise beyond its values at the interval's ends, each
    (N, held joints).

    Without Coulomb friction the torque is smooth on an interval (s(t) quadratic, the path
    one polynomial there), and the interpolation constraints hold it at both ends; between
    them it is bounded by the parabola through its values at the ends and at the interval's
    middle time: ``max(f0, f1) + max(0, f_mid - (f0 + f1) / 2)`` from above, likewise from
    below (a third-order term in the interval's duration is left out: 1e-9 of the limit on the
    default grid). The middle time's torque is computed in full (`torque.torques`), its
    friction taken out. Coulomb friction (`sign` is q''s sign at the grid points) is
    added back with the sign it has at each end, and where the joint turns round inside the
    interval, with either sign (it steps there).
    """
    ta, tb, tc, td, tf = terms
    x = sd ** 2
    f0 = ta[:-1] * u[:, None] + tb[:-1] * x[:-1, None] + tc[:-1] + td[:-1] * sd[:-1, None]
    f1 = ta[1:] * u[:, None] + tb[1:] * x[1:, None] + tc[1:] + td[1:] * sd[1:, None]
    half = dt / 2
    middle = path.sample(s[:-1] + sd[:-1] * half + u * half ** 2 / 2)
    rate = (sd[:-1] + sd[1:]) / 2
    fm = torque.torques(middle.q, middle.qd * rate[:, None],
                        middle.qd * u[:, None] + middle.qdd * rate[:, None] ** 2)[:, held]
    coulomb = (tf[:-1] + tf[1:]) / 2
    fm = fm - coulomb * np.sign(middle.qd[:, held])
    # The smooth part: the ends without their Coulomb term.
    g0, g1 = f0 - tf[:-1] * sign[:-1], f1 - tf[1:] * sign[1:]
    bulge = fm - (g0 + g1) / 2
    turns = (sign[:-1] != sign[1:]) | (sign[:-1] == 0)
    same = tf[:-1] * sign[:-1]                  # the friction of an interval with no turn
    top = np.maximum(np.maximum(f0, f1), np.maximum(g0, g1) + np.maximum(bulge, 0.0)
                     + np.where(turns, coulomb, same))
    bottom = np.minimum(np.minimum(f0, f1), np.minimum(g0, g1) + np.minimum(bulge, 0.0)
                        + np.where(turns, -coulomb, same))
    excess = np.maximum(top - tau_max, -tau_max - bottom)
    return excess, np.abs(bulge) + np.where(turns, 2.0 * coulomb, 0.0)


def _grid(path: Trajectory, count: int) -> NDArray:
    """Uniform grid over the path plus its breaks, duplicates (closer than 1e-9 of a step) out."""
    s = np.union1d(np.linspace(path.start, path.end, count + 1), path.breaks)
    keep = np.r_[True, np.diff(s) > 1e-9 * path.duration / count]
    s = s[keep]
    s[-1] = path.end
    return s


def _compose(path: Trajectory, s: NDArray, sd: NDArray, u: NDArray) -> NDArray:
    """Coefficients of q(s(tau)) per grid interval, s(tau) = s_i + sd_i tau + u_i tau^2 / 2.

    With the path's piece re-expanded about s_i as sum_k c_k d^k, d = tau (sd + u tau / 2):
    d^k = sum_l C(k, l) sd^(k - l) (u/2)^l tau^(k + l).
    """
    piece = np.clip(np.searchsorted(path.breaks, s[:-1], side="right") - 1, 0,
                    path.breaks.shape[0] - 2)
    c = shift(path.coefficients[piece], s[:-1] - path.breaks[piece])       # (N, K, n)
    K = c.shape[1]
    out = np.zeros((c.shape[0], 2 * K - 1, c.shape[2]))
    half = u / 2
    for k in range(K):
        for l in range(k + 1):
            w = comb(k, l) * sd ** (k - l) * half ** l
            out[:, k + l] += c[:, k] * w[:, None]
    return out


def _overshoot(tr: Trajectory, V: NDArray, A: NDArray) -> float:
    """The uniform slow-down (>= 1) that brings the peak velocity and acceleration of every
    piece (`armkit.trajectory.piecewise.peak`) within the limits."""
    rv = np.max(peak(tr, 1, CHECKS_PER_INTERVAL) / V)
    ra = np.max(peak(tr, 2, CHECKS_PER_INTERVAL) / A)
    return float(max(1.0, rv, np.sqrt(ra)))
