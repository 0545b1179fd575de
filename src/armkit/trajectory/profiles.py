"""Rest-to-rest profiles under limits: trapezoidal velocity and jerk-limited (double S).

Both are closed forms (Biagiotti & Melchiorri, *Trajectory Planning for Automatic Machines and
Robots*, 2008, sections 3.2.2 and 3.4), vectorised over any number of problems and joints:

- trapezoidal: accelerate at amax, cruise at vmax, decelerate; triangular (no cruise) when the
  distance is too short to reach vmax;
- jerk-limited (seven segments): jerk +-jmax, acceleration up to amax, velocity up to vmax;
  segments drop out when a limit is not reached.

Synchronisation, so that every joint starts and finishes together:

- ``sync="time"`` (default; what ruckig does): the duration is the longest of the joints' own
  shortest durations; every other joint keeps its acceleration (and jerk) limit and lowers its
  cruise velocity until it takes exactly as long (a quadratic, or for a profile that never
  reaches amax the cubic ``2 Tj^3 - T Tj^2 + D/jmax = 0`` in closed form).
- ``sync="phase"``: one profile shape for all joints, scaled by each joint's distance, so the
  motion is a straight line in joint space. Its limits are the tightest of ``limit_j / D_j``;
  never faster than "time", often a little slower.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.trajectory import _kernels
from armkit.trajectory.piecewise import Trajectory, at_rest

Sync = Literal["time", "phase"]


@dataclass(frozen=True)
class Profile:
    """Synchronised rest-to-rest profiles; leading shape (...) one per problem, n joints.

    Attributes
    ----------
    duration : ndarray, shape (...)
        s; the same for every joint of a problem (a NumPy scalar for one problem).
    times : ndarray, shape (..., n, P + 1)
        Start of each phase and the end, from 0 to duration (phases may have zero length).
    values : ndarray, shape (..., n, P)
        The constant highest derivative in each phase, signed: acceleration (trapezoid, P = 3)
        or jerk (jerk-limited, P = 7); rad/s^2 or rad/s^3 (m/... for prismatic joints).
    order : int
        2 for trapezoidal, 3 for jerk-limited.
    q0, qf : ndarray, shape (..., n)
    """

    duration: NDArray
    times: NDArray
    values: NDArray
    order: int
    q0: NDArray
    qf: NDArray

    def peaks(self) -> tuple[NDArray, NDArray, NDArray]:
        """Peak |velocity|, |acceleration| and |jerk| (inf for a trapezoid) per joint (..., n)."""
        dt = np.diff(self.times, axis=-1)
        if self.order == 2:
            a = np.abs(self.values[..., 0])
            return a * dt[..., 0], a, np.where(a > 0, np.inf, 0.0)
        j = np.abs(self.values[..., 0])
        a = j * dt[..., 0]
        return a * (dt[..., 0] + dt[..., 1]), a, j


def trapezoidal_profile(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, *,
                        sync: Sync = "time") -> Profile:
    """Synchronised trapezoidal-velocity profiles, batch-first.

    Parameters
    ----------
    q0, qf : array_like, shape (..., n)
        Start and goal per problem (rad or m per joint); leading shapes broadcast.
    vmax, amax : array_like, broadcastable to (..., n)
        Positive limits (rad/s, rad/s^2; m/s, m/s^2); vmax may be inf.
    sync : {"time", "phase"}
        See the module notes.

    Returns
    -------
    Profile
        ``order`` 2: phases accelerate, cruise, decelerate.
    """
    return _profile(2, q0, qf, vmax, amax, 1.0, sync)


def jerk_limited_profile(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
                         jmax: ArrayLike, *, sync: Sync = "time") -> Profile:
    """Synchronised jerk-limited (double S, seven segment) profiles, batch-first.

    Parameters
    ----------
    q0, qf : array_like, shape (..., n)
        Start and goal per problem (rad or m per joint); leading shapes broadcast.
    vmax, amax, jmax : array_like, broadcastable to (..., n)
        Positive limits; vmax and amax may be inf, jmax must be finite.
    sync : {"time", "phase"}
        See the module notes.

    Returns
    -------
    Profile
        ``order`` 3: jerk +j, 0, -j, 0 (cruise), -j, 0, +j.

    Example
    -------
    >>> goals = np.random.default_rng(0).uniform(-1.0, 1.0, (1000, 6))
    >>> p = jerk_limited_profile(np.zeros((1000, 6)), goals, 1.0, 2.0, 10.0)
    >>> p.duration.shape
    (1000,)
    """
    return _profile(3, q0, qf, vmax, amax, jmax, sync)


def trapezoidal(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, *,
                sync: Sync = "time") -> Trajectory:
    """Trapezoidal-velocity motion from q0 to qf, all joints starting and ending together.

    Parameters
    ----------
    q0, qf : array_like, shape (n,)
        Start and goal (rad or m per joint).
    vmax, amax : float or array_like (n,)
        Positive limits (rad/s, rad/s^2; m/s, m/s^2), e.g. ``robot.velocity_limits``.
    sync : {"time", "phase"}
        See the module notes.

    Returns
    -------
    Trajectory
        Piecewise quadratic from t = 0, label ``"trapezoidal"``.
    """
    return profile_trajectory(trapezoidal_profile(*_single(q0, qf), vmax, amax, sync=sync),
                              "trapezoidal")


def jerk_limited(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
                 jmax: ArrayLike, *, sync: Sync = "time") -> Trajectory:
    """Jerk-limited (double S) motion from q0 to qf, all joints starting and ending together.

    Parameters
    ----------
    q0, qf : array_like, shape (n,)
        Start and goal (rad or m per joint).
    vmax, amax, jmax : float or array_like (n,)
        Positive limits (rad/s, rad/s^2, rad/s^3; m/... for prismatic joints).
    sync : {"time", "phase"}
        See the module notes.

    Returns
    -------
    Trajectory
        Piecewise cubic from t = 0, label ``"jerk-limited"``; the duration equals ruckig's
        (time synchronisation) for the same limits.
    """
    return profile_trajectory(jerk_limited_profile(*_single(q0, qf), vmax, amax, jmax,
                                                   sync=sync), "jerk-limited")


def profile_trajectory(profile: Profile, label: str = "") -> Trajectory:
    """The `Trajectory` of one problem's profile (leading shape ()), breaks merged over joints.

    Each joint's phases are integrated exactly from rest at q0: on phase k the polynomial is
    ``q + v tau + a tau^2 / 2 (+ j tau^3 / 6)`` with the state at the phase's start.
    """
    if profile.duration.ndim != 0:
        raise InputError(f"profile: expected one problem (leading shape ()), found "
                         f"{profile.duration.shape}")
    if not profile.duration > 0:                    # the goal is the start
        return at_rest(profile.q0, label)
    breaks, c = _kernels.profile_pieces.light(profile.order, np.ascontiguousarray(profile.times),
                                        np.ascontiguousarray(profile.values),
                                        np.ascontiguousarray(profile.q0, dtype=float), 1e-12)
    breaks.setflags(write=False)                # fresh and ours: the Trajectory keeps them
    c.setflags(write=False)
    return Trajectory(breaks, c, label=label)


def _one_problem(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
                 jmax: ArrayLike) -> NDArray | None:
    """One problem, q0 and qf arrays (n,) with limits that are numbers or (n,), stacked as
    (5, 1, n) without asking NumPy to broadcast the shapes first; None for anything else."""
    if not (type(q0) is np.ndarray and type(qf) is np.ndarray and q0.ndim == 1
            and q0.shape == qf.shape and q0.shape[0] > 0):
        return None
    shape = q0.shape
    if (type(vmax) is np.ndarray and type(amax) is np.ndarray and type(jmax) is np.ndarray
            and vmax.shape == amax.shape == jmax.shape == shape):
        return np.array((q0, qf, vmax, amax, jmax), dtype=float).reshape(5, 1, shape[0])
    stacked = np.empty((5, 1, shape[0]))
    try:
        stacked[0, 0] = q0
        stacked[1, 0] = qf
        stacked[2, 0] = vmax
        stacked[3, 0] = amax
        stacked[4, 0] = jmax
    except (TypeError, ValueError):
        return None                             # a limit of another shape: the general way
    return stacked


def _problem(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
             jmax: ArrayLike) -> NDArray:
    """q0, qf and the limits stacked into one float array (5, ..., n), each broadcast to the
    problems' shape (one allocation; the kernel checks the values)."""
    raw = (q0, qf, vmax, amax, jmax)
    try:
        shape = np.broadcast_shapes(*(np.shape(x) for x in raw))
        stacked = np.empty((5,) + shape)
        for row, x in zip(stacked, raw):
            row[...] = x
    except (TypeError, ValueError):
        raise InputError(f"q0, qf, limits: expected numbers of shapes that broadcast to "
                         f"(..., n), found {[np.shape(x) for x in raw[:4]]}") from None
    if not shape:
        raise InputError("q0, qf: expected shape (..., n), found scalars")
    return stacked


