"""Closed-form inverse kinematics: every solution, for the arm families that have one.

Families are recognised from the chain's geometry at q = 0 (its joint axes as lines in space,
`Chain.screws` and `Chain.points`), never from a robot's name, so a user's own arm of the same
family, described as DH, modified DH, screws or URDF, gets the same solver:

- ``lift_swing``: one prismatic and three revolute joints, all along one direction (the
  water-supply arm; a SCARA). Task: position + rotation about that direction. 2 solutions.
- ``yaw_pitch``: four revolute joints, the last three parallel to each other and not to the
  first (the modular 4-DOF arm). Task: position + the pointing of one tool axis. 4 solutions:
  the base angle and its twin, two elbows.
- ``parallel_wrist``: six revolute joints, axes 2-4 parallel, axes 5 and 6 meeting (UR arms,
  the inspection arm). 8 solutions.
- ``spherical_wrist``: axes 1 and 2 meeting, joint 3 revolute or prismatic, axes 4-6 meeting
  in one point (Puma 560, Stanford arm). 8 solutions.

The solutions come from the Paden-Kahan subproblems on the product of exponentials
``T(q) = exp([S_1] q_1) ... exp([S_n] q_n) T_home`` (Murray, Li and Sastry, ch. 3.3), vectorised
over targets; each branch is an extra axis. A branch without a real solution is NaN. Candidates
are checked by forward kinematics elsewhere (``armkit.ik``): nothing here decides success.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from armkit.model.chain import Chain
from armkit.spatial import invert

PARALLEL = 1e-9          # |w_i x w_j| below this: parallel axes
MEET = 1e-9              # distance (m) below this: intersecting axes
ACOS_SLACK = 1e-9        # |cos| up to 1 + this is rounding at a boundary, clipped to 1


# --- geometry on batches of vectors -----------------------------------------------------------

def _dot(a, b):
    """Dot product over the last axis (3 components; faster than a sum over that axis)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a, b):
    """Cross product over the last axis; several times faster than np.cross on small batches."""
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _rotate(w, theta, v):
    """Rotate vectors v (..., 3) about unit axes w (..., 3) by theta (...) (Rodrigues)."""
    c, s = np.cos(theta)[..., None], np.sin(theta)[..., None]
    return v * c + _cross(w, v) * s + w * _dot(w, v)[..., None] * (1 - c)


def _acos(x):
    """arccos, with rounding just past +-1 clipped and real misses (no solution) NaN."""
    x = np.where(np.abs(x) <= 1 + ACOS_SLACK, np.clip(x, -1.0, 1.0), np.nan)
    return np.arccos(x)


def _perp(w, v):
    return v - w * _dot(w, v)[..., None]


def sp1(w, u, v):
    """Paden-Kahan 1: theta with ``Rot(w, theta) u = v`` (vectors relative to the axis).

    Uses the parts of u and v normal to w; where either vanishes (to 1e-9 of |u|) any theta
    works and 0 is given, rather than the angle of two round-off vectors.
    """
    a, b = _perp(w, u), _perp(w, v)
    scale = 1e-9 * np.maximum(np.sqrt(_dot(u, u)), 1e-300)
    degenerate = (np.sqrt(_dot(a, a)) < scale) | (np.sqrt(_dot(b, b)) < scale)
    return np.where(degenerate, 0.0, np.arctan2(_dot(w, _cross(a, b)), _dot(a, b)))


def sp3(w, u, v, delta):
    """Paden-Kahan 3: the two theta with ``|Rot(w, theta) u - v| = delta``; (..., 2), NaN if none."""
    a, b = _perp(w, u), _perp(w, v)
    d2 = delta**2 - _dot(w, u - v) ** 2
    na, nb = np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1)
    theta0 = np.arctan2(_dot(w, _cross(a, b)), _dot(a, b))
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = _acos((na**2 + nb**2 - d2) / (2 * na * nb))
    return np.stack([theta0 - spread, theta0 + spread], axis=-1)


