"""Rigid-body maths: SO(3) rotations and SE(3) homogeneous transforms, batch-first.

Every function takes any leading shape ``(...)`` and works on the trailing axes:
rotations ``(..., 3, 3)``, transforms ``(..., 4, 4)``, points ``(..., 3)``.

Conventions
-----------
- ``T_a_b`` is frame b's pose in frame a; ``T_a_c = T_a_b @ T_b_c``.
- Roll-pitch-yaw ``(r, p, y)`` means ``R = Rz(y) @ Ry(p) @ Rx(r)`` (rotations about the fixed
  x, y, z axes in that order), as in URDF.
- Quaternions are ``(x, y, z, w)`` unless ``scalar_first=True``.
- Twists and screws are ``(v, w)``: linear part first, as the rows of `armkit.jacobian`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError

# scipy's Rotation is imported inside the quaternion functions that use it: it costs about
# 0.2 s, which loading a robot file, printing a pose or computing a pose error need not pay.

# cos(pitch) at or below which roll and yaw are not told apart (gimbal lock): scipy's 1e-7 rad.
GIMBAL_LOCK = 1e-7


def as_array(x: ArrayLike, name: str, tail: tuple[int, ...]) -> NDArray:
    """Return `x` as a finite float array whose trailing shape is `tail`.

    Raises
    ------
    InputError
        ``name: expected shape (..., 4, 4), found (3, 3)`` or a non-finite entry.
    """
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected numbers, found {type(x).__name__}") from None
    if a.shape[a.ndim - len(tail):] != tail or a.ndim < len(tail):
        want = ", ".join(["..."] + [str(t) for t in tail])
        raise InputError(f"{name}: expected shape ({want}), found {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: expected finite numbers, found NaN or inf")
    return a


def as_transform(T: ArrayLike, name: str = "T", tol: float = 1e-6) -> NDArray:
    """Return `T` as a float array of valid homogeneous transforms, shape (..., 4, 4).

    Raises
    ------
    InputError
        If the shape is wrong, the rotation part is not orthonormal with det +1 (within `tol`),
        or the last row is not ``(0, 0, 0, 1)``.
    """
    T = as_array(T, name, (4, 4))
    R = T[..., :3, :3]
    off = np.abs(R @ np.swapaxes(R, -1, -2) - np.eye(3)).max(initial=0.0)
    if off > tol:
        raise InputError(f"{name}: expected a rotation part that is orthonormal with det +1, "
                         f"found one off by {off:.3g}")
    if np.any(np.linalg.det(R) < 0):
        raise InputError(f"{name}: expected a rotation part with det +1, found a reflection "
                         f"(det -1)")
    if np.abs(T[..., 3, :] - (0.0, 0.0, 0.0, 1.0)).max(initial=0.0) > tol:
        raise InputError(f"{name}: expected last row (0, 0, 0, 1), found another")
    return T


# --- building and taking apart ----------------------------------------------------------------

def transform(R: ArrayLike | None = None, p: ArrayLike | None = None) -> NDArray:
    """Homogeneous transform from a rotation and a translation.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3), optional
        Rotation; identity if omitted.
    p : array_like, shape (..., 3), optional
        Translation (m); zero if omitted.

    Returns
    -------
    T : ndarray, shape (..., 4, 4)
        Leading shape broadcast from R and p.
    """
    R = np.eye(3) if R is None else np.asarray(R, dtype=float)
    p = np.zeros(3) if p is None else np.asarray(p, dtype=float)
    lead = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    T = np.zeros(lead + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def translation(p: ArrayLike) -> NDArray:
    """Pure translation, shape (..., 4, 4), for p of shape (..., 3) in m."""
    return transform(p=p)


def _axis_rotation(angle: ArrayLike, i: int, j: int) -> NDArray:
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    R[..., i, i] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    R[..., j, j] = c
    R[..., 3 - i - j, 3 - i - j] = 1.0
    return R


def rotx(angle: ArrayLike) -> NDArray:
    """Rotation about x by `angle` (rad), shape (..., 3, 3)."""
    return _axis_rotation(angle, 1, 2)


def roty(angle: ArrayLike) -> NDArray:
    """Rotation about y by `angle` (rad), shape (..., 3, 3)."""
    return _axis_rotation(angle, 2, 0)


def rotz(angle: ArrayLike) -> NDArray:
    """Rotation about z by `angle` (rad), shape (..., 3, 3)."""
    return _axis_rotation(angle, 0, 1)


def invert(T: ArrayLike) -> NDArray:
    """Inverse of rigid transforms, shape (..., 4, 4): ``T_b_a`` from ``T_a_b``."""
    T = np.asarray(T, dtype=float)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    return transform(Rt, -(Rt @ T[..., :3, 3, None])[..., 0])


def skew(v: ArrayLike) -> NDArray:
    """Cross-product matrix ``[v]`` with ``[v] @ u == cross(v, u)``, shape (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    S = np.zeros(v.shape + (3,))
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    S[..., 0, 1], S[..., 0, 2] = -z, y
    S[..., 1, 0], S[..., 1, 2] = z, -x
    S[..., 2, 0], S[..., 2, 1] = -y, x
    return S


# --- rotation parametrisations: roll-pitch-yaw here, quaternions through scipy's Rotation -------

def _from_scipy(rot, lead: tuple[int, ...]) -> NDArray:
    return rot.as_matrix().reshape(lead + (3, 3))


def _to_scipy(R: ArrayLike):
    from scipy.spatial.transform import Rotation

    R = np.asarray(R, dtype=float)
    return Rotation.from_matrix(R.reshape(-1, 3, 3)), R.shape[:-2]


def rpy_to_matrix(rpy: ArrayLike, *, degrees: bool = False) -> NDArray:
    """Rotation from roll, pitch, yaw: ``Rz(y) @ Ry(p) @ Rx(r)``; rpy (..., 3) -> (..., 3, 3).

    Example
    -------
    >>> rpy_to_matrix([0.0, 0.0, np.pi / 2]).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    rpy = np.asarray(rpy, dtype=float)
    if degrees:
        rpy = np.deg2rad(rpy)
    return rotz(rpy[..., 2]) @ roty(rpy[..., 1]) @ rotx(rpy[..., 0])


def matrix_to_rpy(R: ArrayLike, *, degrees: bool = False) -> NDArray:
    """Roll, pitch, yaw of rotations (..., 3, 3) -> (..., 3); pitch in [-pi/2, pi/2].

    Pitch is ``atan2(-R[2, 0], hypot(R[2, 1], R[2, 2]))``, accurate at every angle (an arcsine
    loses half the digits near +-pi/2); yaw is ``atan2(R[1, 0], R[0, 0])``, and roll is read
    from ``Rz(-yaw) @ R``, so that the three angles rebuild R to rounding error even where roll
    and yaw alone are ill-conditioned. Within `GIMBAL_LOCK` of +-pi/2 only roll -+ yaw is
    defined: yaw is set to zero and roll carries it, as scipy's ``as_euler("xyz")`` does.

    Example
    -------
    >>> matrix_to_rpy(rpy_to_matrix([0.1, -0.2, 0.3])).round(15) + 0.0
    array([ 0.1, -0.2,  0.3])
    """
    R = np.asarray(R, dtype=float)
    cos_pitch = np.hypot(R[..., 2, 1], R[..., 2, 2])
    yaw = np.where(cos_pitch <= GIMBAL_LOCK, 0.0, np.arctan2(R[..., 1, 0], R[..., 0, 0]))
    cy, sy = np.cos(yaw), np.sin(yaw)
    rpy = np.empty(R.shape[:-2] + (3,))
    rpy[..., 0] = np.arctan2(sy * R[..., 0, 2] - cy * R[..., 1, 2],
                             cy * R[..., 1, 1] - sy * R[..., 0, 1])
    rpy[..., 1] = np.arctan2(-R[..., 2, 0], cos_pitch)
    rpy[..., 2] = yaw
    return np.rad2deg(rpy) if degrees else rpy


def quat_to_matrix(quat: ArrayLike, *, scalar_first: bool = False) -> NDArray:
    """Rotation from unit quaternions (..., 4), ``(x, y, z, w)`` by default -> (..., 3, 3)."""
    from scipy.spatial.transform import Rotation

    quat = np.asarray(quat, dtype=float)
    return _from_scipy(Rotation.from_quat(quat.reshape(-1, 4), scalar_first=scalar_first),
                       quat.shape[:-1])


def matrix_to_quat(R: ArrayLike, *, scalar_first: bool = False) -> NDArray:
    """Unit quaternions (..., 4) of rotations (..., 3, 3), with a non-negative scalar part."""
    rot, lead = _to_scipy(R)
    return rot.as_quat(canonical=True, scalar_first=scalar_first).reshape(lead + (4,))


def exp_so3(rotvec: ArrayLike) -> NDArray:
    """Rotation from a rotation vector (axis times angle, rad): (..., 3) -> (..., 3, 3).

    Rodrigues' formula ``I + sin(t)/t [w] + (1 - cos t)/t^2 [w]^2``, ``t = |w|``, with the
    Taylor series of both factors at small t.
    """
    w = np.asarray(rotvec, dtype=float)
    t = np.linalg.norm(w, axis=-1)[..., None, None]
    W = skew(w)
    a = _series(t, lambda t: np.sin(t) / t, lambda t: 1.0 - t**2 / 6)
    b = _series(t, lambda t: 2 * (np.sin(t / 2) / t) ** 2, lambda t: 0.5 - t**2 / 24)
    return np.eye(3) + a * W + b * (W @ W)


def _vee_and_angle(R: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """``vee(R - R^T)`` (..., 3) (twice the sine times the axis), the cosine and the angle."""
    s = np.stack([R[..., 2, 1] - R[..., 1, 2],
                  R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    return s, c, np.arctan2(0.5 * np.linalg.norm(s, axis=-1), c)


def rotation_angle(R: ArrayLike) -> NDArray:
    """Angle (rad, in [0, pi]) of rotations (..., 3, 3): the length of `log_so3`.

    Uses ``atan2(|vee(R - R^T)| / 2, (trace - 1) / 2)``: accurate at every angle, unlike
    ``arccos`` of the trace, which loses half the digits near 0 (a 1e-9 rad error reads as 0).

    Example
    -------
    >>> float(rotation_angle(rotx(1e-9)))
    1e-09
    """
    return _vee_and_angle(np.asarray(R, dtype=float))[2]


def log_so3(R: ArrayLike) -> NDArray:
    """Rotation vector (..., 3) of rotations (..., 3, 3); angle in [0, pi].

    The angle is `rotation_angle`'s. Up to pi/2 the axis is ``vee(R - R^T)`` scaled by
    ``angle / (2 sin angle)`` (its series below 1e-6 rad); past pi/2, where that skew part
    shrinks towards zero, it is the largest column of ``(R + R^T)/2 - cos(angle) I``, which
    equals ``(1 - cos angle) a a^T`` for the unit axis a, signed by the skew part. Both stay
    accurate to rounding over their range.

    Example
    -------
    >>> log_so3(rotz(0.5)).round(12) + 0.0
    array([0. , 0. , 0.5])
    """
    R = np.asarray(R, dtype=float)
    s, c, angle = _vee_and_angle(R)
    sine = 0.5 * np.linalg.norm(s, axis=-1)
    wide = angle > 0.5 * np.pi
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(angle < 1e-6, 0.5 * (1.0 + angle * angle / 6.0), angle / (2.0 * sine))
        w = f[..., None] * s
    if np.any(wide):
        B = 0.5 * (R[wide] + np.swapaxes(R[wide], -1, -2)) - c[wide][:, None, None] * np.eye(3)
        k = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        v = np.take_along_axis(B, k[:, None, None], axis=-1)[..., 0]     # column k
        sign = np.where(np.einsum("...i,...i", v, s[wide]) >= 0.0, 1.0, -1.0)
        w[wide] = (sign * angle[wide] / np.linalg.norm(v, axis=-1))[:, None] * v
    return w


def pose_from_xyz_rpy(xyz: ArrayLike, rpy: ArrayLike, *, degrees: bool = False) -> NDArray:
    """Transform (..., 4, 4) from a position (..., 3) in m and roll-pitch-yaw (..., 3)."""
    return transform(rpy_to_matrix(rpy, degrees=degrees), xyz)


# --- twists: exponential and logarithm on SE(3) --------------------------------------------------

def _series(theta: NDArray, exact, taylor) -> NDArray:
    """exact(theta) where theta is not small, its Taylor expansion where it is (no 0/0)."""
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    return np.where(small, taylor(theta), exact(safe))


def exp_se3(twist: ArrayLike) -> NDArray:
    """Transform from a twist ``(v, w)`` (unit time): (..., 6) -> (..., 4, 4).

    ``exp([v, w]) = [[exp([w]), V v], [0, 1]]`` with
    ``V = I + (1 - cos t)/t^2 [w] + (t - sin t)/t^3 [w]^2``, ``t = |w|``.
    """
    twist = np.asarray(twist, dtype=float)
    v, w = twist[..., :3], twist[..., 3:]
    t = np.linalg.norm(w, axis=-1)[..., None, None]
    W = skew(w)
    b = _series(t, lambda t: 2 * (np.sin(t / 2) / t) ** 2, lambda t: 0.5 - t**2 / 24)
    c = _series(t, lambda t: (t - np.sin(t)) / t**3, lambda t: 1 / 6 - t**2 / 120)
    V = np.eye(3) + b * W + c * (W @ W)
    return transform(exp_so3(w), (V @ v[..., None])[..., 0])


def log_se3(T: ArrayLike) -> NDArray:
    """Twist ``(v, w)`` (..., 6) with ``exp_se3(twist) == T``, rotation angle in [0, pi].

    ``v = V^-1 p`` with ``V^-1 = I - [w]/2 + (1/t^2)(1 - (t/2) cot(t/2)) [w]^2``; the half-angle
    cotangent avoids dividing by ``1 - cos t``, which has lost most of its digits at small t.
    """
    T = np.asarray(T, dtype=float)
    w = log_so3(T[..., :3, :3])
    t = np.linalg.norm(w, axis=-1)[..., None, None]
    W = skew(w)
    d = _series(t, lambda t: (1 - (t / 2) / np.tan(t / 2)) / t**2, lambda t: 1 / 12 + t**2 / 720)
    Vinv = np.eye(3) - 0.5 * W + d * (W @ W)
    v = (Vinv @ T[..., :3, 3, None])[..., 0]
    return np.concatenate([v, w], axis=-1)


def adjoint(T: ArrayLike) -> NDArray:
    """Adjoint (..., 6, 6) of transforms (..., 4, 4), for twists ordered ``(v, w)``.

    ``twist_a = adjoint(T_a_b) @ twist_b`` with ``Ad = [[R, [p] R], [0, R]]``.
    """
    T = np.asarray(T, dtype=float)
    R, p = T[..., :3, :3], T[..., :3, 3]
    Ad = np.zeros(T.shape[:-2] + (6, 6))
    Ad[..., :3, :3] = R
    Ad[..., 3:, 3:] = R
    Ad[..., :3, 3:] = skew(p) @ R
    return Ad


def pose_error(T_a: ArrayLike, T_b: ArrayLike) -> tuple[NDArray, NDArray]:
    """Distance between poses: position error (m) and rotation angle (rad), each (...,).

    Parameters
    ----------
    T_a, T_b : array_like, shape (..., 4, 4)
        Poses in one frame; leading shapes broadcast.
    """
    T_a, T_b = np.asarray(T_a, dtype=float), np.asarray(T_b, dtype=float)
    dp = np.linalg.norm(T_a[..., :3, 3] - T_b[..., :3, 3], axis=-1)
    dR = np.swapaxes(T_a[..., :3, :3], -1, -2) @ T_b[..., :3, :3]
    return dp, rotation_angle(dR)
