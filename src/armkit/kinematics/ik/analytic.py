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
``T(q) = exp([S_1] q_1) ... exp([S_n] q_n) T_home`` (Murray, Li and Sastry, ch. 3.3). Each
family is one numba kernel over a batch of targets, one target at a time in scalar code (3-vectors
as tuples, nothing allocated), so one target costs what one iteration of the batch costs: the
family's branches (a branch without a real solution is NaN), then each branch folded into the
joint limits, checked by forward kinematics against the target, and marked real, reached,
inside the limits, and distinct from the earlier reaching branches. What the family needs of the
chain (axes, points, the inverse home pose, ...) is computed once by `family_of` and kept in
`Family.geometry`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.jit import FEW, kernel
from armkit.kinematics import core
from armkit.kinematics.ik.masks import mask_forms, task_errors_one
from armkit.model.chain import Chain
from armkit.threads import in_ranges, threads_for

PARALLEL = 1e-9          # |w_i x w_j| below this: parallel axes
MEET = 1e-9              # distance (m) below this: intersecting axes
ACOS_SLACK = 1e-9        # |cos| up to 1 + this is rounding at a boundary, clipped to 1
SAME = 1e-9              # branches closer than this in every joint are one solution
TARGETS_PER_THREAD = 128  # a thread is worth its start from this many targets (about 5 us each)

# error_model="numpy": a division by zero gives inf or NaN (a branch without a solution), as
# in NumPy, instead of raising. Compilation on an empty cache is what these kernels cost most
# (BENCHMARKS.md, start-up): one cached kernel per family, so a robot compiles only its own;
# `_helper` for what is called from many places (compiled once, no Python wrapper, since only
# kernels call it); `_inline` for what is called from one place (inlined at numba's IR level:
# one compilation fewer; inlining the many-place helpers too would copy their IR at every call
# site and cost more to compile, measured).
_jit = kernel(cache=True, nogil=True, error_model="numpy")
_inline = kernel(inline="always", error_model="numpy")
_helper = kernel(nogil=True, error_model="numpy", no_cpython_wrapper=True,
                     no_cfunc_wrapper=True)


# --- 3-vectors as tuples ----------------------------------------------------------------------

@_helper
def _vec(a):
    """A 3-vector (a row of a family's geometry) as a tuple."""
    return (a[0], a[1], a[2])


@_helper
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@_helper
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@_helper
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@_helper
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@_helper
def _scaled(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


@_helper
def _perp(w, v):
    """The part of v normal to the unit axis w."""
    return _sub(v, _scaled(w, _dot(w, v)))


@_helper
def _rotate(w, theta, v):
    """v turned about the unit axis w by theta (Rodrigues)."""
    c, s = math.cos(theta), math.sin(theta)
    k = _dot(w, v) * (1.0 - c)
    x = _cross(w, v)
    return (v[0] * c + x[0] * s + w[0] * k, v[1] * c + x[1] * s + w[1] * k,
            v[2] * c + x[2] * s + w[2] * k)


@_helper
def _screw(w, r, theta, x):
    """Point x moved by the rotation theta about the line through r along w."""
    return _add(_rotate(w, theta, _sub(x, r)), r)


@_helper
def _turned(T, v):
    """The rotation of a pose T (4, 4) applied to v."""
    return (T[0, 0] * v[0] + T[0, 1] * v[1] + T[0, 2] * v[2],
            T[1, 0] * v[0] + T[1, 1] * v[1] + T[1, 2] * v[2],
            T[2, 0] * v[0] + T[2, 1] * v[1] + T[2, 2] * v[2])


@_helper
def _columns(R, v):
    """R v for a rotation R given as its three columns."""
    return (R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
            R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
            R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2])


@_helper
def _acos(x):
    """arccos, with rounding just past +-1 clipped and real misses (no solution) NaN."""
    if x > 1.0:
        return 0.0 if x <= 1.0 + ACOS_SLACK else math.nan
    if x < -1.0:
        return math.pi if x >= -1.0 - ACOS_SLACK else math.nan
    return math.acos(x)