def sp4(w, a, b, c):
    """The two theta with ``a . Rot(w, theta) b = c``; (..., 2), NaN if none.

    ``a . Rot b = (a.w)(w.b) + cos(theta) a.b_perp + sin(theta) a.(w x b_perp)``.
    """
    bp = _perp(w, b)
    A, B = _dot(a, bp), _dot(a, _cross(w, bp))
    C = c - _dot(a, w) * _dot(w, b)
    r = np.hypot(A, B)
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = _acos(C / r)
    base = np.arctan2(B, A)
    return np.stack([base - spread, base + spread], axis=-1)


def sp2(w1, w2, u, v):
    """Paden-Kahan 2: (theta1, theta2) with ``Rot(w1, t1) Rot(w2, t2) u = v``, axes meeting at
    the origin of u and v; two branches, each (..., 2), NaN if none."""
    c12 = _dot(w1, w2)
    den = c12**2 - 1
    alpha = (c12 * _dot(w2, u) - _dot(w1, v)) / den
    beta = (c12 * _dot(w1, v) - _dot(w2, u)) / den
    n = _cross(w1, w2)
    g2 = (_dot(u, u) - alpha**2 - beta**2 - 2 * alpha * beta * c12) / _dot(n, n)
    g2 = np.where(g2 > -ACOS_SLACK * np.maximum(_dot(u, u), 1e-300), np.maximum(g2, 0.0), np.nan)
    t1, t2 = [], []
    for sign in (-1.0, 1.0):
        z = alpha[..., None] * w1 + beta[..., None] * w2 + (sign * np.sqrt(g2))[..., None] * n
        t2.append(sp1(w2, u, z))
        t1.append(sp1(w1, z, v))
    return np.stack(t1, axis=-1), np.stack(t2, axis=-1)


def _rotation(w, theta):
    """Rotation matrices (..., 3, 3) about unit axes w (3,) by theta (...)."""
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    t = np.asarray(theta)[..., None, None]
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * (K @ K)


def _screw_motion(w, r, theta, x):
    """Points x (..., 3) moved by the rotation theta about the line (w, r)."""
    return _rotate(w, theta, x - r) + r


# --- the families -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Family:
    """A closed-form solver recognised in a chain."""

    name: str
    mask: tuple[int, ...]            # the task its solutions satisfy exactly
    branches: int
    solve: Callable[[Chain, NDArray], NDArray]     # (chain, targets (N,4,4)) -> (N, K, n)


def _axes(chain: Chain):
    w = chain.screws[:, 3:].copy()
    prismatic = ~chain.revolute
    w[prismatic] = chain.screws[prismatic, :3]
    return w, chain.points


