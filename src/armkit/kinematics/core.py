"""The kinematic core: the packed chain's layout and the one forward kinematics of armkit.

Everything that needs a pose of a configuration (FK, link frames, Jacobians, IK, the collision
checker, dynamics) walks the chain with the compiled steps of this module, on one packed form.

A chain reaches the kernels as `KernelChain`: joint i turns about (or slides along) z of the
frame ``pre @ M_1 @ links[0] @ ... @ links[i-1]``, with M the joint's motion, packed in one
float and one int array (`KernelChain.floats`, `KernelChain.ints`; F and I in the kernels).
For ``nj`` moving joints (mimic joints included), the fields are read through the named
accessors below, never by hand-computed offsets:

=============================  ============================================================
``joint_count(I)``             nj
``I[i]`` (`joint_kind`)        0 revolute, 1 prismatic
``joint_value(q, F, I, nj, i)``  the joint's motion ``scale * q[source] + offset`` (rad or m)
``pre_at(nj)``                 where the 12 numbers of ``pre`` (3 x 4, row by row) start in F
``link_at(nj, i)``             where those of link i (joint i's motion to joint i+1's) start
=============================  ============================================================

A pose travels as 12 scalars (rotation rows and position): `pose_start`, `move` (the joint's
motion), `then` (a constant link), `store_pose`. A kernel that needs the frames of the chain
(collision, dynamics) writes its own loop over the joints with these steps.
`pose_one` and `frames_one` carry a pose as 12 scalars (rotation rows and position) so that the
whole product stays in registers; `pose_jacobian_one` keeps it in its output's rows (less code
to compile for the first IK call, as fast). The batch loops come twice, serial and parallel, and
`run` picks one by the batch's size and the idle cores (`armkit.threads`).

Compilation is lazy (no explicit signatures, which would compile every kernel, the parallel ones
included, when this module is imported): a call compiles only the kernels it runs, one
configuration from Python calls a `_one` kernel directly, and a call with little work runs the
kernels as Python until compiling pays (`armkit.jit`); a batch of poses runs `pose_one`'s
arithmetic as NumPy over the whole batch instead (`_poses_numpy`). The small helpers are
inlined into their callers at numba's IR level, which saves a separate compilation (and cache
file) for each of them.

benchmarks/fk.py measures these against a vectorised NumPy chain, roboticstoolbox's C++ code and
pinocchio; benchmarks/startup.py measures what the first call costs.
"""

from __future__ import annotations

import math

import numpy as np

from armkit.jit import kernel, numba_threads, prange
from armkit.threads import threads_for

_jit = kernel(cache=True, nogil=True)
_inline = kernel(inline="always")
_pjit = kernel(cache=True, nogil=True, parallel=True)

LIGHT_CONFIGURATIONS = 1024     # a batch run as Python before its kernel is compiled (about
#                                 50 us a configuration: `armkit.jit`)
LIGHT_POSES = 100_000           # a batch of poses run in NumPy (`_poses_numpy`, about 1.5 us a
#                                 configuration) before its kernel is compiled
GRAIN = 4096        # samples worth starting a thread for (benchmarks/fk.py: below this, the
#                     start-up of a second thread costs more than the half batch it takes)


@_inline
def joint_count(I):
    """nj, the moving joints of the packed chain."""
    return I.shape[0] // 2


@_inline
def joint_kind(I, i):
    """0 if moving joint i is revolute, 1 if prismatic."""
    return I[i]


@_inline
def joint_value(q, F, I, nj, i):
    """Moving joint i's motion at the joint values q: ``scale * q[source] + offset``."""
    return F[nj + i] * q[I[nj + i]] + F[i]


@_inline
def joint_source(I, nj, i):
    """The index in q of the value that drives moving joint i (its leader's, for a mimic)."""
    return I[nj + i]


@_inline
def joint_scale(F, nj, i):
    """d(motion of moving joint i) / d(its value in q): 1, or a mimic joint's multiplier."""
    return F[nj + i]