# --- the subproblems --------------------------------------------------------------------------

@_helper
def _sp1(w, u, v):
    """Paden-Kahan 1: theta with ``Rot(w, theta) u = v`` (vectors relative to the axis).

    Uses the parts of u and v normal to w; where either vanishes (to 1e-9 of |u|) any theta
    works and 0 is given, rather than the angle of two round-off vectors.
    """
    a, b = _perp(w, u), _perp(w, v)
    scale = max(1e-18 * _dot(u, u), 1e-300)             # squared: 1e-9 of |u|
    if _dot(a, a) < scale or _dot(b, b) < scale:
        return 0.0
    return math.atan2(_dot(w, _cross(a, b)), _dot(a, b))


@_helper
def _sp3(w, u, v, delta):
    """Paden-Kahan 3: the two theta with ``|Rot(w, theta) u - v| = delta``, NaN if none."""
    a, b = _perp(w, u), _perp(w, v)
    along = _dot(w, _sub(u, v))
    d2 = delta * delta - along * along
    na, nb = math.sqrt(_dot(a, a)), math.sqrt(_dot(b, b))
    theta0 = math.atan2(_dot(w, _cross(a, b)), _dot(a, b))
    spread = _acos((na * na + nb * nb - d2) / (2.0 * na * nb))
    return theta0 - spread, theta0 + spread


@_helper
def _sp4(w, a, b, c):
    """The two theta with ``a . Rot(w, theta) b = c``, NaN if none:
    ``a . Rot b = (a.w)(w.b) + cos(theta) a.b_perp + sin(theta) a.(w x b_perp)``."""
    bp = _perp(w, b)
    A, B = _dot(a, bp), _dot(a, _cross(w, bp))
    spread = _acos((c - _dot(a, w) * _dot(w, b)) / math.sqrt(A * A + B * B))
    base = math.atan2(B, A)
    return base - spread, base + spread


@_helper
def _sp2(w1, w2, u, v):
    """Paden-Kahan 2: (theta1, theta2) with ``Rot(w1, t1) Rot(w2, t2) u = v``, axes meeting at
    the origin of u and v; two branches: t1 of each, then t2 of each, NaN if none."""
    c12 = _dot(w1, w2)
    den = c12 * c12 - 1.0
    alpha = (c12 * _dot(w2, u) - _dot(w1, v)) / den
    beta = (c12 * _dot(w1, v) - _dot(w2, u)) / den
    n = _cross(w1, w2)
    uu = _dot(u, u)
    g2 = (uu - alpha * alpha - beta * beta - 2.0 * alpha * beta * c12) / _dot(n, n)
    if not g2 > -ACOS_SLACK * max(uu, 1e-300):
        g2 = math.nan
    elif g2 < 0.0:
        g2 = 0.0
    root = math.sqrt(g2)
    base = _add(_scaled(w1, alpha), _scaled(w2, beta))
    z0, z1 = _sub(base, _scaled(n, root)), _add(base, _scaled(n, root))
    return _sp1(w1, z0, v), _sp1(w1, z1, v), _sp1(w2, u, z0), _sp1(w2, u, z1)


@_inline
def _planar_2r(wa, ra, wb, rb, p, x):
    """Angles of two parallel axes a then b taking point p (home) to x, two elbows:
    ta of each, then tb of each.

    Solves ``Rot_a(ta) Rot_b(tb) p = x`` in the plane normal to the axes: tb makes the distance
    from axis a right (subproblem 3), then ta turns it into place (subproblem 1).
    """
    d = _perp(wa, _sub(x, ra))
    tb0, tb1 = _sp3(wb, _perp(wb, _sub(p, rb)), _perp(wb, _sub(ra, rb)),
                    math.sqrt(_dot(d, d)))
    xa = _sub(x, ra)
    ta0 = _sp1(wa, _sub(_screw(wb, rb, tb0, p), ra), xa)
    ta1 = _sp1(wa, _sub(_screw(wb, rb, tb1, p), ra), xa)
    return ta0, ta1, tb0, tb1