def _cross3(a, b) -> tuple[float, float, float]:
    """Cross product of two 3-vectors as floats (cheaper than NumPy for one pair)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _parallel(a, b) -> bool:
    return math.hypot(*_cross3(a, b)) < PARALLEL


def _line_distance(w1, r1, w2, r2) -> float:
    n, d = _cross3(w1, w2), r2 - r1
    if math.hypot(*n) < PARALLEL:
        return math.hypot(*_cross3(d, w1))
    return abs(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / math.hypot(*n)


def _meeting_point(w1, r1, w2, r2) -> NDArray:
    """The point where two intersecting, non-parallel lines meet."""
    A = np.stack([w1, -w2], axis=1)
    s, *_ = np.linalg.lstsq(A, r2 - r1, rcond=None)
    return r1 + s[0] * w1


def _planar_2r(wa, ra, wb, rb, p, x):
    """Angles (..., 2) of two parallel axes a then b taking point p (home) to x (..., 3).

    Solves ``Rot_a(ta) Rot_b(tb) p = x`` in the plane normal to the axes: tb makes the distance
    from axis a right (subproblem 3, two elbows), then ta turns it into place (subproblem 1).
    """
    delta = np.linalg.norm(_perp(wa, x - ra), axis=-1)
    tb = sp3(wb, _perp(wb, p - rb), _perp(wb, ra - rb) + 0 * x, delta)
    y = _screw_motion(wb, rb, tb, p)
    ta = sp1(wa, y - ra, x[..., None, :] - ra)
    return ta, tb


def _normal_to(a):
    """A unit vector normal to a (3,)."""
    v = _perp(a, np.eye(3)[np.argmin(np.abs(a))])
    return v / np.linalg.norm(v)


def _lift_swing(chain: Chain, targets: NDArray) -> NDArray:
    """Lift along a and three swings about axes along a: (N, 2, 4)."""
    w, r = _axes(chain)
    p = int(np.flatnonzero(~chain.revolute)[0])
    i1, i2, i3 = np.flatnonzero(chain.revolute)
    a = w[i1]
    M = chain.T_home
    t0, x_t = M[:3, 3], targets[:, :3, 3]
    lift = _dot(a, x_t - t0) / np.dot(a, w[p])          # swings keep the height along a
    x = x_t - lift[:, None] * w[p]
    u = _normal_to(a)                                    # total turn about a, from orientation
    phi = sp1(a, u, targets[:, :3, :3] @ (M[:3, :3].T @ u))
    c3 = x - _rotate(a, phi, t0 - r[i3])                # where the third swing axis must be
    t1, t2 = _planar_2r(w[i1], r[i1], w[i2], r[i2], r[i3], c3)
    sign = w[[i1, i2, i3]] @ a                          # each axis along (+1) or against a
    t3 = sign[2] * (phi[:, None] - sign[0] * t1 - sign[1] * t2)
    q = np.empty(t1.shape + (4,))
    q[..., p] = lift[:, None]
    q[..., i1], q[..., i2], q[..., i3] = t1, t2, t3
    return q


def _pointing_axis(chain: Chain) -> int:
    """The tool axis a yaw-and-pitch arm points: the one along its last link (else normal to
    the pitch axes)."""
    w, r = _axes(chain)
    R = chain.T_home[:3, :3]
    link = _perp(w[1], chain.T_home[:3, 3] - r[3])
    if np.linalg.norm(link) > MEET:
        return int(np.argmax(np.abs(R.T @ link)))
    return int(np.argmin(np.abs(R.T @ w[1])))


def _yaw_pitch(chain: Chain, targets: NDArray) -> NDArray:
    """Base yaw and three parallel pitch joints: (N, 4, 4), position + pointing of one axis."""
    w, r = _axes(chain)
    M = chain.T_home
    t0, x_t = M[:3, 3], targets[:, :3, 3]
    n0 = w[1]
    # The tool point's height along the pitch axes is fixed by the base angle alone.
    t1 = sp4(w[0], x_t - r[0], n0, np.dot(n0, t0 - r[0]))                       # (N, 2)
    back = lambda v: _rotate(w[0], -t1, v[:, None, :])    # noqa: E731  undo the base turn
    x = back(x_t - r[0]) + r[0]                                                 # (N, 2, 3)
    k = _pointing_axis(chain)
    phi = sp1(n0, M[:3, k], back(targets[:, :3, k]))                            # pitch sum
    x4 = x - _rotate(n0, phi, t0 - r[3])                 # where the last pitch axis must be
    t2, t3 = _planar_2r(w[1], r[1], w[2], r[2], r[3], x4)                       # (N, 2, 2)
    sign = w[1:4] @ n0
    t4 = sign[2] * (phi[..., None] - sign[0] * t2 - sign[1] * t3)
    q = np.stack([np.broadcast_to(t1[..., None], t2.shape), t2, t3, t4], axis=-1)
    return q.reshape(len(targets), 4, 4)


def _apply(T, x):
    """Transforms (..., 4, 4) applied to points (..., 3)."""
    return (T[..., :3, :3] @ x[..., None])[..., 0] + T[..., :3, 3]


def _parallel_wrist(chain: Chain, targets: NDArray) -> NDArray:
    """Axes 2-4 parallel, axes 5 and 6 meeting: (N, 8, 6)."""
    w, r = _axes(chain)
    g = targets @ invert(chain.T_home)                  # exp(S1 q1) ... exp(S6 q6)
    c0 = _meeting_point(w[4], r[4], w[5], r[5])          # fixed by joints 5 and 6
    n0 = w[1]
    x_t = _apply(g, c0)
    # Joints 2-4 keep every point's height along their axes: that fixes the base angle.
    t1 = sp4(w[0], x_t - r[0], n0, np.dot(n0, c0 - r[0]))                      # (N, 2)
    R1 = _rotation(w[0], -t1)                                                   # (N, 2, 3, 3)
    Rg = R1 @ g[:, None, :3, :3]                         # rotation of exp(S2 q2) ... exp(S6 q6)
    # Axis 6's direction against the pitch axes fixes joint 5 (two ways).
    d6 = Rg @ w[5]
    t5 = sp4(w[4], n0, w[5], _dot(n0, d6))                                      # (N, 2, 2)
    u = np.swapaxes(Rg, -1, -2) @ n0                                            # (N, 2, 3)
    t6 = sp1(w[5], u[:, :, None, :], _rotate(w[4], -t5, n0))                    # (N, 2, 2)
    e = _normal_to(n0)
    K = (Rg[:, :, None] @ _rotation(w[5], -t6)) @ _rotation(w[4], -t5)
    phi = sp1(n0, e, K @ e)                                                     # pitch sum
    # Where the point r4 on axis 4 must go: undo joints 6 and 5, apply g, undo joint 1.
    y = _screw_motion(w[5], r[5], -t6, _screw_motion(w[4], r[4], -t5, r[3]))
    y = _apply(g[:, None, None], y)
    x4 = _rotate(w[0], -t1[..., None], y - r[0]) + r[0]                          # (N, 2, 2, 3)
    t2, t3 = _planar_2r(w[1], r[1], w[2], r[2], r[3], x4)                       # (N, 2, 2, 2)
    sign = w[1:4] @ n0
    t4 = sign[2] * (phi[..., None] - sign[0] * t2 - sign[1] * t3)
    shape = t2.shape
    q = np.stack([np.broadcast_to(t1[:, :, None, None], shape), t2, t3, t4,
                  np.broadcast_to(t5[..., None], shape), np.broadcast_to(t6[..., None], shape)],
                 axis=-1)
    return q.reshape(len(targets), 8, 6)


def _undo(chain: Chain, i: int, value, x):
    """Points x moved back by joint i's motion of `value` (home axes)."""
    w, r = _axes(chain)
    if chain.revolute[i]:
        return _screw_motion(w[i], r[i], -value, x)
    return x - value[..., None] * w[i]