@_inline
def pre_at(nj):
    """Index in F of ``pre``'s 12 numbers (base to joint 1's motion)."""
    return 2 * nj


@_inline
def link_at(nj, i):
    """Index in F of link i's 12 numbers (joint i's motion to joint i+1's; the last ends at the
    tool)."""
    return 2 * nj + 12 + 12 * i


@_inline
def pose_start(F, at):
    """The top three rows of the transform at F[at:at + 12] as the 12-scalar pose."""
    return (F[at], F[at + 1], F[at + 2], F[at + 3],
            F[at + 4], F[at + 5], F[at + 6], F[at + 7],
            F[at + 8], F[at + 9], F[at + 10], F[at + 11])


@_inline
def turn(T, c, s):
    """T @ Rz(theta), given c = cos(theta) and s = sin(theta)."""
    r00, r01, r02, p0, r10, r11, r12, p1, r20, r21, r22, p2 = T
    return (c * r00 + s * r01, c * r01 - s * r00, r02, p0,
            c * r10 + s * r11, c * r11 - s * r10, r12, p1,
            c * r20 + s * r21, c * r21 - s * r20, r22, p2)


@_inline
def slide(T, value):
    """T @ Tz(value)."""
    r00, r01, r02, p0, r10, r11, r12, p1, r20, r21, r22, p2 = T
    return (r00, r01, r02, p0 + value * r02,
            r10, r11, r12, p1 + value * r12,
            r20, r21, r22, p2 + value * r22)


@_inline
def move(T, kind, value):
    """T @ Rz(value) for a revolute joint, T @ Tz(value) for a prismatic one."""
    if kind == 0:
        return turn(T, math.cos(value), math.sin(value))
    return slide(T, value)


@_inline
def then(T, F, at):
    """T @ C for the constant rigid transform C whose top three rows are F[at:at + 12]."""
    r00, r01, r02, p0, r10, r11, r12, p1, r20, r21, r22, p2 = T
    return (r00 * F[at] + r01 * F[at + 4] + r02 * F[at + 8],
            r00 * F[at + 1] + r01 * F[at + 5] + r02 * F[at + 9],
            r00 * F[at + 2] + r01 * F[at + 6] + r02 * F[at + 10],
            r00 * F[at + 3] + r01 * F[at + 7] + r02 * F[at + 11] + p0,
            r10 * F[at] + r11 * F[at + 4] + r12 * F[at + 8],
            r10 * F[at + 1] + r11 * F[at + 5] + r12 * F[at + 9],
            r10 * F[at + 2] + r11 * F[at + 6] + r12 * F[at + 10],
            r10 * F[at + 3] + r11 * F[at + 7] + r12 * F[at + 11] + p1,
            r20 * F[at] + r21 * F[at + 4] + r22 * F[at + 8],
            r20 * F[at + 1] + r21 * F[at + 5] + r22 * F[at + 9],
            r20 * F[at + 2] + r21 * F[at + 6] + r22 * F[at + 10],
            r20 * F[at + 3] + r21 * F[at + 7] + r22 * F[at + 11] + p2)