@_inline
def _home_undone(g, T):
    """g = T @ inv(T_home) for a family whose geometry rows 12-15 hold inv(T_home) (rotation
    columns, then position): the rotation as three columns, and the position."""
    R = (_turned(T, _vec(g[12])), _turned(T, _vec(g[13])), _turned(T, _vec(g[14])))
    return R, _add(_turned(T, _vec(g[15])), (T[0, 3], T[1, 3], T[2, 3]))


# --- the families: one target T (4, 4) -> branches q (K, n) -----------------------------------

@_inline
def _lift_swing_one(g, T, q):
    """Lift along a and three swings about axes along a: 2 branches.

    Rows: 0 a, 1 the lift's direction, 2-3 axis and point of swing 1, 4-5 of swing 2, 6 the
    point of swing 3, 7 the home tool point, 8 inv(R_home) u, 9 u (normal to a), 10 the swings'
    signs along a, 11 joint indices (lift, swing 1, swing 2), 12 (swing 3, -, -).
    """
    a, wp, t0, u, sign = _vec(g[0]), _vec(g[1]), _vec(g[7]), _vec(g[9]), _vec(g[10])
    x_t = (T[0, 3], T[1, 3], T[2, 3])
    lift = _dot(a, _sub(x_t, t0)) / _dot(a, wp)        # swings keep the height along a
    x = _sub(x_t, _scaled(wp, lift))
    phi = _sp1(a, u, _turned(T, _vec(g[8])))            # total turn about a, from orientation
    c3 = _sub(x, _rotate(a, phi, _sub(t0, _vec(g[6]))))  # where the third swing axis must be
    t1a, t1b, t2a, t2b = _planar_2r(_vec(g[2]), _vec(g[3]), _vec(g[4]), _vec(g[5]),
                                    _vec(g[6]), c3)
    p, i1, i2, i3 = int(g[11, 0]), int(g[11, 1]), int(g[11, 2]), int(g[12, 0])
    for k in range(2):
        t1, t2 = (t1a, t2a) if k == 0 else (t1b, t2b)
        q[k, p], q[k, i1], q[k, i2] = lift, t1, t2
        q[k, i3] = sign[2] * (phi - sign[0] * t1 - sign[1] * t2)


@_inline
def _yaw_pitch_one(g, T, q):
    """Base yaw and three parallel pitch joints: 4 branches (base angle, then elbow).

    Rows: 0-3 axes, 4-7 points, 8 the home tool point, 9 the home pointing axis, 10 the pitch
    joints' signs along axis 2, 11 (pointing axis index, -, -).
    """
    w0, n0, r0, r3, t0 = _vec(g[0]), _vec(g[1]), _vec(g[4]), _vec(g[7]), _vec(g[8])
    sign = _vec(g[10])
    k = int(g[11, 0])
    x_t = (T[0, 3], T[1, 3], T[2, 3])
    pointing = (T[0, k], T[1, k], T[2, k])
    # The tool point's height along the pitch axes is fixed by the base angle alone.
    t1a, t1b = _sp4(w0, _sub(x_t, r0), n0, _dot(n0, _sub(t0, r0)))
    for i in range(2):
        t1 = t1a if i == 0 else t1b
        x = _add(_rotate(w0, -t1, _sub(x_t, r0)), r0)     # the base turn undone
        phi = _sp1(n0, _vec(g[9]), _rotate(w0, -t1, pointing))      # pitch sum
        x4 = _sub(x, _rotate(n0, phi, _sub(t0, r3)))       # where the last pitch axis must be
        t2a, t2b, t3a, t3b = _planar_2r(n0, _vec(g[5]), _vec(g[2]), _vec(g[6]), r3, x4)
        for e in range(2):
            t2, t3 = (t2a, t3a) if e == 0 else (t2b, t3b)
            b = 2 * i + e
            q[b, 0], q[b, 1], q[b, 2] = t1, t2, t3
            q[b, 3] = sign[2] * (phi - sign[0] * t2 - sign[1] * t3)


