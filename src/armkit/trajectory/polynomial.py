"""Point-to-point polynomials: cubic and quintic, every joint over the same duration.

The quintic between rest states is the inspection-robot paper's law (SPEC.md, R3)

    q(t) = q0 + (qf - q0) (10 s^3 - 15 s^4 + 6 s^5),   s = t / T.

Both are one-segment cases of `armkit.spline`: the cubic meets the end positions and
velocities, the quintic also the end accelerations. All joints share the duration, so they start
and finish together. Without a duration, the shortest one that keeps every joint within its
velocity, acceleration and jerk limit is taken, from the laws' peak values
between rest states:

=======  =========  ===========================  ============
law      peak |qd|  peak |qdd|                   peak |qddd|
=======  =========  ===========================  ============
cubic    1.5 D/T    6 D/T^2 (at the ends)        12 D/T^3
quintic  1.875 D/T  10/sqrt(3) D/T^2 (s = 0.21)  60 D/T^3
=======  =========  ===========================  ============
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.trajectory.piecewise import Trajectory, at_rest
from armkit.trajectory.splines import spline

# Peak |velocity|, |acceleration|, |jerk| per unit distance at T = 1, rest to rest.
PEAKS = {"cubic": (1.5, 6.0, 12.0), "quintic": (1.875, 10.0 / np.sqrt(3.0), 60.0)}


def cubic(q0: ArrayLike, qf: ArrayLike, duration: float | None = None, *,
          start_velocity: ArrayLike = 0.0, end_velocity: ArrayLike = 0.0,
          vmax: ArrayLike | None = None, amax: ArrayLike | None = None,
          jmax: ArrayLike | None = None) -> Trajectory:
    """Cubic from q0 to qf, every joint over the same duration.

    Parameters
    ----------
    q0, qf : array_like, shape (n,)
        Start and goal, rad or m per joint.
    duration : float, optional
        Seconds. If omitted: the shortest within the limits (rest to rest only).
    start_velocity, end_velocity : float or array_like (n,)
        Zero by default (rad/s or m/s).
    vmax, amax, jmax : float or array_like (n,), optional
        Limits used to choose the duration (inf or None for none).

    Returns
    -------
    Trajectory
        One piece from t = 0; accelerations step at the ends (6 D/T^2 between rest states).
    """
    return _one_piece("cubic", q0, qf, duration, (vmax, amax, jmax),
                      {"start_velocity": start_velocity, "end_velocity": end_velocity,
                       "start_acceleration": None, "end_acceleration": None})


def quintic(q0: ArrayLike, qf: ArrayLike, duration: float | None = None, *,
            start_velocity: ArrayLike = 0.0, end_velocity: ArrayLike = 0.0,
            start_acceleration: ArrayLike = 0.0, end_acceleration: ArrayLike = 0.0,
            vmax: ArrayLike | None = None, amax: ArrayLike | None = None,
            jmax: ArrayLike | None = None) -> Trajectory:
    """Quintic from q0 to qf; between rest states the 10-15-6 law.

    Parameters
    ----------
    q0, qf : array_like, shape (n,)
        Start and goal, rad or m per joint.
    duration : float, optional
        Seconds (the paper's T = 10 s). If omitted: the shortest within the limits (rest to
        rest only).
    start_velocity, end_velocity, start_acceleration, end_acceleration : float or array_like
        End conditions, zero by default (rad/s, rad/s^2 or m/s, m/s^2).
    vmax, amax, jmax : float or array_like (n,), optional
        Limits used to choose the duration.

    Returns
    -------
    Trajectory
        One piece from t = 0.

    Example
    -------
    >>> tr = quintic(np.zeros(6), np.deg2rad([30, -45, 60, 0, 90, 0]), 10.0)
    >>> np.rad2deg(tr.evaluate(5.0))           # halfway: half of each move
    array([ 15. , -22.5,  30. ,   0. ,  45. ,   0. ])
    """
    return _one_piece("quintic", q0, qf, duration, (vmax, amax, jmax),
                      {"start_velocity": start_velocity, "end_velocity": end_velocity,
                       "start_acceleration": start_acceleration,
                       "end_acceleration": end_acceleration})


def _one_piece(law: str, q0: ArrayLike, qf: ArrayLike, duration: float | None, lims: tuple,
               ends: dict) -> Trajectory:
    """The one-segment spline of degree 3 or 5 from q0 to qf with the given end conditions."""
    q0, qf = _ends(q0, qf)
    moving = any(np.any(v) for v in ends.values() if v is not None)
    if duration is None and not moving and np.array_equal(q0, qf):
        for name, value in zip(("vmax", "amax", "jmax"), lims):
            limits(name, value, q0.shape[0])        # still checked
        return at_rest(q0, law)                     # no motion: nothing to time
    T = _duration(law, q0, qf, duration, lims, moving)
    tr = spline([0.0, T], [q0, qf], 3 if law == "cubic" else 5, **ends)
    return Trajectory(tr.breaks, tr.coefficients, label=law)


def _ends(q0: ArrayLike, qf: ArrayLike) -> tuple[NDArray, NDArray]:
    try:
        a, b = np.asarray(q0, dtype=float), np.asarray(qf, dtype=float)
    except (TypeError, ValueError):
        raise InputError("q0, qf: expected joint values") from None
    if a.ndim != 1 or a.shape != b.shape:
        raise InputError(f"q0, qf: expected two arrays of shape (n,), found {a.shape} and "
                         f"{b.shape}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise InputError("q0, qf: expected finite joint values, found NaN or inf")
    return a, b


def limits(name: str, value: ArrayLike | None, n: int) -> NDArray:
    """A limit per joint (n,): positive, inf where none; None means none at all."""
    if value is None:
        return np.full(n, np.inf)
    try:
        v = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected one positive number or {n}, found {value!r}") \
            from None
    if not (v > 0).all():
        raise InputError(f"{name}: expected positive limits, found {v.tolist()}")
    return v


def _duration(law: str, q0: NDArray, qf: NDArray, duration: float | None, lims: tuple,
              moving_ends: bool) -> float:
    if duration is not None:
        if not (np.isfinite(duration) and duration > 0):
            raise InputError(f"duration: expected a positive number of seconds, found {duration}")
        return float(duration)
    if moving_ends:
        raise InputError("duration: expected a duration when an end velocity or acceleration "
                         "is given, found none")
    n, D = q0.shape[0], np.abs(qf - q0)
    v, a, j = (limits(name, x, n) for name, x in zip(("vmax", "amax", "jmax"), lims))
    kv, ka, kj = PEAKS[law]
    T = np.max(np.r_[kv * D / v, np.sqrt(ka * D / a), np.cbrt(kj * D / j)])
    if not T > 0:
        raise InputError("duration: expected a duration, or limits (vmax, amax, jmax) and a "
                         "goal away from the start, found neither")
    return float(T)
