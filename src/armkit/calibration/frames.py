"""Frames: points and poses a camera (or any sensor) measures, mapped into the robot's base.

A camera is mounted one of three ways, all held by a `CameraMount`:

- ``fixed``: a fixed ``T_base_camera`` (the modular-arm paper's stereo camera, or a LiDAR);
- ``eye_to_hand``: a hand-eye result for a fixed camera, X = T_base_camera;
- ``eye_in_hand``: a hand-eye result for a camera on the gripper, X = T_gripper_camera, so the
  robot's pose at the moment of the measurement (``T_base_gripper``) is needed too.

``points_to_base(mount, p)`` and ``poses_to_base(mount, T)`` do the mapping; with a hand-eye
result's covariance, ``point_covariance_in_base`` carries its uncertainty along.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.calibration.handeye import HandEyeResult
from armkit.errors import InputError
from armkit.model.chain import freeze
from armkit.spatial import as_array, as_transform, skew

MountKind = Literal["fixed", "eye_to_hand", "eye_in_hand"]


@dataclass(frozen=True)
class CameraMount:
    """Where a camera sits: a fixed camera-to-base transform or a hand-eye result.

    Parameters
    ----------
    kind : {"fixed", "eye_to_hand", "eye_in_hand"}
    T : array_like, shape (4, 4)
        ``T_base_camera`` (fixed, eye_to_hand) or ``T_gripper_camera`` (eye_in_hand), m.
    covariance : array_like, shape (6, 6), optional
        Of T's small rotation (rad, about T's own axes) then translation (m); None if unknown.
    """

    kind: MountKind
    T: NDArray
    covariance: NDArray | None = None

    def __post_init__(self):
        if self.kind not in ("fixed", "eye_to_hand", "eye_in_hand"):
            raise InputError(f"mount kind: expected fixed, eye_to_hand or eye_in_hand, found "
                             f"{self.kind!r}")
        object.__setattr__(self, "T", as_transform(self.T, "T"))
        if self.T.shape != (4, 4):
            raise InputError(f"T: expected shape (4, 4), found {self.T.shape}")
        if self.covariance is not None:
            cov = as_array(self.covariance, "covariance", (6, 6))
            if cov.shape != (6, 6):
                raise InputError(f"covariance: expected shape (6, 6), found {cov.shape}")
            object.__setattr__(self, "covariance", cov)
        freeze(self, "T", "covariance")


def camera_mount(source: ArrayLike | HandEyeResult | CameraMount) -> CameraMount:
    """A `CameraMount` from a fixed ``T_base_camera`` (4, 4), a hand-eye result, or a mount.

    Raises
    ------
    InputError
        If the hand-eye result was refused (it has no X), or the transform is not rigid.
    """
    if isinstance(source, CameraMount):
        return source
    if isinstance(source, HandEyeResult):
        if not source.success:
            raise InputError(f"hand-eye result: expected a solved one, found a refusal "
                             f"({source.reason})")
        cov = source.covariance if np.all(np.isfinite(source.covariance)) else None
        return CameraMount(source.mode, source.X, cov)
    return CameraMount("fixed", source)


def camera_to_base(mount: ArrayLike | HandEyeResult | CameraMount,
                   T_base_gripper: ArrayLike | None = None) -> NDArray:
    """``T_base_camera`` (..., 4, 4) of a mount; an eye-in-hand camera needs the robot's
    ``T_base_gripper`` (..., 4, 4) when the camera measured.

    Raises
    ------
    InputError
        If an eye-in-hand camera has no gripper pose, or a fixed one is given one.
    """
    mount = camera_mount(mount)
    if mount.kind == "eye_in_hand":
        if T_base_gripper is None:
            raise InputError("T_base_gripper: expected the robot's pose when the camera "
                             "measured (the camera is on the gripper), found none")
        return as_transform(T_base_gripper, "T_base_gripper") @ mount.T
    if T_base_gripper is not None:
        raise InputError(f"T_base_gripper: expected none for a {mount.kind} camera (it does not "
                         f"move with the gripper), found one")
    return np.array(mount.T)


def points_to_base(mount: ArrayLike | HandEyeResult | CameraMount, points: ArrayLike,
                   T_base_gripper: ArrayLike | None = None) -> NDArray:
    """Points (..., 3) measured in the camera (sensor) frame, in the robot's base frame, m.

    Parameters
    ----------
    mount : CameraMount, HandEyeResult or array_like (4, 4)
        A bare (4, 4) array is a fixed ``T_base_camera``.
    points : array_like, shape (..., 3)
        In the camera frame, m.
    T_base_gripper : array_like, shape (4, 4), optional
        The robot's pose at the measurement; only for an eye-in-hand camera.

    Returns
    -------
    ndarray, shape (..., 3)

    Example
    -------
    >>> points_to_base(np.eye(4), [0.1, 0.2, 0.3])
    array([0.1, 0.2, 0.3])
    """
    T = camera_to_base(mount, T_base_gripper)
    p = as_array(points, "points", (3,))
    return p @ T[:3, :3].T + T[:3, 3]


def poses_to_base(mount: ArrayLike | HandEyeResult | CameraMount, T_camera_object: ArrayLike,
                  T_base_gripper: ArrayLike | None = None) -> NDArray:
    """Poses (..., 4, 4) measured in the camera frame, in the base frame:
    ``T_base_object = T_base_camera @ T_camera_object``."""
    T = camera_to_base(mount, T_base_gripper)
    return T @ as_transform(T_camera_object, "T_camera_object")


def point_covariance_in_base(mount: ArrayLike | HandEyeResult | CameraMount, points: ArrayLike,
                             T_base_gripper: ArrayLike | None = None) -> NDArray:
    """Covariance (..., 3, 3) in m^2 of camera points mapped to the base, from the mount's.

    A point p measured exactly in the camera frame lands at ``T (exp(d_rot) p + d_p)``; to
    first order its base position moves by ``R_base_camera (-[p]x d_rot + d_p)``. Zero when
    the mount has no covariance (a fixed transform is taken as exact).
    """
    mount = camera_mount(mount)
    T = camera_to_base(mount, T_base_gripper)
    p = as_array(points, "points", (3,))
    if mount.covariance is None:
        return np.zeros(p.shape + (3,))
    J = np.concatenate([-skew(p), np.broadcast_to(np.eye(3), p.shape + (3,))], axis=-1)
    J = T[:3, :3] @ J                                  # (..., 3, 6)
    return J @ mount.covariance @ np.swapaxes(J, -1, -2)