@_inline
def _parallel_wrist_one(g, T, q):
    """Axes 2-4 parallel, axes 5 and 6 meeting: 8 branches (base, wrist, elbow).

    Rows: 0-5 axes, 6-11 points, 12-15 inv(T_home), 16 where axes 5 and 6 meet, 17 a unit
    vector normal to axis 2, 18 the signs of axes 2-4 along axis 2.
    """
    w0, n0, w2, w4, w5 = _vec(g[0]), _vec(g[1]), _vec(g[2]), _vec(g[4]), _vec(g[5])
    r0, r1, r2, r3, r4, r5 = (_vec(g[6]), _vec(g[7]), _vec(g[8]), _vec(g[9]), _vec(g[10]),
                              _vec(g[11]))
    c0, e, sign = _vec(g[16]), _vec(g[17]), _vec(g[18])
    G, gp = _home_undone(g, T)                          # exp(S1 q1) ... exp(S6 q6)
    x_t = _add(_columns(G, c0), gp)
    # Joints 2-4 keep every point's height along their axes: that fixes the base angle.
    t1a, t1b = _sp4(w0, _sub(x_t, r0), n0, _dot(n0, _sub(c0, r0)))
    for i in range(2):
        t1 = t1a if i == 0 else t1b
        # Rotation of exp(S2 q2) ... exp(S6 q6): joint 1 undone.
        Rg = (_rotate(w0, -t1, G[0]), _rotate(w0, -t1, G[1]), _rotate(w0, -t1, G[2]))
        # Axis 6's direction against the pitch axes fixes joint 5 (two ways).
        t5a, t5b = _sp4(w4, n0, w5, _dot(n0, _columns(Rg, w5)))
        u = (_dot(Rg[0], n0), _dot(Rg[1], n0), _dot(Rg[2], n0))
        for j in range(2):
            t5 = t5a if j == 0 else t5b
            t6 = _sp1(w5, u, _rotate(w4, -t5, n0))
            phi = _sp1(n0, e, _columns(Rg, _rotate(w5, -t6, _rotate(w4, -t5, e))))  # pitch sum
            # Where the point r4 on axis 4 must go: undo joints 6 and 5, apply g, undo joint 1.
            y = _screw(w5, r5, -t6, _screw(w4, r4, -t5, r3))
            y = _add(_columns(G, y), gp)
            x4 = _add(_rotate(w0, -t1, _sub(y, r0)), r0)
            t2a, t2b, t3a, t3b = _planar_2r(n0, r1, w2, r2, r3, x4)
            for k in range(2):
                t2, t3 = (t2a, t3a) if k == 0 else (t2b, t3b)
                b = 4 * i + 2 * j + k
                q[b, 0], q[b, 1], q[b, 2] = t1, t2, t3
                q[b, 3] = sign[2] * (phi - sign[0] * t2 - sign[1] * t3)
                q[b, 4], q[b, 5] = t5, t6


@_helper
def _arm_undone(g, G, gp, t1, t2, q3, prismatic, p):
    """g applied to point p, then joints 1, 2 and 3 of a spherical-wrist arm undone."""
    w0, w1, w2, s = _vec(g[0]), _vec(g[1]), _vec(g[2]), _vec(g[16])
    z = _add(_columns(G, p), gp)
    z = _screw(w1, s, -t2, _screw(w0, s, -t1, z))
    if prismatic:
        return _sub(z, _scaled(w2, q3))
    return _screw(w2, _vec(g[8]), -q3, z)


