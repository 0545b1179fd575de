"""Jerk-limited retiming: a fast motion along a joint path within velocity, acceleration and
jerk limits, from rest to rest, with acceleration continuous everywhere.

A time-optimal retiming within velocity and acceleration limits (`armkit.trajectory.retime`)
is bang-bang: its acceleration steps between the limits, so its jerk is unbounded. Here the
path speed is planned on a grid s_0 < ... < s_N of the path parameter, with x_i = (ds/dt)^2 and
u_i = d2s/dt2 at each grid point (u continuous, unlike TOPP-RA's u constant between points):

- ``x_{i+1} - x_i = (u_i + u_{i+1}) (s_{i+1} - s_i)`` (d x / ds = 2 u, trapezoidal);
- joint velocity ``q' sqrt(x)`` and joint acceleration ``q' u + q'' x`` within their limits at
  every grid point;
- joint jerk ``sqrt(x) (q' du/ds + 3 q'' u + q''' x)`` within its limits in the middle of
  every interval, with sqrt(x) taken from the previous plan (the first from the acceleration
  limits alone): a linear programme in (x, u), solved a few times (sequential linear
  programming, as in the jerk-limited extensions of TOPP: H. Pham, Q.-C. Pham, IEEE T-RO 34(3),
  2018, section VI; K. Hauser, "Fast interpolation and time-optimization with contact", IJRR
  2014), each maximising the sum of x (the speed) over the path;
- rest at both ends with zero acceleration (x = u = 0), so that the motion starts and stops
  without an acceleration step.

The plan becomes a motion as s(t): a quintic in time on each interval matching s, ds/dt and
d2s/dt2 at both ends (so acceleration is continuous), composed with the path's pieces into an
exact piecewise polynomial q(t) (of degree 15 for a cubic path).

How the limits hold between samples: on every piece of the result, joint velocity, acceleration
and jerk are polynomials in time; their largest magnitude on the piece is found exactly, at the
piece's ends and at the real roots of the next derivative inside it (the eigenvalues of a
companion matrix per piece and joint), and the motion is then slowed uniformly by the least
factor that brings every one within its limit (velocity scales as 1/k, acceleration 1/k^2,
jerk 1/k^3). The limits therefore hold at every instant, not only at grid points, up to
rounding (a relative 1e-9 is kept in hand for it).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from armkit.errors import InputError
from armkit.trajectory.bounds import peaks
from armkit.trajectory.piecewise import Trajectory, shift
from armkit.trajectory.polynomial import limits
from armkit.trajectory.retiming import RetimeResult, waypoint_path

ROUNDS = 12           # linear programmes at most, after the one without jerk limits
GROWTH = 1.1          # how much faster than the last plan the next may be, anywhere
FLOOR = 0.02          # of the fastest speed: the least bound on ds/dt anywhere
SMOOTHING = 5.0       # cost of u's total variation, per fastest |u|, against x's (below)
SETTLED = 0.002       # rounds stop when the motion gets shorter by less than this fraction
MARGIN = 1e-9         # relative, kept in hand against rounding in the final check
END = 1.5             # x_1 = END u_1 ds on a first interval at constant jerk from rest
GAUSS = np.polynomial.legendre.leggauss(16)


def retime_jerk(path: Trajectory | ArrayLike, vmax: ArrayLike, amax: ArrayLike,
                jmax: ArrayLike, *, grid: int = 400) -> RetimeResult:
    """A fast motion along a path, rest to rest, within joint velocity, acceleration and jerk
    limits, its acceleration continuous (no steps, no chatter).

    Parameters
    ----------
    path : Trajectory or array_like (k, n)
        The geometric path: a trajectory whose time is read as the path parameter (a cubic
        spline through waypoints, as `waypoint_path` makes), or waypoints.
    vmax, amax, jmax : float or array_like (n,)
        Velocity (rad/s, m/s), acceleration (/s^2) and jerk (/s^3) limits, positive; the
        acceleration and jerk limits finite.
    grid : int
        Number of uniform grid intervals; the path's breaks are added to them.

    Returns
    -------
    RetimeResult
        ``success``; the ``trajectory`` (label ``"jerk-limited"``, from t = 0, its knots the
        times the path's knots are passed); on failure the ``reason`` and where (``stop``).
        Between samples the limits hold as the module's docstring says.

    Raises
    ------
    InputError
        For bad limits, grid or path.

    Example
    -------
    >>> import armkit
    >>> r = armkit.robot("inspection_6dof")
    >>> waypoints = np.deg2rad([[0, 0, 0, 0, 0, 0], [30, -20, 40, 0, 10, 0], [60, 0, 0, 0, 0, 0]])
    >>> smooth = retime_jerk(waypoints, r.velocity_limits, r.acceleration_limits, r.jerk_limits)
    >>> smooth.success, smooth.reason
    (True, 'ok')
    """
    if not isinstance(path, Trajectory):
        path = waypoint_path(path)
    n = path.n
    V, A, J = (limits(name, x, n) for name, x in (("vmax", vmax), ("amax", amax),
                                                   ("jmax", jmax)))
    if not (np.isfinite(A).all() and np.isfinite(J).all()):
        raise InputError(f"amax, jmax: expected finite limits, found {A.tolist()} and "
                         f"{J.tolist()}")
    if not (isinstance(grid, (int, np.integer)) and 2 <= grid <= 100_000):
        raise InputError(f"grid: expected 2 to 100000 intervals, found {grid!r}")
    s = _grid(path, int(grid))
    plan = _Plan(path, s, V, A, J)
    fastest = plan.fastest()
    if fastest is None:
        return RetimeResult(False, None, "exceeds the limits", float(path.start))
    plan.cost = plan.cost / max(fastest[0].max(), 1e-300)     # x per the fastest plan's
    # Sequential linear programmes: each plan's speed bounds the next (times GROWTH), so each
    # is within the jerk limits at its rows; the first is bounded by the fastest plan.
    best, reference, growth = None, np.sqrt(np.maximum(fastest[0], 0.0)), 1.0
    for _ in range(ROUNDS):
        found = plan.solve(reference, growth)
        if found is None:
            break
        duration = float(_durations(s, *found).sum())
        if best is not None and duration > best[0] * (1 - SETTLED):
            break
        best, reference, growth = (duration, *found), np.sqrt(np.maximum(found[0], 0.0)), GROWTH
    if best is None or not np.isfinite(best[0]):
        return RetimeResult(False, None, "stops inside the path", float(path.start))
    # Last, the same speed bound once more with a cost on the acceleration's total variation:
    # among plans about as fast, the one whose acceleration does not alternate between grid
    # points (a linear programme leaves that free where a velocity bound holds the speed).
    smooth = plan.solve(np.sqrt(np.maximum(best[1], 0.0)), 1.0,
                        smoothing=SMOOTHING / max(np.abs(fastest[1]).max(), 1e-300))
    if smooth is not None and np.isfinite(_durations(s, *smooth).sum()):
        best = (0.0, *smooth)
    _, x, u = best
    sd = np.sqrt(np.maximum(x, 0.0))
    dt = _durations(s, x, u)
    t = np.r_[0.0, np.cumsum(dt)]
    tr = Trajectory(t, _compose(path, s, sd, u, dt), knots=np.interp(path.knots, s, t),
                    label="jerk-limited")
    factor = _slow_down(tr, V, A, J)
    return RetimeResult(True, tr.scaled(factor) if factor > 1 else tr, "ok", float("nan"))


def _grid(path: Trajectory, count: int) -> NDArray:
    """A uniform grid over the path with its breaks added (closer than 1e-6 of a step: one)."""
    s = np.union1d(np.linspace(path.start, path.end, count + 1), path.breaks)
    keep = np.r_[True, np.diff(s) > 1e-6 * path.duration / count]
    s = s[keep]
    s[-1] = path.end
    return s


class _Plan:
    """The linear programme in z = (x_0..x_N, u_0..u_N) over one grid, built once; `solve`
    fills in the jerk rows for a reference speed."""

    def __init__(self, path: Trajectory, s: NDArray, V: NDArray, A: NDArray, J: NDArray):
        N, n = s.shape[0] - 1, path.n
        ds = np.diff(s)
        at = path.sample(s)
        self.N, self.n, self.J = N, n, J
        with np.errstate(divide="ignore"):
            xv = np.min((V / np.abs(at.qd)) ** 2, axis=1)
        i = np.arange(N)
        # Acceleration at the grid points: -A <= q' u + q'' x <= A.
        rows = np.arange((N + 1) * n)
        node = np.tile(np.arange(N + 1), n)
        acc = sparse.csr_matrix((np.r_[at.qdd.T.ravel(), at.qd.T.ravel()],
                                 (np.r_[rows, rows], np.r_[node, N + 1 + node])),
                                shape=((N + 1) * n, 2 * (N + 1)))
        self.acc = sparse.vstack([acc, -acc]).tocsr()
        self.acc_bound = np.tile(np.repeat(A, N + 1), 2)
        # Jerk sqrt(x) (q' du/ds + 3 q'' u + q''' x) in the middle of each interval; on the
        # first and last, at constant jerk from and to rest, at their inner end, where
        # du/ds = +-u / (3 ds). Weights of (x_i, x_{i+1}, u_i, u_{i+1}) per interval.
        self.ends = N > 2
        where = s[:-1] + ds / 2
        if self.ends:
            where[0], where[-1] = s[1], s[-2]
        g = path.sample(where)
        w = np.empty((N, 4, n))
        w[:, 0] = w[:, 1] = g.qddd / 2
        w[:, 2] = -g.qd / ds[:, None] + 1.5 * g.qdd
        w[:, 3] = g.qd / ds[:, None] + 1.5 * g.qdd
        if self.ends:
            w[0] = [0 * g.qd[0], g.qddd[0], 0 * g.qd[0], g.qd[0] / (3 * ds[0]) + 3 * g.qdd[0]]
            w[-1] = [g.qddd[-1], 0 * g.qd[-1], -g.qd[-1] / (3 * ds[-1]) + 3 * g.qdd[-1],
                     0 * g.qd[-1]]
        self.jerk_weights = w
        self.jerk_cols = np.c_[i, i + 1, N + 1 + i, N + 2 + i]              # (N, 4)
        # x_{i+1} - x_i = ds_i (u_i + u_{i+1}): u linear in s, x quadratic in s; on the first
        # and last intervals, at constant jerk from and to rest (s ~ t^3), x = END u ds.
        wa, wb = np.ones(N), np.ones(N)
        if self.ends:
            wa[0], wb[0], wa[-1], wb[-1] = 0.0, END, END, 0.0
        self.eq = sparse.csr_matrix((np.r_[-np.ones(N), np.ones(N), -ds * wa, -ds * wb],
                                     (np.r_[i, i, i, i],
                                      np.r_[i, i + 1, N + 1 + i, N + 2 + i])),
                                    shape=(N, 2 * (N + 1)))
        # Rest at both ends, x = u = 0; the velocity limits as bounds on x.
        self.bounds = np.zeros((2 * (N + 1), 2))
        self.bounds[1:N, 1] = np.minimum(xv[1:-1], 1e300)
        self.bounds[N + 2:2 * N + 1] = [-np.inf, np.inf]
        # Maximise the speed: x weighted by the length of path each grid point stands for
        # (`retime_jerk` divides it by the largest x of the fastest plan).
        weight = np.r_[ds / 2, 0.0] + np.r_[0.0, ds / 2]
        self.cost = np.r_[-weight / weight.max(), np.zeros(N + 1)]

    def solve(self, reference: NDArray, growth: float,
              smoothing: float = 0.0) -> tuple[NDArray, NDArray] | None:
        """(x, u) of the fastest plan whose speed stays within `growth` times `reference`
        (N + 1,) ds/dt, its jerk rows taking that bound as ds/dt: a plan within the jerk
        limits (at the rows), since the true ds/dt is no larger. None when there is none.
        `smoothing` is the cost of a unit of u's total variation (see `_run`)."""
        N, n = self.N, self.n
        # A floor lets a point where the last plan stopped move again.
        top = np.maximum(growth * reference, FLOOR * reference.max())
        at = np.maximum(top[:-1], top[1:])
        if self.ends:
            at[0], at[-1] = top[1], top[-2]
        values = self.jerk_weights * at[:, None, None]                     # (N, 4, n)
        rows = np.broadcast_to(np.arange(N)[:, None, None] + N * np.arange(n), values.shape)
        cols = np.broadcast_to(self.jerk_cols[:, :, None], values.shape)
        jerk = sparse.csr_matrix((values.ravel(), (rows.ravel(), cols.ravel())),
                                 shape=(N * n, 2 * (N + 1)))
        bound = np.repeat(self.J, N)
        bounds = self.bounds.copy()
        bounds[:N + 1, 1] = np.minimum(bounds[:N + 1, 1], top ** 2)
        return self._run(sparse.vstack([self.acc, jerk, -jerk]).tocsr(),
                         np.r_[self.acc_bound, bound, bound], bounds, smoothing)

    def fastest(self) -> tuple[NDArray, NDArray] | None:
        """(x, u) of the fastest plan within the velocity and acceleration limits alone."""
        return self._run(self.acc, self.acc_bound, self.bounds)

    def _run(self, A_ub, b_ub, bounds, smoothing: float = 0.0
             ) -> tuple[NDArray, NDArray] | None:
        """Solve with the rows given; with `smoothing`, plus that cost on the total variation
        of u (N more variables d_i >= |u_{i+1} - u_i|)."""
        N = self.N
        cost, eq = self.cost, self.eq
        if smoothing > 0:
            i = np.arange(N)
            change = sparse.csr_matrix((np.r_[-np.ones(N), np.ones(N)],
                                        (np.r_[i, i], N + 1 + np.r_[i, i + 1])),
                                       shape=(N, 2 * (N + 1)))
            spread = sparse.hstack([sparse.vstack([change, -change]),
                                    -sparse.vstack([sparse.eye(N), sparse.eye(N)])])
            A_ub = sparse.vstack([sparse.hstack([A_ub, sparse.csr_matrix((A_ub.shape[0], N))]),
                                  spread]).tocsr()
            b_ub = np.r_[b_ub, np.zeros(2 * N)]
            eq = sparse.hstack([eq, sparse.csr_matrix((N, N))]).tocsr()
            cost = np.r_[cost, np.full(N, smoothing)]
            bounds = np.r_[bounds, np.tile([0.0, np.inf], (N, 1))]
        done = linprog(cost, A_ub=A_ub, b_ub=b_ub, A_eq=eq, b_eq=np.zeros(N), bounds=bounds,
                       method="highs")
        if done.status != 0:
            return None
        return done.x[:N + 1], done.x[N + 1:2 * (N + 1)]


def _durations(s: NDArray, x: NDArray, u: NDArray) -> NDArray:
    """Time (s) on each grid interval, (N,): on the interior ones the integral of ds / sqrt(x)
    with x quadratic in s (u linear), by Gauss-Legendre; on the first and last, at constant
    jerk from or to rest, sqrt(6 ds / |u|) with u at the inner end."""
    ds = np.diff(s)
    nodes, weights = GAUSS
    sigma = (nodes + 1) / 2                                               # (G,) in (0, 1)
    xs = (x[:-1, None] + 2 * u[:-1, None] * ds[:, None] * sigma
          + np.diff(u)[:, None] * ds[:, None] * sigma ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = ds * (weights / 2 / np.sqrt(np.maximum(xs, 0.0))).sum(axis=1)
        if len(ds) > 2:
            h[0] = np.sqrt(6 * ds[0] / abs(u[1]))
            h[-1] = np.sqrt(6 * ds[-1] / abs(u[-2]))
    return h


def _compose(path: Trajectory, s: NDArray, sd: NDArray, u: NDArray, dt: NDArray) -> NDArray:
    """Coefficients (N, 5 d + 1, n) of q(s(tau)) per grid interval, d the path's degree and
    s(tau) the quintic matching s, ds/dt and d2s/dt2 at both ends of the interval (tau from 0
    to dt)."""
    N = dt.shape[0]
    ds = np.diff(s)
    # Quintic Hermite d(tau) = s(tau) - s_i with d(0) = 0, d'(0) = sd_i, d''(0) = u_i and
    # d(h) = ds, d'(h) = sd_{i+1}, d''(h) = u_{i+1}: the last three coefficients solve
    # a 3 x 3 system in h.
    h = dt
    a1, a2 = sd[:-1], u[:-1] / 2
    r0 = ds - a1 * h - a2 * h ** 2
    r1 = sd[1:] - a1 - 2 * a2 * h
    r2 = u[1:] - 2 * a2
    a3 = (10 * r0 - 4 * r1 * h + r2 * h ** 2 / 2) / h ** 3
    a4 = (-15 * r0 + 7 * r1 * h - r2 * h ** 2) / h ** 4
    a5 = (6 * r0 - 3 * r1 * h + r2 * h ** 2 / 2) / h ** 5
    K = 5 * max(path.degree, 1) + 1
    d = np.zeros((N, K))
    d[:, 1:6] = np.c_[a1, a2, a3, a4, a5][:, :K - 1]
    # The path's piece under each interval (its middle: a grid point may lie a hair before a
    # break it stands for), re-expanded about the interval's start.
    piece = np.clip(np.searchsorted(path.breaks, s[:-1] + ds / 2, side="right") - 1, 0,
                    path.breaks.shape[0] - 2)
    c = shift(path.coefficients[piece], s[:-1] - path.breaks[piece])       # (N, K, n)
    out = np.zeros((N, K, path.n))
    power = np.zeros((N, K))
    power[:, 0] = 1.0
    for k in range(c.shape[1]):
        out += power[:, :, None] * c[:, k][:, None, :]
        power = _times(power, d)
    return out


def _times(p: NDArray, q: NDArray) -> NDArray:
    """Product of polynomials p, q (N, K) per row, truncated to K coefficients (exact here:
    the degrees used add up to less than K)."""
    K = p.shape[1]
    out = np.zeros_like(p)
    for k in range(K):
        if p[:, k].any():
            out[:, k:] += p[:, k:k + 1] * q[:, :K - k]
    return out


def _slow_down(tr: Trajectory, V: NDArray, A: NDArray, J: NDArray) -> float:
    """The least uniform slow-down (>= 1) that brings every peak within its limit."""
    keep = 1 - MARGIN
    return float(max(1.0, np.max(peaks(tr, 1) / (V * keep)),
                     np.sqrt(np.max(peaks(tr, 2) / (A * keep))),
                     np.cbrt(np.max(peaks(tr, 3) / (J * keep)))))
