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


@dataclass(frozen=True, init=False)
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

    def __init__(self, duration: NDArray, times: NDArray, values: NDArray, order: int,
                 q0: NDArray, qf: NDArray):
        # Straight into the instance's dict: the __init__ a frozen dataclass writes sets each
        # field through object.__setattr__, a sixth of one profile's time.
        fields = self.__dict__
        fields["duration"], fields["times"], fields["values"] = duration, times, values
        fields["order"], fields["q0"], fields["qf"] = order, q0, qf

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
    one = _one(2, q0, qf, vmax, amax, 1.0, sync)
    return one if one is not None else _profile(2, q0, qf, vmax, amax, 1.0, sync)


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
    one = _one(3, q0, qf, vmax, amax, jmax, sync)
    return one if one is not None else _profile(3, q0, qf, vmax, amax, jmax, sync)


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
    return _motion(2, q0, qf, vmax, amax, 1.0, sync, "trapezoidal")


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
    return _motion(3, q0, qf, vmax, amax, jmax, sync, "jerk-limited")


def profile_trajectory(profile: Profile, label: str = "") -> Trajectory:
    """The `Trajectory` of one problem's profile (leading shape ()), breaks merged over joints.

    Each joint's phases are integrated exactly from rest at q0: on phase k the polynomial is
    ``q + v tau + a tau^2 / 2 (+ j tau^3 / 6)`` with the state at the phase's start.
    """
    if profile.duration.ndim != 0:
        raise InputError(f"profile: expected one problem (leading shape ()), found "
                         f"{profile.duration.shape}")
    return _trajectory(profile.order, np.ascontiguousarray(profile.times),
                       np.ascontiguousarray(profile.values),
                       np.ascontiguousarray(profile.q0, dtype=float), label)


def _trajectory(order: int, times: NDArray, values: NDArray, q0: NDArray,
                label: str) -> Trajectory:
    """One problem's phases (C-contiguous times (n, P + 1), values (n, P), q0 (n,)) as a
    `Trajectory`."""
    if not times[0, -1] > 0:                    # the goal is the start
        return at_rest(q0, label)
    breaks, c = _kernels.profile_pieces.light(order, times, values, q0, 1e-12)
    breaks.setflags(write=False)                # fresh and ours: the Trajectory keeps them
    c.setflags(write=False)
    # The kernel's breaks increase by construction and its values are finite for checked
    # inputs (tests/trajectory/test_profiles.py checks them again): the Trajectory need not.
    return Trajectory(breaks, c, label=label, check=False)


def _motion(order: int, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
            jmax: ArrayLike, sync: str, label: str) -> Trajectory:
    """`trapezoidal` and `jerk_limited`: one problem's phases (`_one`) into the pieces kernel,
    or the general way when the inputs are not one problem."""
    one = _one(order, q0, qf, vmax, amax, jmax, sync)
    if one is None:                             # the general way, and its messages
        return profile_trajectory(_profile(order, *_single(q0, qf), vmax, amax, jmax, sync),
                                  label)
    return _trajectory(order, one.times, one.values, one.q0, label)


_NUMBER = np.empty(0)       # a limit's "no value per joint": the timing kernel takes its number
_FLOAT = np.dtype(float)    # NumPy converts a dtype given as an instance faster than as a type


def _limit(x: ArrayLike) -> tuple[NDArray, float]:
    """A limit as the timing kernel takes it: a float as its number (with `_NUMBER` as the
    array), anything else as an array (a number: shape (1,)) with the number unused."""
    if type(x) is float:
        return _NUMBER, x
    return np.ascontiguousarray(x, dtype=_FLOAT), 0.0


def _one(order: int, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
         jmax: ArrayLike, sync: str) -> Profile | None:
    """One problem through the timing kernel with as few steps in Python as it takes: q0, qf
    (n,) copied to fresh float arrays (the `Profile` keeps them), each limit a float passed as
    a number or an array (n,) or (1,) passed as it is (copied only if read-only). None for
    inputs of other kinds or shapes, which take the general way (`_profile`)."""
    if sync != "time" and sync != "phase":
        raise InputError(f"sync: expected 'time' or 'phase', found {sync!r}")
    if type(q0) is np.ndarray and q0.ndim != 1:
        return None                             # a batch: no copy to find that out
    try:
        q0, qf = np.array(q0, dtype=_FLOAT), np.array(qf, dtype=_FLOAT)
        (V, v), (A, a), (J, j) = _limit(vmax), _limit(amax), _limit(jmax)
    except (TypeError, ValueError):
        return None
    if not q0.ndim == qf.ndim == V.ndim == A.ndim == J.ndim == 1:
        return None
    if not (V.flags.writeable and A.flags.writeable and J.flags.writeable):
        # Read-only limits (a Robot's): numba types them apart from writable arrays and would
        # compile the kernel again for every mix of the two.
        V, A, J = (x if x.flags.writeable else x.copy() for x in (V, A, J))
    n, K = len(q0), 3 if order == 2 else 7
    times, values = np.empty((n, K + 1)), np.empty((n, K))
    bad = _kernels.profile_timing.light(order, n, q0, qf, V, A, J, v, a, j, sync == "phase",
                                        times, values)
    if bad:
        if bad == 5:                            # the lengths are not one problem's
            return None
        _refuse(bad, order, (vmax, amax, jmax))
    return Profile(times[0, -1], times, values, order, q0, qf)


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
    if not shape[-1]:
        raise InputError(f"q0, qf: expected shape (..., n) with n >= 1 joints, found {shape}")
    return stacked


def _single(q0: ArrayLike, qf: ArrayLike) -> tuple[NDArray, NDArray]:
    a, b = np.asarray(q0, dtype=float), np.asarray(qf, dtype=float)
    if a.ndim != 1 or a.shape != b.shape:
        raise InputError(f"q0, qf: expected shape (n,) each (for batches use the *_profile "
                         f"functions), found {a.shape} and {b.shape}")
    return a, b


def _profile(order: int, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike,
             jmax: ArrayLike, sync: str) -> Profile:
    """Run the timing kernel on the problems (a trapezoid's jmax is 1.0, unused), stacked and
    broadcast first: a batch, or one problem that `_one` did not take (`_one` checked sync)."""
    arrays = _problem(q0, qf, vmax, amax, jmax)
    lead, n = arrays.shape[1:], arrays.shape[-1]
    K = 3 if order == 2 else 7
    times, values = np.empty(lead + (K + 1,)), np.empty(lead + (K,))
    flat = arrays.reshape(5, -1)
    bad = _kernels.profile_timing.sized(flat[0].size, order, n, flat[0], flat[1], flat[2],
                                        flat[3], flat[4], 0.0, 0.0, 0.0, sync == "phase",
                                        times.reshape(-1, K + 1), values.reshape(-1, K))
    if bad:
        _refuse(bad, order, (vmax, amax, jmax))
    return Profile(times[..., 0, -1].copy(), times, values, order, arrays[0], arrays[1])


def _refuse(bad: int, order: int, limits: tuple[ArrayLike, ArrayLike, ArrayLike]) -> None:
    """Raise for the kernel's first bad input (1 q0 or qf, 2 vmax, 3 amax, 4 jmax)."""
    if bad == 1:
        raise InputError("q0, qf: expected finite joint values, found NaN or inf")
    name = ("vmax", "amax", "jmax")[bad - 2]
    finite = "" if name == "vmax" or (name == "amax" and order == 3) else " finite"
    raise InputError(f"{name}: expected positive{finite} limits, found "
                     f"{np.unique(np.asarray(limits[bad - 2], dtype=float)).tolist()}")