@_inline
def _spherical_wrist_one(g, T, q):
    """Axes 1 and 2 meeting, axes 4-6 meeting in one point: 8 branches (elbow, shoulder,
    wrist).

    Rows: 0-5 axes, 6-11 points, 12-15 inv(T_home), 16 where axes 1 and 2 meet, 17 the wrist
    centre, 18 a unit vector normal to axis 6, 19 (1 if joint 3 is prismatic, -, -).
    """
    w2, w3, w4, w5 = _vec(g[2]), _vec(g[3]), _vec(g[4]), _vec(g[5])
    s, c0, e = _vec(g[16]), _vec(g[17]), _vec(g[18])
    prismatic = g[19, 0] != 0.0
    G, gp = _home_undone(g, T)
    x_t = _add(_columns(G, c0), gp)
    d = _sub(x_t, s)
    delta = math.sqrt(_dot(d, d))                       # kept by joints 1 and 2
    if prismatic:                                       # |c0 + q w2 - s| = delta: a quadratic
        cs = _sub(c0, s)
        b = _dot(w2, cs)
        disc = b * b - (_dot(cs, cs) - delta * delta)
        root = math.sqrt(disc) if disc >= 0.0 else math.nan
        q3a, q3b = -b - root, -b + root
    else:
        r2 = _vec(g[8])
        q3a, q3b = _sp3(w2, _sub(c0, r2), _sub(s, r2), delta)
    for k in range(2):
        q3 = q3a if k == 0 else q3b
        y = _add(c0, _scaled(w2, q3)) if prismatic else _screw(w2, _vec(g[8]), q3, c0)
        t1a, t1b, t2a, t2b = _sp2(_vec(g[0]), _vec(g[1]), _sub(y, s), d)
        for m in range(2):
            t1, t2 = (t1a, t2a) if m == 0 else (t1b, t2b)
            axis6 = _sub(_arm_undone(g, G, gp, t1, t2, q3, prismatic, _add(c0, w5)), c0)
            t4a, t4b, t5a, t5b = _sp2(w3, w4, w5, axis6)
            side = _arm_undone(g, G, gp, t1, t2, q3, prismatic, _add(c0, e))
            for n in range(2):
                t4, t5 = (t4a, t5a) if n == 0 else (t4b, t5b)
                z = _screw(w4, c0, -t5, _screw(w3, c0, -t4, side))
                b = 4 * k + 2 * m + n
                q[b, 0], q[b, 1], q[b, 2] = t1, t2, q3
                q[b, 3], q[b, 4], q[b, 5] = t4, t5, _sp1(w5, e, _sub(z, c0))


# --- every branch checked: folded into the limits, FK, errors, distinct --------------------------

@_inline
def _fold(v, lower, upper, ref):
    """A revolute angle wrapped to [-pi, pi), then moved by whole turns into [lower, upper]
    nearest ref (the turn nearest ref and its two neighbours: ranges up to four turns); left
    as it is when none of them is inside."""
    turn = 2.0 * math.pi
    v = (v + math.pi) % turn - math.pi
    nearest = v + turn * np.rint((ref - v) / turn)
    best, gap = v, math.inf
    for shift in (0.0, -turn, turn):
        c = nearest + shift
        if lower <= c <= upper and abs(c - ref) < gap:
            best, gap = c, abs(c - ref)
    return best


@_inline
def _check(q, T, q_ref, limits, chain, mask, tol, errors, flags, pose):
    """Branches q (K, n) of target T folded in place; errors (K, 2) position and rotation by
    FK; flags (K, 4): real, reached (within tol under the mask), inside the limits, and valid
    (reached and not equal to an earlier valid branch). chain: the `KernelChain` packed
    (floats, ints)."""
    F, I = chain
    K, n = q.shape
    for b in range(K):
        real = True
        for j in range(n):
            real &= math.isfinite(q[b, j])
        inside = True
        for j in range(n):
            v = q[b, j] if real else 0.0
            if limits[2, j] != 0.0:
                v = _fold(v, limits[0, j], limits[1, j], q_ref[j])
            q[b, j] = v
            inside &= limits[0, j] - 1e-12 <= v <= limits[1, j] + 1e-12
        core.pose_one(q[b], F, I, pose)
        pe, re = task_errors_one(pose, T, mask)
        errors[b, 0], errors[b, 1] = pe, re
        reached = real and pe < tol[0] and re < tol[1]
        valid = reached
        for c in range(b):
            if valid and flags[c, 3]:
                same = True
                for j in range(n):
                    same &= abs(q[b, j] - q[c, j]) <= SAME
                valid = not same
        flags[b, 0], flags[b, 1], flags[b, 2], flags[b, 3] = real, reached, inside, valid