def _spherical_wrist(chain: Chain, targets: NDArray) -> NDArray:
    """Axes 1 and 2 meeting, axes 4-6 meeting in one point: (N, 8, 6)."""
    w, r = _axes(chain)
    g = targets @ invert(chain.T_home)
    s = _meeting_point(w[0], r[0], w[1], r[1])
    c0 = _meeting_point(w[3], r[3], w[4], r[4])          # the wrist centre
    x_t = _apply(g, c0)
    delta = np.linalg.norm(x_t - s, axis=-1)            # kept by joints 1 and 2
    if chain.revolute[2]:
        q3 = sp3(w[2], c0 - r[2], s - r[2] + 0 * x_t, delta)                   # (N, 2)
        y = _screw_motion(w[2], r[2], q3, c0)
    else:                                               # |c0 + q v - s| = delta: a quadratic
        b = np.dot(w[2], c0 - s)
        root = np.sqrt(np.where(b**2 - (np.dot(c0 - s, c0 - s) - delta**2) >= 0,
                                b**2 - (np.dot(c0 - s, c0 - s) - delta**2), np.nan))
        q3 = np.stack([-b - root, -b + root], axis=-1)
        y = c0 + q3[..., None] * w[2]
    t1, t2 = sp2(w[0], w[1], y - s, (x_t - s)[:, None, :])                      # (N, 2, 2)
    q3 = np.broadcast_to(q3[..., None], t1.shape)

    def arm_undone(p):                                  # g applied to p, joints 1-3 undone
        z = _apply(g[:, None, None], p)
        z = _screw_motion(w[0], s, -t1, z)
        z = _screw_motion(w[1], s, -t2, z)
        return _undo(chain, 2, q3, z)

    p6 = c0 + w[5]                                      # a point on axis 6 beside the centre
    t4, t5 = sp2(w[3], w[4], w[5], arm_undone(p6) - c0)                          # (N, 2, 2, 2)
    e = _normal_to(w[5])
    z = arm_undone(c0 + e)[..., None, :]
    z = _screw_motion(w[4], c0, -t5, _screw_motion(w[3], c0, -t4, z))
    t6 = sp1(w[5], e, z - c0)
    shape = t4.shape
    q = np.stack([np.broadcast_to(t1[..., None], shape), np.broadcast_to(t2[..., None], shape),
                  np.broadcast_to(q3[..., None], shape), t4, t5, t6], axis=-1)
    return q.reshape(len(targets), 8, 6)


