"""The dynamics kernels, written on the kinematic core (`armkit.kinematics.core`).

Each kernel walks the chain with the core's pose steps (`pose_start`, `move`, `then`) on the
robot's packed floats D (`armkit.model.inertia.KernelInertia.floats`, which continue the
chain's F) and ints I, so the link poses are those of the one forward kinematics. The
recursions run in the base (world) frame, with spatial vectors taken at its origin
(Featherstone, "Rigid Body Dynamics Algorithms", 2008, ch. 5: the recursive Newton-Euler
algorithm in absolute coordinates; ch. 6: the composite rigid body algorithm):

- joint i's motion subspace ``S_i = (z_i, p_i x z_i)`` for a revolute joint with axis z_i
  through p_i, ``(0, z_i)`` for a prismatic one (angular part first);
- body i's spatial inertia at the origin, from its 10 parameters in joint frame i, rotated
  and shifted there: mass m, first moment h = m c and rotational inertia I_O;
- in these coordinates a body's force passes to its parent unchanged, so the backward pass of
  RNEA is a running sum and the composite inertia of CRBA a sum of parameters.

A mimic joint moves with ``scale * q[source]``: its velocity and acceleration are scaled
likewise, and its torque (or mass-matrix entries) are added, times the scale, to its
leader's. Armature adds ``armature * qdd`` per joint value, friction ``viscous * qd +
coulomb * sign(qd)``.

Vectors travel as 3-tuples of scalars, which numba keeps in registers. The batch loops come
serial and parallel, run by `armkit.kinematics.core.run`. Inverse dynamics runs in the joint
frames instead, with the chain's links (`rnea_one`). benchmarks/dynamics.py measures
these against Pinocchio and roboticstoolbox-python.
"""

from __future__ import annotations

import math

import numpy as np

from armkit.jit import kernel, prange
from armkit.kinematics.core import (joint_count, joint_kind, joint_scale, joint_source,
                                    joint_value, link_at, move, pose_start, pre_at, then)

_jit = kernel(cache=True, nogil=True)
_inline = kernel(inline="always")
_pjit = kernel(cache=True, nogil=True, parallel=True)

BODY = 10       # floats per body: m, m c (3), I about the joint frame's origin (xx yy zz xy xz yz)


# --- the packed inertias' fields -------------------------------------------------------------

@_inline
def value_count(D, nj):
    """n, the joint values (D holds 3 floats of armature and friction per value at its end)."""
    return (D.shape[0] - 24 * nj - 15) // 3


@_inline
def gravity_at(nj):
    """Index in D of gravity (3, m/s^2, base frame): right after the chain's floats, where a
    link after the last one would start."""
    return link_at(nj, nj)


@_inline
def body_at(nj, i):
    """Index in D of body i's 10 parameters (in the kernel's joint frame i)."""
    return link_at(nj, nj) + 3 + BODY * i


@_inline
def armature_at(nj, n, k):
    """Index in D of joint value k's armature (kg m^2 or kg)."""
    return 24 * nj + 15 + k


@_inline
def viscous_at(nj, n, k):
    """Index in D of joint value k's viscous friction coefficient."""
    return 24 * nj + 15 + n + k


@_inline
def coulomb_at(nj, n, k):
    """Index in D of joint value k's Coulomb friction."""
    return 24 * nj + 15 + 2 * n + k


# --- small vector algebra on 3-tuples ----------------------------------------------------------