@_jit
def _lift_swing(g, targets, q_ref, limits, chain, mask, tol, q, errors, flags):
    pose = np.empty((4, 4))
    for i in range(targets.shape[0]):
        _lift_swing_one(g, targets[i], q[i])
        _check(q[i], targets[i], q_ref[i], limits, chain, mask, tol, errors[i], flags[i], pose)


@_jit
def _yaw_pitch(g, targets, q_ref, limits, chain, mask, tol, q, errors, flags):
    pose = np.empty((4, 4))
    for i in range(targets.shape[0]):
        _yaw_pitch_one(g, targets[i], q[i])
        _check(q[i], targets[i], q_ref[i], limits, chain, mask, tol, errors[i], flags[i], pose)


@_jit
def _parallel_wrist(g, targets, q_ref, limits, chain, mask, tol, q, errors, flags):
    pose = np.empty((4, 4))
    for i in range(targets.shape[0]):
        _parallel_wrist_one(g, targets[i], q[i])
        _check(q[i], targets[i], q_ref[i], limits, chain, mask, tol, errors[i], flags[i], pose)


@_jit
def _spherical_wrist(g, targets, q_ref, limits, chain, mask, tol, q, errors, flags):
    pose = np.empty((4, 4))
    for i in range(targets.shape[0]):
        _spherical_wrist_one(g, targets[i], q[i])
        _check(q[i], targets[i], q_ref[i], limits, chain, mask, tol, errors[i], flags[i], pose)


# --- recognising a family ---------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Family:
    """A closed-form solver recognised in a chain.

    name; mask: the task its solutions satisfy exactly; branches: K, the solutions it gives
    per target (some NaN where they do not exist); geometry (G, 3): what its kernel needs of
    the chain, computed once; kernel: the numba kernel of the family (see `candidates`);
    limits (3, n): lower, upper and 1.0 for a revolute joint, as the kernel takes them.
    """

    name: str
    mask: tuple[int, ...]
    branches: int
    geometry: NDArray
    kernel: object
    limits: NDArray


# Recognition runs once per solver, in plain Python on 3-tuples (for a handful of vectors
# several times cheaper than NumPy's calls on tiny arrays).

def _axes(chain: Chain) -> tuple[list, list]:
    """Joint axis directions (the translation direction of a prismatic joint) and points."""
    w = [tuple(S[3:]) if revolute else tuple(S[:3])
         for S, revolute in zip(chain.screws.tolist(), chain.revolute.tolist())]
    return w, [tuple(p) for p in chain.points.tolist()]


