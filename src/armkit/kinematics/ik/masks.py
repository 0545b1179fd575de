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

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.jit import kernel
from armkit.kinematics.core import LIGHT_CONFIGURATIONS
from armkit.model.chain import frozen_array

_jit = kernel(cache=True, nogil=True, error_model="numpy")
_inner = kernel(nogil=True, error_model="numpy")      # called by kernels only: not cached

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


@dataclass(frozen=True)
class MaskForms:
    """One mask in the forms the solvers use: flags (6,) bool, ints (6,) int64 (the kernels'
    mask), rows (m,) int64 (the task rows), all read-only, and its name (`mask_name`)."""

    flags: NDArray
    ints: NDArray
    rows: NDArray
    name: str


def _forms(flags: tuple[int, ...]) -> MaskForms:
    names = {value: name for name, value in NAMED_MASKS.items()}
    return MaskForms(frozen_array(flags, bool), frozen_array(flags, np.int64),
                     frozen_array(np.flatnonzero(flags), np.int64),
                     names.get(flags, "".join(str(f) for f in flags)))


# Every one of the 63 masks, fixed at import: a single solve looks its mask up instead of
# building small arrays (a few microseconds each, on a call of a few tens).
MASK_FORMS = {flags: _forms(flags) for flags in itertools.product((0, 1), repeat=6)
              if any(flags)}


def mask_forms(mask: NDArray) -> MaskForms:
    """The forms of a mask (6,) of booleans (`as_mask`)."""
    return MASK_FORMS[tuple(mask.tolist())]    # bools hash and compare as the keys' 0s and 1s


def mask_name(mask: NDArray) -> str:
    """The mask's name, or its flags as a string of 0s and 1s."""
    flags = tuple(int(f) for f in mask.tolist())
    forms = MASK_FORMS.get(flags)
    return forms.name if forms is not None else "".join(str(f) for f in flags)


@_inner
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


@_inner
def _log_rotation(E, out):
    """Rotation vector (3,) of the rotation E (3, 3) into out; accurate near 0 and pi."""
    sx, sy, sz = E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]
    s = 0.5 * math.sqrt(sx * sx + sy * sy + sz * sz)
    c = 0.5 * (E[0, 0] + E[1, 1] + E[2, 2] - 1.0)
    angle = math.atan2(s, c)
    if angle < 1e-6:
        f = 0.5 * (1.0 + angle * angle / 6.0)           # angle / (2 sin angle), series
        out[0], out[1], out[2] = f * sx, f * sy, f * sz
    elif angle < math.pi - 1e-6:
        f = angle / (2.0 * s)
        out[0], out[1], out[2] = f * sx, f * sy, f * sz
    else:
        # Near pi the skew part vanishes: take the axis from the diagonal of (E + I) / 2.
        k = 0
        if E[1, 1] > E[k, k]:
            k = 1
        if E[2, 2] > E[k, k]:
            k = 2
        v0, v1, v2 = E[0, k], E[1, k], E[2, k]
        if k == 0:
            v0 += 1.0
        elif k == 1:
            v1 += 1.0
        else:
            v2 += 1.0
        norm = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        sign = 1.0 if (v0 * sx + v1 * sy + v2 * sz) >= 0.0 else -1.0
        f = sign * angle / norm
        out[0], out[1], out[2] = f * v0, f * v1, f * v2


@_jit
def task_residual(T, J, Tt, mask, rows, e, A, E, w):
    """Residual e (m,) of the task and its Jacobian A (m, n), so that ``A dq = e`` is the
    Gauss-Newton step, at tool pose T (4, 4) with geometric Jacobian J (6, n, base frame).
    Returns |e|^2.

    Rows follow `rows` (the mask's flags). Position rows: ``p_target - p`` (base frame).
    Rotation rows, about the tool's own axes, are the derivatives of the very measure that
    `task_errors_one` judges, so that a solver that drives e to zero meets the tolerance:

    - three flags: ``log(R^T R_target)``;
    - two flags (free axis f, b the target's f axis in tool coordinates): the rotation that
      turns the tool's f axis onto b, ``angle * (e_f x b) / |e_f x b|``;
    - one flag about axis k (o, p the next axes, a the target's o axis in tool coordinates):
      ``atan2(a_p, a_o)``, the heading about k; its Jacobian row has the terms that couple it
      to rotations about o and p (without them a redundant arm settles where the log's k
      component vanishes but the heading does not).
    """
    n = J.shape[1]
    count = mask[3] + mask[4] + mask[5]
    for r in range(3):
        for c in range(3):
            E[r, c] = T[0, r] * Tt[0, c] + T[1, r] * Tt[1, c] + T[2, r] * Tt[2, c]
    if count == 3:
        _log_rotation(E, w)
    for i in range(rows.shape[0]):                     # positions, and R^T J_w rows as a start
        r = rows[i]
        if r < 3:
            e[i] = Tt[r, 3] - T[r, 3]
            for j in range(n):
                A[i, j] = J[r, j]
        else:
            k = r - 3
            e[i] = w[k] if count == 3 else 0.0
            for j in range(n):                          # R^T J_w: about the tool's axes
                A[i, j] = T[0, k] * J[3, j] + T[1, k] * J[4, j] + T[2, k] * J[5, j]
    if count == 2:
        f = 0 if not mask[3] else (1 if not mask[4] else 2)
        g, h = (f + 1) % 3, (f + 2) % 3
        bf, bg, bh = E[f, f], E[g, f], E[h, f]
        s = math.sqrt(bg * bg + bh * bh)
        angle = math.atan2(s, bf)
        if s > 1e-300:
            scale = jac = angle / s
            vg, vh = -bh, bg                             # e_f x b
        else:                                           # aligned, or opposite: any normal axis
            scale, jac = angle, 1.0
            vg, vh = 1.0, 0.0
        for i in range(rows.shape[0]):
            r = rows[i]
            if r >= 3:
                k = r - 3
                e[i] = scale * (vg if k == g else vh)
                bk = bg if k == g else bh
                for j in range(n):
                    Wf = T[0, f] * J[3, j] + T[1, f] * J[4, j] + T[2, f] * J[5, j]
                    A[i, j] = jac * (bf * A[i, j] - bk * Wf)
    elif count == 1:
        k = 0 if mask[3] else (1 if mask[4] else 2)
        o, p = (k + 1) % 3, (k + 2) % 3
        ak, ao, ap = E[k, o], E[o, o], E[p, o]
        r2 = ao * ao + ap * ap
        for i in range(rows.shape[0]):
            if rows[i] >= 3:
                if r2 > 1e-24:
                    e[i] = math.atan2(ap, ao)
                    c = ak / r2
                    for j in range(n):
                        Wo = T[0, o] * J[3, j] + T[1, o] * J[4, j] + T[2, o] * J[5, j]
                        Wp = T[0, p] * J[3, j] + T[1, p] * J[4, j] + T[2, p] * J[5, j]
                        A[i, j] -= c * (ao * Wo + ap * Wp)
    cost = 0.0
    for i in range(rows.shape[0]):
        cost += e[i] * e[i]
    return cost


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
    _errors_batch.sized(flat.shape[0], flat, flat_target, np.asarray(mask, dtype=np.int64),
                        position, rotation, few=LIGHT_CONFIGURATIONS)
    return position.reshape(lead), rotation.reshape(lead)