@_inline
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@_inline
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@_inline
def scaled(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


@_inline
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@_inline
def symmetric_times(J, w):
    """J @ w for the symmetric J given as (xx, yy, zz, xy, xz, yz)."""
    return (J[0] * w[0] + J[3] * w[1] + J[4] * w[2],
            J[3] * w[0] + J[1] * w[1] + J[5] * w[2],
            J[4] * w[0] + J[5] * w[1] + J[2] * w[2])


@_inline
def axis_of(T, kind):
    """Joint i's motion subspace in the base frame at its origin, (angular, linear), from its
    frame T after the motion (12-scalar pose, z the axis)."""
    z = (T[2], T[6], T[10])
    if kind == 0:
        return z, cross((T[3], T[7], T[11]), z)
    return (0.0, 0.0, 0.0), z


@_inline
def body_in_base(T, D, b):
    """Body parameters at D[b:b + 10] (joint frame T) in the base frame at its origin: mass,
    first moment h (3,) and rotational inertia I_O as (xx, yy, zz, xy, xz, yz)."""
    m = D[b]
    p = (T[3], T[7], T[11])
    # First moment about p in base axes: R (m c).
    hy = (T[0] * D[b + 1] + T[1] * D[b + 2] + T[2] * D[b + 3],
          T[4] * D[b + 1] + T[5] * D[b + 2] + T[6] * D[b + 3],
          T[8] * D[b + 1] + T[9] * D[b + 2] + T[10] * D[b + 3])
    # R J R^T, J about p in the joint frame's axes.
    jxx, jyy, jzz, jxy, jxz, jyz = D[b + 4], D[b + 5], D[b + 6], D[b + 7], D[b + 8], D[b + 9]
    a00 = T[0] * jxx + T[1] * jxy + T[2] * jxz
    a01 = T[0] * jxy + T[1] * jyy + T[2] * jyz
    a02 = T[0] * jxz + T[1] * jyz + T[2] * jzz
    a10 = T[4] * jxx + T[5] * jxy + T[6] * jxz
    a11 = T[4] * jxy + T[5] * jyy + T[6] * jyz
    a12 = T[4] * jxz + T[5] * jyz + T[6] * jzz
    a20 = T[8] * jxx + T[9] * jxy + T[10] * jxz
    a21 = T[8] * jxy + T[9] * jyy + T[10] * jyz
    a22 = T[8] * jxz + T[9] * jyz + T[10] * jzz
    # Shifted from p to the origin: + m (|p|^2 E - p p^T) + 2 (p . hy) E - (p hy^T + hy p^T).
    pp = dot(p, p)
    ph = dot(p, hy)
    xx = a00 * T[0] + a01 * T[1] + a02 * T[2] + m * (pp - p[0] * p[0]) + 2 * (ph - p[0] * hy[0])
    yy = a10 * T[4] + a11 * T[5] + a12 * T[6] + m * (pp - p[1] * p[1]) + 2 * (ph - p[1] * hy[1])
    zz = a20 * T[8] + a21 * T[9] + a22 * T[10] + m * (pp - p[2] * p[2]) + 2 * (ph - p[2] * hy[2])
    xy = a00 * T[4] + a01 * T[5] + a02 * T[6] - m * p[0] * p[1] - p[0] * hy[1] - hy[0] * p[1]
    xz = a00 * T[8] + a01 * T[9] + a02 * T[10] - m * p[0] * p[2] - p[0] * hy[2] - hy[0] * p[2]
    yz = a10 * T[8] + a11 * T[9] + a12 * T[10] - m * p[1] * p[2] - p[1] * hy[2] - hy[1] * p[2]
    return m, add(hy, scaled(p, m)), (xx, yy, zz, xy, xz, yz)


@_inline
def inertia_times(m, h, J, w, v):
    """The spatial inertia (m, h, J) at the origin times the motion (w, v): (J w + h x v,
    m v - h x w)."""
    return add(symmetric_times(J, w), cross(h, v)), add(scaled(v, m), cross(w, h))


@_inline
def force_cross(w, v, n, f):
    """The spatial cross product for forces, (w, v) x* (n, f) = (w x n + v x f, w x f)."""
    return add(cross(w, n), cross(v, f)), cross(w, f)


@_inline
def read6(row, at):
    return (row[at], row[at + 1], row[at + 2]), (row[at + 3], row[at + 4], row[at + 5])


@_inline
def write6(row, at, a, b):
    row[at], row[at + 1], row[at + 2] = a[0], a[1], a[2]
    row[at + 3], row[at + 4], row[at + 5] = b[0], b[1], b[2]


@_inline
def joint_terms(q, qd, qdd, D, nj, tau):
    """tau[k] = armature qdd + viscous qd + coulomb sign(qd), per joint value k."""
    n = q.shape[0]
    for k in range(n):
        rate = qd[k]
        sign = 1.0 if rate > 0.0 else -1.0 if rate < 0.0 else 0.0
        tau[k] = (D[armature_at(nj, n, k)] * qdd[k] + D[viscous_at(nj, n, k)] * rate
                  + D[coulomb_at(nj, n, k)] * sign)


# --- one configuration ---------------------------------------------------------------------------

@_inline
def rotation_at(D, at):
    """The rotation (9, row by row) and translation (3) of the rigid transform at D[at:at+12]."""
    return ((D[at], D[at + 1], D[at + 2], D[at + 4], D[at + 5], D[at + 6], D[at + 8],
             D[at + 9], D[at + 10]), (D[at + 3], D[at + 7], D[at + 11]))


@_inline
def times(R, v):
    """R @ v for the rotation R given row by row."""
    return (R[0] * v[0] + R[1] * v[1] + R[2] * v[2], R[3] * v[0] + R[4] * v[1] + R[5] * v[2],
            R[6] * v[0] + R[7] * v[1] + R[8] * v[2])


@_inline
def transposed_times(R, v):
    """R^T @ v for the rotation R given row by row."""
    return (R[0] * v[0] + R[3] * v[1] + R[6] * v[2], R[1] * v[0] + R[4] * v[1] + R[7] * v[2],
            R[2] * v[0] + R[5] * v[1] + R[8] * v[2])


@_inline
def turned(v, c, s):
    """Rz(theta) @ v, given c = cos(theta) and s = sin(theta)."""
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


@_inline
def unturned(v, c, s):
    """Rz(theta)^T @ v."""
    return (c * v[0] + s * v[1], c * v[1] - s * v[0], v[2])


@_jit
def rnea_one(q, qd, qdd, D, I, tau):
    """Joint torques (n,) of the motion (q, qd, qdd) into tau, gravity and joint terms
    included (recursive Newton-Euler); False if q, qd or qdd is not finite or not of the
    robot's n values (then nothing is computed). See `rnea_with`."""
    return rnea_with(q, qd, qdd, D, I, tau, np.empty((joint_count(I), 11)))


@_jit
def rnea_with(q, qd, qdd, D, I, tau, work):
    """`rnea_one` with its scratch (n_joints, 11) given (a batch loop reuses one).

    Unlike the other kernels, this one runs in the joint frames themselves (Luh, Walker and
    Paul's form): each frame's angular velocity and acceleration and its origin's linear
    acceleration go from joint to joint through the packed chain's constant links and the
    joint's motion about (along) z, a rotation about z costing four products; each body's
    force and moment about its frame's origin come from its parameters as packed, and go back
    to the base the same way. About half the products of the base-frame form.
    """
    nj = joint_count(I)
    n = value_count(D, nj)
    if q.shape[0] != n or qd.shape[0] != n or qdd.shape[0] != n or tau.shape[0] != n:
        return False
    g = gravity_at(nj)
    w, dw = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    # The base accelerates upward at -gravity: every body then feels its weight.
    a = (-D[g], -D[g + 1], -D[g + 2])
    # Per joint in `work`: the force and moment of its body (6), cos and sin of its turn (2),
    # its origin in the frame before (3).
    finite = True
    for i in range(nj):
        R, t = rotation_at(D, pre_at(nj) if i == 0 else link_at(nj, i - 1))
        value = joint_value(q, D, I, nj, i)
        source, scale = joint_source(I, nj, i), joint_scale(D, nj, i)
        rate, acc = scale * qd[source], scale * qdd[source]
        finite &= math.isfinite(value + rate + acc)
        revolute = joint_kind(I, i) == 0
        if not revolute:                        # the slide moves the origin along R's z
            t = add(t, scaled((R[2], R[5], R[8]), value))
        # The new origin's acceleration, then everything in the new frame's axes.
        a = add(a, add(cross(dw, t), cross(w, cross(w, t))))
        w, dw, a = transposed_times(R, w), transposed_times(R, dw), transposed_times(R, a)
        if revolute:
            c, s = math.cos(value), math.sin(value)
            w, dw, a = unturned(w, c, s), unturned(dw, c, s), unturned(a, c, s)
            dw = (dw[0] + w[1] * rate, dw[1] - w[0] * rate, dw[2] + acc)
            w = (w[0], w[1], w[2] + rate)
        else:
            c, s = 1.0, 0.0
            a = (a[0] + 2.0 * w[1] * rate, a[1] - 2.0 * w[0] * rate, a[2] + acc)
        # Newton and Euler about the frame's origin: h = m c, J about the origin.
        b = body_at(nj, i)
        m, h = D[b], (D[b + 1], D[b + 2], D[b + 3])
        J = (D[b + 4], D[b + 5], D[b + 6], D[b + 7], D[b + 8], D[b + 9])
        force = add(scaled(a, m), add(cross(dw, h), cross(w, cross(w, h))))
        moment = add(add(symmetric_times(J, dw), cross(w, symmetric_times(J, w))), cross(h, a))
        row = work[i]
        write6(row, 0, force, moment)
        row[6], row[7], row[8], row[9], row[10] = c, s, t[0], t[1], t[2]
    joint_terms(q, qd, qdd, D, nj, tau)
    # Backward: what bodies i..nj-1 need, about frame i's origin, in its axes.
    f, moment = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for i in range(nj - 1, -1, -1):
        row = work[i]
        own_force, own_moment = read6(row, 0)
        f, moment = add(f, own_force), add(moment, own_moment)
        along = moment[2] if joint_kind(I, i) == 0 else f[2]
        tau[joint_source(I, nj, i)] += joint_scale(D, nj, i) * along
        if i > 0:                               # into the frame before joint i
            R, _ = rotation_at(D, link_at(nj, i - 1))
            c, s, t = row[6], row[7], (row[8], row[9], row[10])
            f = times(R, turned(f, c, s))
            moment = add(times(R, turned(moment, c, s)), cross(t, f))
    return finite


@_jit
def mass_one(q, D, I, M):
    """Joint-space mass matrix (n, n) at q into M, armature included (composite rigid body
    algorithm); False if q is not finite or not of the robot's n values (then nothing is
    computed)."""
    return mass_with(q, D, I, M, np.empty((joint_count(I), 16)))


@_jit
def mass_with(q, D, I, M, work):
    """`mass_one` with its scratch (n_joints, 16) given: per body S (6), then its 10
    parameters in the base frame."""
    nj = joint_count(I)
    n = value_count(D, nj)
    if q.shape[0] != n or M.shape[0] != n or M.shape[1] != n:
        return False
    T = pose_start(D, pre_at(nj))
    finite = True
    for i in range(nj):
        value = joint_value(q, D, I, nj, i)
        finite &= math.isfinite(value)
        T = move(T, joint_kind(I, i), value)
        sw, sv = axis_of(T, joint_kind(I, i))
        row = work[i]
        write6(row, 0, sw, sv)
        m, h, J = body_in_base(T, D, body_at(nj, i))
        row[6], row[7], row[8], row[9] = m, h[0], h[1], h[2]
        for k in range(6):
            row[10 + k] = J[k]
        T = then(T, D, link_at(nj, i))
    for a in range(n):
        for b in range(n):
            M[a, b] = 0.0
        M[a, a] = D[armature_at(nj, n, a)]
    # Composite inertia of bodies j..nj-1, summed from the tip: in base coordinates a sum of
    # parameters. M_ij = S_i . (Ic_j S_j) for i <= j.
    cm, ch, cJ = 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for j in range(nj - 1, -1, -1):
        row = work[j]
        cm += row[6]
        ch = add(ch, (row[7], row[8], row[9]))
        cJ = (cJ[0] + row[10], cJ[1] + row[11], cJ[2] + row[12], cJ[3] + row[13],
              cJ[4] + row[14], cJ[5] + row[15])
        sw, sv = read6(row, 0)
        fn, ff = inertia_times(cm, ch, cJ, sw, sv)
        b, sj = joint_source(I, nj, j), joint_scale(D, nj, j)
        for i in range(j + 1):
            aw, av = read6(work[i], 0)
            value = joint_scale(D, nj, i) * sj * (dot(aw, fn) + dot(av, ff))
            a = joint_source(I, nj, i)
            M[a, b] += value
            if i != j:
                M[b, a] += value
    return finite


@_jit
def solve_spd(M, x):
    """Solve M y = x in place (x becomes y) by Cholesky, M (n, n) symmetric positive
    definite, overwritten by its factor; False if M is not positive definite."""
    n = x.shape[0]
    for j in range(n):
        d = M[j, j]
        for k in range(j):
            d -= M[j, k] * M[j, k]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        M[j, j] = d
        for i in range(j + 1, n):
            s = M[i, j]
            for k in range(j):
                s -= M[i, k] * M[j, k]
            M[i, j] = s / d
    for i in range(n):
        s = x[i]
        for k in range(i):
            s -= M[i, k] * x[k]
        x[i] = s / M[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= M[k, i] * x[k]
        x[i] = s / M[i, i]
    return True


@_jit
def forward_one(q, qd, tau, D, I, qdd):
    """Joint accelerations (n,) under the torques tau into qdd: M(q)^-1 (tau - bias), bias
    the torques of (q, qd) at rest acceleration; False if q is not finite or M is not
    positive definite, or an array is not of the robot's n values."""
    n = value_count(D, joint_count(I))
    if q.shape[0] != n or qd.shape[0] != n or tau.shape[0] != n or qdd.shape[0] != n:
        return False
    M = np.empty((n, n))
    zero = np.zeros(n)
    finite = mass_one(q, D, I, M)
    rnea_one(q, qd, zero, D, I, qdd)
    for k in range(n):
        qdd[k] = tau[k] - qdd[k]
    return solve_spd(M, qdd) and finite


@_inline
def apply_b(m, h, J, w, v, xw, xv, sign):
    """B x for B = (v x* I - I v x + sign (I v) xbar) / 2, the body term of the Coriolis
    matrix (sign +1) or its transpose (sign -1): (I v) xbar x = x x* (I v)."""
    an, af = inertia_times(m, h, J, xw, xv)
    cn, cf = force_cross(w, v, an, af)                 # v x* (I x)
    mw, mv = cross(w, xw), add(cross(w, xv), cross(v, xw))
    dn, df = inertia_times(m, h, J, mw, mv)            # I (v x x)
    ln, lf = inertia_times(m, h, J, w, v)
    en, ef = force_cross(xw, xv, ln, lf)               # x x* (I v)
    return (scaled(add(add(cn, scaled(dn, -1.0)), scaled(en, sign)), 0.5),
            scaled(add(add(cf, scaled(df, -1.0)), scaled(ef, sign)), 0.5))


@_jit
def coriolis_matrix_one(q, qd, D, I, C):
    """The Coriolis matrix C (n, n) with C qd the Coriolis and centrifugal torques and
    dM/dt - 2 C skew-symmetric, into C; False if q is not finite.

    With v_i = J_i qd each body's velocity and I_i its spatial inertia (base frame), C =
    sum_i J_i^T (I_i dJ_i/dt + B_i J_i), B_i = (v_i x* I_i - I_i v_i x + (I_i v_i) xbar) / 2
    (Niemeyer and Slotine's body factorisation; Echeandia and Wensing, "Numerical methods to
    compute the Coriolis matrix and Christoffel symbols for rigid-body systems", 2021). In a
    serial chain, entry (j, k) sums over the bodies beyond both joints.
    """
    nj = joint_count(I)
    n = q.shape[0]
    T = pose_start(D, pre_at(nj))
    w, v = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    # Per body: S (6), dS/dt (6), velocity (6), inertia (10).
    work = np.empty((nj, 28))
    finite = True
    for i in range(nj):
        value = joint_value(q, D, I, nj, i)
        finite &= math.isfinite(value)
        T = move(T, joint_kind(I, i), value)
        sw, sv = axis_of(T, joint_kind(I, i))
        rate = joint_scale(D, nj, i) * qd[joint_source(I, nj, i)]
        w, v = add(w, scaled(sw, rate)), add(v, scaled(sv, rate))
        row = work[i]
        write6(row, 0, sw, sv)
        write6(row, 6, cross(w, sw), add(cross(w, sv), cross(v, sw)))
        write6(row, 12, w, v)
        m, h, J = body_in_base(T, D, body_at(nj, i))
        row[18], row[19], row[20], row[21] = m, h[0], h[1], h[2]
        for k in range(6):
            row[22 + k] = J[k]
        T = then(T, D, link_at(nj, i))
    # G_k = Ic_k dS_k + sum_{i >= k} B_i S_k (the column k for rows j <= k);
    # H_j = (Ic_j S_j, sum_{i >= j} B_i^T S_j) (the row j for columns k < j).
    G = np.zeros((nj, 6))
    H = np.zeros((nj, 12))
    c = np.zeros(10)
    for k in range(nj - 1, -1, -1):
        row = work[k]
        for r in range(10):
            c[r] += row[18 + r]
        m, h, J = c[0], (c[1], c[2], c[3]), (c[4], c[5], c[6], c[7], c[8], c[9])
        sw, sv = read6(row, 0)
        dw_, dv_ = read6(row, 6)
        gn, gf = inertia_times(m, h, J, dw_, dv_)
        hn, hf = inertia_times(m, h, J, sw, sv)
        tn, tf = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        for i in range(k, nj):
            body = work[i]
            bw, bv = read6(body, 12)
            bm, bh = body[18], (body[19], body[20], body[21])
            bJ = (body[22], body[23], body[24], body[25], body[26], body[27])
            xn, xf = apply_b(bm, bh, bJ, bw, bv, sw, sv, 1.0)
            gn, gf = add(gn, xn), add(gf, xf)
            yn, yf = apply_b(bm, bh, bJ, bw, bv, sw, sv, -1.0)
            tn, tf = add(tn, yn), add(tf, yf)
        write6(G[k], 0, gn, gf)
        write6(H[k], 0, hn, hf)
        write6(H[k], 6, tn, tf)
    for a in range(n):
        for b in range(n):
            C[a, b] = 0.0
    for j in range(nj):
        sw, sv = read6(work[j], 0)
        a, sj = joint_source(I, nj, j), joint_scale(D, nj, j)
        for k in range(nj):
            b, sk = joint_source(I, nj, k), joint_scale(D, nj, k)
            if j <= k:
                gn, gf = read6(G[k], 0)
                value = dot(sw, gn) + dot(sv, gf)
            else:
                hn, hf = read6(H[j], 0)
                tn, tf = read6(H[j], 6)
                dw_, dv_ = read6(work[k], 6)
                kw, kv = read6(work[k], 0)
                value = dot(hn, dw_) + dot(hf, dv_) + dot(tn, kw) + dot(tf, kv)
            C[a, b] += sj * sk * value
    return finite


# --- batch loops: Q (N, n) -> outputs with leading N ---------------------------------------------

CHUNK = 1024       # configurations of a parallel batch that share one scratch array


@_jit
def rnea(Q, QD, QDD, D, I, tau):
    work = np.empty((joint_count(I), 11))
    for k in range(Q.shape[0]):
        rnea_with(Q[k], QD[k], QDD[k], D, I, tau[k], work)


@_pjit
def rnea_parallel(Q, QD, QDD, D, I, tau):
    N = Q.shape[0]
    for c in prange((N + CHUNK - 1) // CHUNK):
        work = np.empty((joint_count(I), 11))
        for k in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            rnea_with(Q[k], QD[k], QDD[k], D, I, tau[k], work)


@_jit
def mass(Q, D, I, M):
    work = np.empty((joint_count(I), 16))
    for k in range(Q.shape[0]):
        mass_with(Q[k], D, I, M[k], work)


@_pjit
def mass_parallel(Q, D, I, M):
    N = Q.shape[0]
    for c in prange((N + CHUNK - 1) // CHUNK):
        work = np.empty((joint_count(I), 16))
        for k in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            mass_with(Q[k], D, I, M[k], work)


@_jit
def forward(Q, QD, TAU, D, I, QDD, ok):
    for k in range(Q.shape[0]):
        ok[k] = forward_one(Q[k], QD[k], TAU[k], D, I, QDD[k])


@_pjit
def forward_parallel(Q, QD, TAU, D, I, QDD, ok):
    for k in prange(Q.shape[0]):
        ok[k] = forward_one(Q[k], QD[k], TAU[k], D, I, QDD[k])


@_jit
def coriolis(Q, QD, D, I, C):
    for k in range(Q.shape[0]):
        coriolis_matrix_one(Q[k], QD[k], D, I, C[k])


@_pjit
def coriolis_parallel(Q, QD, D, I, C):
    for k in prange(Q.shape[0]):
        coriolis_matrix_one(Q[k], QD[k], D, I, C[k])