def _dot3(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _sub3(a, b) -> tuple[float, float, float]:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _axpy3(s, a, b) -> tuple[float, float, float]:
    """s a + b."""
    return (s * a[0] + b[0], s * a[1] + b[1], s * a[2] + b[2])


def _cross3(a, b) -> tuple[float, float, float]:
    """Cross product of two 3-vectors as floats (cheaper than NumPy for one pair)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _parallel(a, b) -> bool:
    """|a x b| < PARALLEL (the cross product written out: called a dozen times per robot)."""
    return math.hypot(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0]) < PARALLEL


def _line_distance(w1, r1, w2, r2) -> float:
    n, d = _cross3(w1, w2), _sub3(r2, r1)
    if math.hypot(*n) < PARALLEL:
        return math.hypot(*_cross3(d, w1))
    return abs(_dot3(n, d)) / math.hypot(*n)


def _meeting_point(w1, r1, w2, r2) -> tuple[float, float, float]:
    """The point where two intersecting, non-parallel lines meet:
    r1 + s w1 with s = ((r2 - r1) x w2) . (w1 x w2) / |w1 x w2|^2."""
    n = _cross3(w1, w2)
    return _axpy3(_dot3(_cross3(_sub3(r2, r1), w2), n) / _dot3(n, n), w1, r1)


def _normal_to(a) -> tuple[float, float, float]:
    """A unit vector normal to a (unit, 3)."""
    x, y, z = abs(a[0]), abs(a[1]), abs(a[2])
    k = (0 if x <= z else 2) if x <= y else (1 if y <= z else 2)     # min's first smallest
    v = _axpy3(-a[k], a, ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))[k])
    return _axpy3(1.0 / math.hypot(*v) - 1.0, v, v)


def _home(chain: Chain) -> tuple[list, tuple]:
    """T_home's rotation as rows, and its position."""
    (a, b, c, x), (d, e, f, y), (g, h, i, z), _ = chain.T_home.tolist()
    return [(a, b, c), (d, e, f), (g, h, i)], (x, y, z)


def _pointing_axis(chain: Chain, w, r) -> int:
    """The tool axis a yaw-and-pitch arm points: the one along its last link (else normal to
    the pitch axes)."""
    R, t0 = _home(chain)
    link = _sub3(t0, r[3])
    link = _axpy3(-_dot3(w[1], link), w[1], link)
    columns = list(zip(*R))
    if math.hypot(*link) > MEET:
        return max(range(3), key=lambda k: abs(_dot3(columns[k], link)))
    return min(range(3), key=lambda k: abs(_dot3(columns[k], w[1])))


def _rotation_flags(k: int, pointing: bool) -> tuple[int, ...]:
    """Mask flags for a rotation about tool axis k, or for pointing tool axis k."""
    flags = [0, 0, 0] if not pointing else [1, 1, 1]
    flags[k] = 0 if pointing else 1
    return (1, 1, 1, *flags)


def _family(chain: Chain, name: str, mask: tuple[int, ...], branches: int, rows: list,
            kernel) -> Family:
    # One flat list and one concatenation: NumPy builds a (G, 3) array from nested tuples
    # several times slower.
    geometry = np.array([x for row in rows for x in row], dtype=float).reshape(-1, 3)
    limits = np.concatenate((chain.lower, chain.upper, chain.revolute)).reshape(3, -1)
    geometry.setflags(write=False)
    limits.setflags(write=False)
    return Family(name, mask, branches, geometry, kernel, limits)


def _home_inverse(chain: Chain) -> list:
    """inv(T_home) as four rows: its rotation's columns (the home rotation's rows), then its
    position."""
    R, (x, y, z) = _home(chain)
    (a, b, c), (d, e, f), (g, h, i) = R
    return [*R, (-(a * x + d * y + g * z), -(b * x + e * y + h * z), -(c * x + f * y + i * z))]


def family_of(chain: Chain) -> Family | None:
    """The closed-form family of a chain, or None (then only the numeric solvers apply).

    `armkit.kinematics.ik.IKSolver` asks once and keeps the answer. A chain with mimic joints
    has none.
    """
    if chain.coupled:
        return None
    w, r = _axes(chain)
    n, rev = chain.n, chain.revolute.tolist()
    meet = lambda i, j: (not _parallel(w[i], w[j])                   # noqa: E731
                         and _line_distance(w[i], r[i], w[j], r[j]) < MEET)
    along = lambda i: _dot3(w[i], w[1])                               # noqa: E731
    if n == 4 and sum(rev) == 3 and all(_parallel(w[i], w[0]) for i in range(4)):
        p = rev.index(False)
        i1, i2, i3 = (i for i in range(4) if rev[i])
        a = w[i1]
        u = _normal_to(a)
        R, t0 = _home(chain)
        rows = [a, w[p], w[i1], r[i1], w[i2], r[i2], r[i3], t0,
                tuple(_dot3(column, u) for column in zip(*R)), u,
                tuple(_dot3(w[i], a) for i in (i1, i2, i3)), (p, i1, i2), (i3, 0, 0)]
        k = max(range(3), key=lambda k: abs(_dot3(tuple(row[k] for row in R), a)))
        return _family(chain, "lift_swing", _rotation_flags(k, pointing=False), 2, rows,
                       _lift_swing)
    if (n == 4 and all(rev) and _parallel(w[1], w[2]) and _parallel(w[1], w[3])
            and not _parallel(w[0], w[1])):
        k = _pointing_axis(chain, w, r)
        R, t0 = _home(chain)
        rows = [*w, *r, t0, tuple(row[k] for row in R), (along(1), along(2), along(3)),
                (k, 0, 0)]
        return _family(chain, "yaw_pitch", _rotation_flags(k, pointing=True), 4, rows,
                       _yaw_pitch)
    if n != 6:
        return None
    if (all(rev) and _parallel(w[1], w[2]) and _parallel(w[1], w[3])
            and not _parallel(w[0], w[1]) and meet(4, 5) and not _parallel(w[4], w[1])):
        rows = [*w, *r, *_home_inverse(chain), _meeting_point(w[4], r[4], w[5], r[5]),
                _normal_to(w[1]), (along(1), along(2), along(3))]
        return _family(chain, "parallel_wrist", (1,) * 6, 8, rows, _parallel_wrist)
    if all(rev[i] for i in (0, 1, 3, 4, 5)) and meet(0, 1) and meet(3, 4) and \
            not _parallel(w[4], w[5]):
        centre = _meeting_point(w[3], r[3], w[4], r[4])
        if math.hypot(*_cross3(_sub3(centre, r[5]), w[5])) < MEET:
            rows = [*w, *r, *_home_inverse(chain), _meeting_point(w[0], r[0], w[1], r[1]),
                    centre, _normal_to(w[5]), (0.0 if rev[2] else 1.0, 0, 0)]
            return _family(chain, "spherical_wrist", (1,) * 6, 8, rows, _spherical_wrist)
    return None


def _owned(a: NDArray) -> NDArray:
    """a as a C-ordered, writable float array (what the kernels were compiled for), copied
    only if it is not one already."""
    if a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=float, order="C")


