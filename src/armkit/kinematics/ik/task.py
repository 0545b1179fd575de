"""What an IK target asks for: a task mask, and the errors that decide success.

A mask has six flags ``(x, y, z, rx, ry, rz)``. The first three select position components in the
base frame. The last three select rotations about the tool's own axes, and their count says
what the orientation error is:

- three flags: the whole rotation between tool and target (angle, rad);
- two flags: the free axis must point as the target's (angle between the two axes), the tool
  may roll about it: the pointing task of a 5-DOF arm, or a 4-DOF yaw-and-pitch arm;
- one flag, about axis k: the angle about k between the tool's other axes and the target's,
  projected onto the plane normal to k (the heading of a SCARA arm);
- none: orientation is free.

Named masks: ``"pose"`` (all six), ``"position"``, ``"position+yaw"`` (rotation about tool z),
``"position+pitch"`` (rotation about tool y), ``"position+axis"`` (the tool's x axis points
as the target's; roll about it is free).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError

NAMED_MASKS = {
    "pose": (1, 1, 1, 1, 1, 1),
    "position": (1, 1, 1, 0, 0, 0),
    "position+yaw": (1, 1, 1, 0, 0, 1),
    "position+pitch": (1, 1, 1, 0, 1, 0),
    "position+axis": (1, 1, 1, 0, 1, 1),
}


def as_mask(mask: str | ArrayLike) -> NDArray:
    """The mask as 6 booleans; raises InputError naming what was expected."""
    if isinstance(mask, str):
        if mask not in NAMED_MASKS:
            raise InputError(f"mask: expected one of {', '.join(NAMED_MASKS)} or 6 flags, "
                             f"found {mask!r}")
        return np.array(NAMED_MASKS[mask], dtype=bool)
    flags = np.asarray(mask)
    if flags.shape != (6,) or not flags.any():
        raise InputError(f"mask: expected 6 flags (x y z rx ry rz), not all zero, "
                         f"found {flags.tolist()}")
    return flags.astype(bool)


def mask_name(mask: NDArray) -> str:
    """The mask's name, or its flags as a string of 0s and 1s."""
    for name, flags in NAMED_MASKS.items():
        if tuple(mask.astype(int)) == flags:
            return name
    return "".join(str(int(f)) for f in mask)


def _angle_between(a: NDArray, b: NDArray) -> NDArray:
    """Angle (rad) between vectors (..., 3), accurate near 0 and pi (atan2 of |a x b|, a.b)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def task_errors(T: ArrayLike, T_target: ArrayLike, mask: NDArray) -> tuple[NDArray, NDArray]:
    """Position error (m) and rotation error (rad) of tool poses against targets under a mask.

    Parameters
    ----------
    T, T_target : array_like, shape (..., 4, 4)
        Reached and wanted tool poses; leading shapes broadcast.
    mask : ndarray of bool, shape (6,)

    Returns
    -------
    position_error, rotation_error : ndarray, shape (...,)
    """
    T, T_target = np.asarray(T, dtype=float), np.asarray(T_target, dtype=float)
    dp = (T_target[..., :3, 3] - T[..., :3, 3])[..., mask[:3]]
    position = np.linalg.norm(dp, axis=-1)
    R, Rt = T[..., :3, :3], T_target[..., :3, :3]
    flags = np.flatnonzero(mask[3:])
    lead = np.broadcast_shapes(R.shape[:-2], Rt.shape[:-2])
    if flags.size == 3:
        from armkit.spatial import rotation_angle
        rotation = rotation_angle(np.swapaxes(R, -1, -2) @ Rt)
    elif flags.size == 2:
        free = 3 - flags.sum()                       # the axis not flagged: 0, 1 or 2
        rotation = _angle_between(R[..., :, free], Rt[..., :, free])
    elif flags.size == 1:
        k = flags[0]
        other = (k + 1) % 3
        axis = R[..., :, k]
        a, b = R[..., :, other], Rt[..., :, other]
        a = a - np.sum(a * axis, axis=-1, keepdims=True) * axis
        b = b - np.sum(b * axis, axis=-1, keepdims=True) * axis
        rotation = _angle_between(a, b)
    else:
        rotation = np.zeros(lead)
    return np.broadcast_to(position, lead), np.broadcast_to(rotation, lead)