def _single(q0: ArrayLike, qf: ArrayLike) -> tuple[NDArray, NDArray]:
    a, b = np.asarray(q0, dtype=float), np.asarray(qf, dtype=float)
    if a.ndim != 1 or a.shape != b.shape:
        raise InputError(f"q0, qf: expected shape (n,) each (for batches use the *_profile "
                         f"functions), found {a.shape} and {b.shape}")
    return a, b


def _profile(order: int, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
             jmax: ArrayLike, sync: str) -> Profile:
    """Run the timing kernel on the problems (a trapezoid's jmax is 1.0, unused). One problem
    is a batch of one, with as few steps in Python around the kernel as it takes."""
    if sync != "time" and sync != "phase":
        raise InputError(f"sync: expected 'time' or 'phase', found {sync!r}")
    K = 3 if order == 2 else 7
    one = _one_problem(q0, qf, vmax, amax, jmax)
    if one is not None:
        n = one.shape[2]
        times, values = np.empty((1, n, K + 1)), np.empty((1, n, K))
        bad = _kernels.profile_timing.light(order, one, sync == "phase", times, values)
        if bad:
            _refuse(bad, order, one)
        times = times[0]
        return Profile(times[0, -1], times, values[0], order, one[0, 0], one[1, 0])
    arrays = _problem(q0, qf, vmax, amax, jmax)
    lead, n = arrays.shape[1:], arrays.shape[-1]
    times, values = np.empty(lead + (K + 1,)), np.empty(lead + (K,))
    bad = _kernels.profile_timing.sized(arrays[0].size, order, arrays.reshape(5, -1, n),
                                        sync == "phase", times.reshape(-1, n, K + 1),
                                        values.reshape(-1, n, K))
    if bad:
        _refuse(bad, order, arrays)
    return Profile(times[..., 0, -1].copy(), times, values, order, arrays[0], arrays[1])


def _refuse(bad: int, order: int, arrays: NDArray) -> None:
    """Raise for the kernel's first bad input (1 q0 or qf, 2 vmax, 3 amax, 4 jmax)."""
    if bad == 1:
        raise InputError("q0, qf: expected finite joint values, found NaN or inf")
    name = ("vmax", "amax", "jmax")[bad - 2]
    finite = "" if name == "vmax" or (name == "amax" and order == 3) else " finite"
    raise InputError(f"{name}: expected positive{finite} limits, found "
                     f"{np.unique(arrays[bad]).tolist()}")