def candidates(chain: Chain, family: Family, targets: NDArray, q_ref: NDArray, mask: NDArray,
               tol_position: float, tol_rotation: float, threads: int | None = None):
    """Every branch of the family's closed form for targets (N, 4, 4), checked.

    Parameters
    ----------
    q_ref : ndarray, shape (N, n)
        Revolute angles are moved by whole turns into the limits nearest these.
    mask : ndarray of bool, (6,)
        The task the errors measure.
    tol_position, tol_rotation : float
        m and rad: a branch within both reaches its target.
    threads : int, optional
        Most threads a large batch may use (default: `armkit.threads`' choice).

    Returns
    -------
    q : ndarray, (N, K, n)
        The branches folded into the limits (zeros, folded, where a branch has no real
        solution).
    errors : ndarray, (N, K, 2)
        Position (m) and rotation (rad) error of each branch by forward kinematics.
    flags : ndarray of bool, (N, K, 4)
        real (the branch exists), reached (within the tolerances), inside (the joint limits),
        valid (reached, and distinct from the earlier valid branches: one solution each).
    """
    N, K, n = targets.shape[0], family.branches, chain.n
    q = np.empty((N, K, n))
    errors = np.empty((N, K, 2))
    flags = np.empty((N, K, 4), dtype=np.bool_)
    k = chain.kernel
    targets, q_ref = _owned(targets), _owned(q_ref)
    args = (family.limits, (k.F, k.I), mask_forms(mask).ints,
            np.array([tol_position, tol_rotation]))
    if N <= FEW:
        family.kernel.light(family.geometry, targets, q_ref, *args, q, errors, flags)
    else:
        in_ranges(lambda a, b: family.kernel(family.geometry, targets[a:b], q_ref[a:b], *args,
                                             q[a:b], errors[a:b], flags[a:b]),
                  N, threads_for(N, TARGETS_PER_THREAD, threads))
    return q, errors, flags