# --- recognising a family ---------------------------------------------------------------------

def _rotation_flags(k: int, pointing: bool) -> tuple[int, ...]:
    """Mask flags for a rotation about tool axis k, or for pointing tool axis k."""
    flags = [0, 0, 0] if not pointing else [1, 1, 1]
    flags[k] = 0 if pointing else 1
    return (1, 1, 1, *flags)


def family_of(chain: Chain) -> Family | None:
    """The closed-form family of a chain, or None (then only the numeric solvers apply).

    `armkit.kinematics.ik.IKSolver` asks once and keeps the answer. A chain with mimic joints
    has none.
    """
    if chain.coupled:
        return None
    w, r = _axes(chain)
    n, rev = chain.n, chain.revolute
    meet = lambda i, j: (not _parallel(w[i], w[j])                   # noqa: E731
                         and _line_distance(w[i], r[i], w[j], r[j]) < MEET)
    R = chain.T_home[:3, :3]
    if n == 4 and rev.sum() == 3 and all(_parallel(w[i], w[0]) for i in range(4)):
        a = w[np.flatnonzero(rev)[0]]
        k = int(np.argmax(np.abs(R.T @ a)))
        return Family("lift_swing", _rotation_flags(k, pointing=False), 2, _lift_swing)
    if (n == 4 and rev.all() and _parallel(w[1], w[2]) and _parallel(w[1], w[3])
            and not _parallel(w[0], w[1])):
        return Family("yaw_pitch", _rotation_flags(_pointing_axis(chain), pointing=True), 4,
                      _yaw_pitch)
    if n != 6:
        return None
    if (rev.all() and _parallel(w[1], w[2]) and _parallel(w[1], w[3])
            and not _parallel(w[0], w[1]) and meet(4, 5) and not _parallel(w[4], w[1])):
        return Family("parallel_wrist", (1,) * 6, 8, _parallel_wrist)
    if rev[[0, 1, 3, 4, 5]].all() and meet(0, 1) and meet(3, 4) and not _parallel(w[4], w[5]):
        centre = _meeting_point(w[3], r[3], w[4], r[4])
        if np.linalg.norm(_cross(centre - r[5], w[5])) < MEET:
            return Family("spherical_wrist", (1,) * 6, 8, _spherical_wrist)
    return None


def candidates(chain: Chain, family: Family, targets: NDArray) -> NDArray:
    """Every branch of the family's closed form, (N, K, n), angles in [-pi, pi); NaN where a
    branch has no real solution."""
    with np.errstate(invalid="ignore", divide="ignore"):
        q = family.solve(chain, targets)
    return np.where(chain.revolute, (q + np.pi) % (2 * np.pi) - np.pi, q)