@_inline
def store_pose(T, out):
    """Write the 12-scalar pose T into out (4, 4)."""
    for k in range(12):
        out[k // 4, k % 4] = T[k]
    out[3, 0] = 0.0
    out[3, 1] = 0.0
    out[3, 2] = 0.0
    out[3, 3] = 1.0


@_jit
def pose_one(q, F, I, out):
    """Tool pose of one configuration q (n,) into out (4, 4); False if q is not finite.
    F, I: the chain packed (`KernelChain.floats`, `KernelChain.ints`)."""
    nj = joint_count(I)
    T = pose_start(F, pre_at(nj))
    finite = True
    for i in range(nj):
        v = joint_value(q, F, I, nj, i)
        finite &= math.isfinite(v)
        T = then(move(T, joint_kind(I, i), v), F, link_at(nj, i))
    store_pose(T, out)
    return finite


@_jit
def frames_one(q, F, I, joint_frames, out):
    """Joint frames after each motion (n_joints, 4, 4) (z is the joint axis) and the tool
    pose."""
    nj = joint_count(I)
    T = pose_start(F, pre_at(nj))
    for i in range(nj):
        T = move(T, joint_kind(I, i), joint_value(q, F, I, nj, i))
        store_pose(T, joint_frames[i])
        T = then(T, F, link_at(nj, i))
    store_pose(T, out)


@_inline
def axes_to_columns(axes, I, n, px, py, pz):
    """Turn the joint origins o_i (rows 0-2) and axes z_i (rows 3-5) held in axes (6, n) into
    the Jacobian's columns for the tool origin p: ``(z_i x (p - o_i), z_i)`` for a revolute
    joint, ``(z_i, 0)`` for a prismatic one."""
    for i in range(n):
        zx, zy, zz = axes[3, i], axes[4, i], axes[5, i]
        if joint_kind(I, i) == 0:
            dx, dy, dz = px - axes[0, i], py - axes[1, i], pz - axes[2, i]
            axes[0, i] = zy * dz - zz * dy
            axes[1, i] = zz * dx - zx * dz
            axes[2, i] = zx * dy - zy * dx
        else:
            axes[0, i], axes[1, i], axes[2, i] = zx, zy, zz
            axes[3, i], axes[4, i], axes[5, i] = 0.0, 0.0, 0.0


@_jit
def jacobian_one(q, F, I, J):
    """Geometric Jacobian (6, n), base frame, of one configuration q (n,) into J, for a chain
    without mimic joints (moving joint i is column i); False if q is not finite. The same
    products as `pose_jacobian_one`, with the pose in 12 scalars and no pose written."""
    nj = joint_count(I)
    T = pose_start(F, pre_at(nj))
    finite = True
    for i in range(nj):
        value = joint_value(q, F, I, nj, i)
        finite &= math.isfinite(value)
        T = move(T, joint_kind(I, i), value)
        J[0, i], J[1, i], J[2, i] = T[3], T[7], T[11]          # o_i, for now
        J[3, i], J[4, i], J[5, i] = T[2], T[6], T[10]          # z_i
        T = then(T, F, link_at(nj, i))
    axes_to_columns(J, I, nj, T[3], T[7], T[11])
    return finite


@_jit
def pose_jacobian_one(q, F, I, out, J):
    """Tool pose into out (4, 4) and the geometric Jacobian (6, n), base frame, into J.

    Column of moving joint i: revolute ``(z_i x (p - o_i), z_i)``, prismatic ``(z_i, 0)``;
    z_i the joint axis, o_i a point on it, p the tool origin; a mimic joint's column is added,
    times its multiplier, to its leader's. Returns False if q is not finite.
    """
    n = joint_count(I)
    coupled = n != J.shape[1]
    for i in range(n):
        coupled |= joint_source(I, n, i) != i or joint_scale(F, n, i) != 1.0
    # Joint origins and axes in J's columns (or in scratch, when mimic joints share columns).
    axes = np.empty((6, n)) if coupled else J
    # The running pose is out's top three rows, updated row by row with `_move`'s and `_then`'s
    # products in their order (the same results): a loop over rows is a third of the code that
    # the 12-scalar form inlines, and this kernel is compiled by the first jacobian and IK call.
    for r in range(3):
        for c in range(4):
            out[r, c] = F[pre_at(n) + 4 * r + c]
    finite = True
    for i in range(n):
        value = joint_value(q, F, I, n, i)
        finite &= math.isfinite(value)
        if joint_kind(I, i) == 0:
            c, s = math.cos(value), math.sin(value)
            for r in range(3):
                a, b = out[r, 0], out[r, 1]
                out[r, 0] = c * a + s * b
                out[r, 1] = c * b - s * a
        else:
            for r in range(3):
                out[r, 3] = out[r, 3] + value * out[r, 2]
        lk = link_at(n, i)
        for r in range(3):
            axes[r, i] = out[r, 3]                                      # o_i, for now
            axes[3 + r, i] = out[r, 2]                                  # z_i
            a, b, d, p = out[r, 0], out[r, 1], out[r, 2], out[r, 3]
            out[r, 0] = a * F[lk] + b * F[lk + 4] + d * F[lk + 8]
            out[r, 1] = a * F[lk + 1] + b * F[lk + 5] + d * F[lk + 9]
            out[r, 2] = a * F[lk + 2] + b * F[lk + 6] + d * F[lk + 10]
            out[r, 3] = a * F[lk + 3] + b * F[lk + 7] + d * F[lk + 11] + p
    axes_to_columns(axes, I, n, out[0, 3], out[1, 3], out[2, 3])
    if coupled:
        J[:, :] = 0.0
        for i in range(n):
            for r in range(6):
                J[r, joint_source(I, n, i)] += joint_scale(F, n, i) * axes[r, i]
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0
    return finite


# --- batch loops: Q (N, n) -> outputs with leading N ------------------------------------------

def _poses_numpy(Q, F, I, out):
    """`poses` over the whole batch at once: `pose_one`'s products in their order on arrays of
    N, the cosines and sines from `math` as the kernel's (the same bits)."""
    nj, N = joint_count(I), Q.shape[0]
    T = pose_start(F, pre_at(nj))
    for i in range(nj):
        value = joint_scale(F, nj, i) * Q[:, joint_source(I, nj, i)] + F[i]
        if joint_kind(I, i) == 0:
            # math's cosine of inf raises where numba's is NaN: give it NaN.
            value = np.where(np.isinf(value), np.nan, value)
            T = turn(T, np.fromiter(map(math.cos, value), float, N),
                      np.fromiter(map(math.sin, value), float, N))
        else:
            T = slide(T, value)
        T = then(T, F, link_at(nj, i))
    for k in range(12):
        out[:, k // 4, k % 4] = T[k]
    out[:, 3] = (0.0, 0.0, 0.0, 1.0)


@kernel(cache=True, nogil=True, python=_poses_numpy)
def poses(Q, F, I, out):
    for k in range(Q.shape[0]):
        pose_one(Q[k], F, I, out[k])


@_pjit
def poses_parallel(Q, F, I, out):
    for k in prange(Q.shape[0]):
        pose_one(Q[k], F, I, out[k])


@_jit
def frames(Q, F, I, joint_frames, out):
    for k in range(Q.shape[0]):
        frames_one(Q[k], F, I, joint_frames[k], out[k])


@_pjit
def frames_parallel(Q, F, I, joint_frames, out):
    for k in prange(Q.shape[0]):
        frames_one(Q[k], F, I, joint_frames[k], out[k])


@_jit
def pose_jacobians(Q, F, I, out, J):
    for k in range(Q.shape[0]):
        pose_jacobian_one(Q[k], F, I, out[k], J[k])


@_pjit
def pose_jacobians_parallel(Q, F, I, out, J):
    for k in prange(Q.shape[0]):
        pose_jacobian_one(Q[k], F, I, out[k], J[k])


def run(serial, parallel, Q: np.ndarray, *args, few: int = LIGHT_CONFIGURATIONS) -> None:
    """Call the serial batch loop, or the parallel one on as many threads as the batch's size
    and the idle cores are worth (`armkit.threads.threads_for`); up to `few` samples run light
    (`armkit.jit`) while the serial loop is not compiled, whatever the threads."""
    threads = threads_for(Q.shape[0], GRAIN)
    if threads == 1 or (Q.shape[0] <= few and not serial.is_compiled):
        serial.sized(Q.shape[0], Q, *args, few=few)
        return
    with numba_threads(threads):
        parallel(Q, *args)
