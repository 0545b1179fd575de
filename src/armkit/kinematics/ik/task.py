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

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError

_jit = numba.njit(cache=True, nogil=True)

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


@_jit
def _angle(ax, ay, az, bx, by, bz):
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)


@_jit
def task_errors_one(T, Tt, mask):
    """Position (m) and rotation (rad) error of one pose T (4, 4) against Tt (4, 4)."""
    p2 = 0.0
    for r in range(3):
        if mask[r]:
            d = Tt[r, 3] - T[r, 3]
            p2 += d * d
    count = mask[3] + mask[4] + mask[5]
    if count == 0:
        return math.sqrt(p2), 0.0
    if count == 3:
        tr = 0.0
        sx, sy, sz = 0.0, 0.0, 0.0
        # E = R^T Rt; its trace and skew part, without forming it.
        for r in range(3):
            tr += T[r, 0] * Tt[r, 0] + T[r, 1] * Tt[r, 1] + T[r, 2] * Tt[r, 2]
            sx += T[r, 2] * Tt[r, 1] - T[r, 1] * Tt[r, 2]
            sy += T[r, 0] * Tt[r, 2] - T[r, 2] * Tt[r, 0]
            sz += T[r, 1] * Tt[r, 0] - T[r, 0] * Tt[r, 1]
        return math.sqrt(p2), math.atan2(0.5 * math.sqrt(sx * sx + sy * sy + sz * sz),
                                         0.5 * (tr - 1.0))
    if count == 2:
        free = 0 if not mask[3] else (1 if not mask[4] else 2)
        return math.sqrt(p2), _angle(T[0, free], T[1, free], T[2, free],
                                     Tt[0, free], Tt[1, free], Tt[2, free])
    k = 0 if mask[3] else (1 if mask[4] else 2)
    o = (k + 1) % 3
    kx, ky, kz = T[0, k], T[1, k], T[2, k]
    da = T[0, o] * kx + T[1, o] * ky + T[2, o] * kz
    db = Tt[0, o] * kx + Tt[1, o] * ky + Tt[2, o] * kz
    return math.sqrt(p2), _angle(T[0, o] - da * kx, T[1, o] - da * ky, T[2, o] - da * kz,
                                 Tt[0, o] - db * kx, Tt[1, o] - db * ky, Tt[2, o] - db * kz)


@_jit
def _errors_batch(T, Tt, mask, position, rotation):
    for k in range(T.shape[0]):
        position[k], rotation[k] = task_errors_one(T[k], Tt[k], mask)


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
    lead = np.broadcast_shapes(T.shape[:-2], T_target.shape[:-2])
    # Copies, not broadcast views: numba wants arrays it may own.
    flat = np.broadcast_to(T, lead + (4, 4)).reshape(-1, 4, 4).copy()
    flat_target = np.broadcast_to(T_target, lead + (4, 4)).reshape(-1, 4, 4).copy()
    position, rotation = np.empty(flat.shape[0]), np.empty(flat.shape[0])
    _errors_batch(flat, flat_target, np.asarray(mask, dtype=np.int64), position, rotation)
    return position.reshape(lead), rotation.reshape(lead)
