"""The compiled collision checker: arm capsules against the scene and against each other.

Distances are exact for capsule-sphere, capsule-capsule and capsule-box (the squared distance
from a segment to a box is piecewise quadratic along the segment: minimised piece by piece);
capsule-cylinder takes the convex distance along the segment by golden-section search and
subtracts the search's Lipschitz slack, so it is a lower bound within 1e-8 m.

Certification. Between two configurations on a straight joint-space line, a point of the arm on
link j moves at most ``D = sum_i w_i |dq_i|`` over the joints i it rides on, with ``w_i`` a
bound on its distance from joint i's axis (revolute) or 1 (prismatic): `displacement_weights`.
At a checked state q the free distance ``f(q)`` (the gap to the nearest obstacle, or half the
gap between two capsules of the arm) says how far every point may move without contact. A piece
of an edge between checked states a and b is certified when ``f_a + f_b > D_ab + r``: the
largest displacement between them is taken into the clearance test, so every configuration on
it keeps at least r / 2 from every obstacle (r between capsules of the arm), not only the
checked ones. Pieces that fail the test are halved (coarse to fine), so states are dense only
near obstacles; a state with ``f <= r`` fails the edge. r is the checker's `resolution`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk_frames
from armkit.jit import kernel, numba_threads, prange
from armkit.model.chain import KernelChain
from armkit.model.robot import Robot, joint_array
from armkit.planning.geometry import ArmGeometry, arm_geometry, link_to_body
from armkit.planning.scene import BOX, CAPSULE, SPHERE, Scene, SceneKernel, scene_kernel
from armkit.threads import threads_for

_jit = kernel(cache=True, nogil=True)
# Helpers with one call site are inlined in numba's IR (a jitted callee's code is optimised
# again in each caller's module: a flat call tree compiles faster).
_inline = kernel(cache=True, nogil=True, inline="always")

GOLDEN_STEPS = 40           # bracket 0.618**40 ~ 4e-9 of the segment; its slack is subtracted


# --- distances in an obstacle's frame (scalars, inlined) ---------------------------------------

@_inline
def _clamp01(x):
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


@_jit
def _segment_point(ax, ay, az, bx, by, bz, px, py, pz):
    """Distance from the segment a-b to the point p."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    dd = dx * dx + dy * dy + dz * dz
    t = 0.0
    if dd > 0.0:
        t = _clamp01(((px - ax) * dx + (py - ay) * dy + (pz - az) * dz) / dd)
    ex, ey, ez = ax + t * dx - px, ay + t * dy - py, az + t * dz - pz
    return math.sqrt(ex * ex + ey * ey + ez * ez)


@_jit
def _segment_segment(ax, ay, az, bx, by, bz, cx, cy, cz, ex, ey, ez):
    """Distance between segments a-b and c-e (Ericson, Real-Time Collision Detection 5.1.9)."""
    d1x, d1y, d1z = bx - ax, by - ay, bz - az
    d2x, d2y, d2z = ex - cx, ey - cy, ez - cz
    rx, ry, rz = ax - cx, ay - cy, az - cz
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    s, t = 0.0, 0.0
    if a <= 1e-300 and e <= 1e-300:
        pass
    elif a <= 1e-300:
        t = _clamp01(f / e)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= 1e-300:
            s = _clamp01(-c / a)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = _clamp01((b * f - c * e) / denom) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = _clamp01(-c / a)
            elif t > 1.0:
                t = 1.0
                s = _clamp01((b - c) / a)
    ux = ax + d1x * s - cx - d2x * t
    uy = ay + d1y * s - cy - d2y * t
    uz = az + d1z * s - cz - d2z * t
    return math.sqrt(ux * ux + uy * uy + uz * uz)


@_jit
def _segment_box(W, o, F, h):
    """Distance from the segment p + t d (t in [0, 1]) to the box |x_k| <= h_k: p = W[o:o+3],
    d = W[o+3:o+6], W[o+6:o+14] scratch, half sizes F[h:h+3].

    Along the segment the squared distance is a sum over axes of squared excesses, each zero or
    linear in t between the crossings of the box's face planes: a quadratic per piece.
    """
    ts = o + 6
    W[ts], W[ts + 1] = 0.0, 1.0
    m = 2
    for k in range(3):
        dk = W[o + 3 + k]
        if dk != 0.0:
            for sgn in (-1.0, 1.0):
                t = (sgn * F[h + k] - W[o + k]) / dk
                if 0.0 < t < 1.0:
                    W[ts + m] = t
                    m += 1
    for i in range(1, m):                       # insertion sort, at most 8 values
        v, j = W[ts + i], i - 1
        while j >= 0 and W[ts + j] > v:
            W[ts + j + 1] = W[ts + j]
            j -= 1
        W[ts + j + 1] = v
    best = np.inf
    for i in range(m - 1):
        t0, t1 = W[ts + i], W[ts + i + 1]
        tm = 0.5 * (t0 + t1)
        qa, qb, qc = 0.0, 0.0, 0.0              # excess^2 = (alpha + beta t)^2 summed
        for k in range(3):
            pk, dk, hk = W[o + k], W[o + 3 + k], F[h + k]
            x = pk + tm * dk
            if x > hk:
                alpha, beta = pk - hk, dk
            elif x < -hk:
                alpha, beta = -hk - pk, -dk
            else:
                continue
            qa += beta * beta
            qb += 2.0 * alpha * beta
            qc += alpha * alpha
        t = t0
        if qa > 0.0:
            t = min(max(-qb / (2.0 * qa), t0), t1)
        else:
            t = t0 if qb >= 0.0 else t1
        v = (qa * t + qb) * t + qc
        if v < best:
            best = v
    return math.sqrt(max(best, 0.0))


@_inline
def _point_cylinder(x, y, z, radius, half):
    dr = max(math.sqrt(x * x + y * y) - radius, 0.0)
    dz = max(abs(z) - half, 0.0)
    return math.sqrt(dr * dr + dz * dz)


@_jit
def _segment_cylinder(px, py, pz, dx, dy, dz, radius, half):
    """A lower bound (within 1e-8 of the segment's length) on the distance from the segment
    p + t d to the solid cylinder of `radius` and half length `half` about z: golden-section
    search of the convex distance along the segment, minus its Lipschitz slack."""
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    g = 0.6180339887498949
    lo, hi = 0.0, 1.0
    c, e = 1.0 - g, g
    fc, fe, best = 0.0, 0.0, np.inf
    for k in range(GOLDEN_STEPS + 4):
        if k < 2:
            t = float(k)                            # the ends
        elif k == 2:
            t = c
        elif k == 3:
            t = e
        elif fc < fe:                               # keep [lo, e]: a new inner point c
            hi, e, fe = e, c, fc
            c = hi - g * (hi - lo)
            t = c
        else:                                       # keep [c, hi]: a new inner point e
            lo, c, fc = c, e, fe
            e = lo + g * (hi - lo)
            t = e
        f = _point_cylinder(px + t * dx, py + t * dy, pz + t * dz, radius, half)
        best = min(best, f)
        if t == c:
            fc = f
        if t == e:
            fe = f
    return max(best - length * (hi - lo), 0.0)


@_inline
def _local_distance(kind, F, h, W, o):
    """Distance from the segment p + t d in an obstacle's frame (p = W[o:o+3], d =
    W[o+3:o+6], W[o+6:o+14] scratch) to the obstacle of kind and dimensions F[h:h+3].
    Negative (penetration) for spheres and capsules."""
    px, py, pz, dx, dy, dz = W[o], W[o + 1], W[o + 2], W[o + 3], W[o + 4], W[o + 5]
    if kind == 0:
        return _segment_box(W, o, F, h)
    if kind == 1:
        return _segment_point(px, py, pz, px + dx, py + dy, pz + dz, 0.0, 0.0, 0.0) - F[h]
    if kind == 2:
        return _segment_cylinder(px, py, pz, dx, dy, dz, F[h], F[h + 1])
    return _segment_segment(px, py, pz, px + dx, py + dy, pz + dz, 0.0, 0.0, -F[h + 1], 0.0,
                            0.0, F[h + 1]) - F[h]


@_inline
def _to_local(F, v, ax, ay, az, bx, by, bz, W, o):
    """The world segment a-b in the frame whose inverse is F[v:v+12] (3, 4): p into W[o:o+3],
    d into W[o+3:o+6]."""
    for r in range(3):
        i = v + 4 * r
        pr = F[i] * ax + F[i + 1] * ay + F[i + 2] * az + F[i + 3]
        W[o + r] = pr
        W[o + 3 + r] = F[i] * bx + F[i + 1] * by + F[i + 2] * bz + F[i + 3] - pr


# --- sine and cosine of a joint angle, inlined -----------------------------------------------
#
# A call into libm's sin and cos costs about 20 ns a pair here, a sixth of a state's check; a
# loop of the polynomials below vectorises and costs a few ns a pair. The angle x is reduced to
# y = x - k pi/2, |y| <= pi/4, by subtracting k times pi/2 split in three parts (Cody and
# Waite's reduction): the first two have 33 significant bits, so their products with k are exact
# for |x| < _REDUCED_BELOW; the third holds the rest. sin y and cos y are then their Taylor
# polynomials through y**17 and y**18, whose first omitted terms are below 1e-19 for
# |y| <= pi/4. y's rounding error is carried along (tail) and corrected for to first order: the
# results agree with libm's to 1 ulp (tests/planning/test_checker.py). Larger and non-finite
# angles go to libm.

_TWO_OVER_PI = 2.0 / math.pi
_PI_2_HIGH = 1.5707963267341256             # pi/2 to 33 significant bits
_PI_2_MID = 6.077100506303966e-11           # the next 33 bits of pi/2
_PI_2_LOW = 2.0222662487959506e-21          # pi/2 - _PI_2_HIGH - _PI_2_MID, rounded
_ROUNDING = 1.5 * 2.0**52                   # (v + it) - it is v rounded to an integer
_REDUCED_BELOW = 1e5
_SIN = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(1, 9))    # y**3 .. y**17
_COS = tuple((-1) ** k / math.factorial(2 * k) for k in range(2, 10))       # y**4 .. y**18


@_inline
def _sin_cos_reduced(x):
    """(sin x, cos x) within 1 ulp of libm's for |x| < _REDUCED_BELOW (else those of 0),
    without a branch: a loop of these vectorises."""
    x = x if abs(x) < _REDUCED_BELOW else 0.0
    k = (x * _TWO_OVER_PI + _ROUNDING) - _ROUNDING
    t = x - k * _PI_2_HIGH                      # exact
    m = k * _PI_2_MID                           # exact
    r = t - m
    v = r - t                                   # r's rounding error, exactly (Knuth's sum)
    error = (t - (r - v)) + (-m - v)
    y = r + (error - k * _PI_2_LOW)
    tail = (r - y) + (error - k * _PI_2_LOW)    # x - k pi/2 = y + tail
    z = y * y
    ps = _SIN[0] + z * (_SIN[1] + z * (_SIN[2] + z * (_SIN[3] + z * (          # Horner in z
        _SIN[4] + z * (_SIN[5] + z * (_SIN[6] + z * _SIN[7]))))))
    pc = _COS[0] + z * (_COS[1] + z * (_COS[2] + z * (_COS[3] + z * (
        _COS[4] + z * (_COS[5] + z * (_COS[6] + z * _COS[7]))))))
    s = y + (tail + y * z * ps)
    h = 0.5 * z
    u = 1.0 - h                                 # and its rounding error, exactly:
    c = u + (((1.0 - u) - h) + (z * z * pc - y * tail))
    quarter = int(k) & 3                        # x = y + quarter * pi/2 (mod 2 pi)
    odd = (quarter & 1) != 0
    return ((c if odd else s) * float(1 - (quarter & 2)),
            (s if odd else c) * float(1 - ((quarter + 1) & 2)))


@_jit
def sin_cos(x):
    """(sin x, cos x) within 1 ulp of libm's, any x (libm's beyond the reduction's range)."""
    if not abs(x) < _REDUCED_BELOW:
        return math.sin(x), math.cos(x)
    return _sin_cos_reduced(x)


@_inline
def joint_trig(Q, base, count, F, I, T, at):
    """The moving joints' values v (from the states Q[base : base + count * ns], ns the state's
    size) into T[at : at + count * n], their sines and cosines into the next count * n and the
    count * n after (n moving joints): for `free_distance`. One loop over the angles that
    vectorises, then libm for the rare ones beyond the reduction's range."""
    n, ns = I[0], state_size(I)
    i_source = 4 + n + I[1] + 2 * I[2] + I[3]
    f_scale = n + 12 + 12 * n + 7 * I[1] + ns + 19 * I[3]
    for s in range(count):
        for i in range(n):
            T[at + s * n + i] = F[f_scale + i] * Q[base + s * ns + I[i_source + i]] + F[i]
    total = count * n
    for c in range(at, at + total):
        T[c + total], T[c + 2 * total] = _sin_cos_reduced(T[c])
    for c in range(at, at + total):
        if not abs(T[c]) < _REDUCED_BELOW:
            T[c + total], T[c + 2 * total] = math.sin(T[c]), math.cos(T[c])


# --- the model: one float array F and one int array I (few arguments cross numba's dispatcher) -
#
# I: n, m (capsules), pairs, obstacles, then kinds (n), body (m), pairs (2 per pair), obstacle
# kinds, the joint values' sources (n), the links' DH-form flags (n), the state's size. F:
# offsets (n), pre (3, 4), links (n, 3, 4), capsule ends a, b (m, 3) each in its body frame,
# radius (m), displacement weights (n), obstacle inverses (o, 3, 4), dims (o, 3), centres
# (o, 3), bounding radii (o), the moving joints' mimic scales (n), then the obstacles' world
# bounding boxes (o, 6: lower corner, upper corner), the capsules' bounding-ball radii (m), the
# box of the whole scene (6). Work W: segments (m, 6), p, d and the sort scratch (14), the
# capsules' bounding balls (m, 4), the last closest capsule-obstacle pair, q (n), the capsules'
# world bounding boxes and their distances from the scene's box (m, 7), one state's joint
# values, sines and cosines (3n: `joint_trig`).

@_inline
def weights_at(I):
    """Where the displacement weights start in F."""
    n, m = I[0], I[1]
    return n + 12 + 12 * n + 7 * m


@_inline
def work_array(I):
    """The kernels' work array W."""
    W = np.empty(17 * I[1] + 15 + 4 * I[0])
    W[10 * I[1] + 14] = -1.0              # no closest pair yet
    return W


@_inline
def state_size(I):
    """The length n of a state q: the robot's joint values (its moving joints, mimic ones
    included, are I[0])."""
    return I[I.shape[0] - 1]


@_inline
def state_at(I):
    """Where the work array holds a state q (n,)."""
    return 10 * I[1] + 15


@_inline
def _times_link(a, b, c, d, F, lk):
    """A row (a, b, c, d) of a frame times the link transform F[lk:lk+12] (3, 4)."""
    return (a * F[lk] + b * F[lk + 4] + c * F[lk + 8],
            a * F[lk + 1] + b * F[lk + 5] + c * F[lk + 9],
            a * F[lk + 2] + b * F[lk + 6] + c * F[lk + 10],
            a * F[lk + 3] + b * F[lk + 7] + c * F[lk + 11] + d)


@_jit
def free_distance(T, at, stride, F, I, W, floor, cap):
    """How far (m) every point of the arm may move from a state without contact, the state
    given by its moving joints' values T[at : at + n], their sines T[at + stride ...] and
    cosines T[at + 2 stride ...] (`joint_trig`): ``min(gap to any obstacle, gap between two
    non-adjacent capsules / 2)`` (both may move), returned as ``min(that, cap)``; it stops
    early, with some value <= floor, once a pair is within floor. Obstacles a cheap lower bound
    (bounding ball, then for a box the separation along its axes) puts beyond the best so far
    are skipped. F, I: the model; W: work."""
    n, m, npairs, nobs = I[0], I[1], I[2], I[3]
    i_body = 4 + n
    i_pairs = i_body + m
    i_okind = i_pairs + 2 * npairs
    i_source = i_okind + nobs
    i_dh = i_source + n
    f_links = n + 12
    f_ca = f_links + 12 * n
    f_cb = f_ca + 3 * m
    f_rad = f_cb + 3 * m
    f_inv = f_rad + m + state_size(I)
    f_dims = f_inv + 12 * nobs
    f_cen = f_dims + 3 * nobs
    f_bound = f_cen + 3 * nobs
    f_scale = f_bound + nobs
    f_box = f_scale + n
    f_ball = f_box + 6 * nobs
    f_union = f_ball + m
    w_p = 6 * m
    w_b = w_p + 14
    w_box = w_b + 4 * m + 1 + n
    # The capsules' world segments into W[6k : 6k + 6], capsules sorted by body (-1: fixed).
    k = 0
    while k < m and I[i_body + k] < 0:
        for r in range(3):
            W[6 * k + r], W[6 * k + 3 + r] = F[f_ca + 3 * k + r], F[f_cb + 3 * k + r]
        k += 1
    # The frame T (rows r0, r1, r2 of 3 x 4) in scalars: they stay in registers.
    r00, r01, r02, r03 = F[n], F[n + 1], F[n + 2], F[n + 3]
    r10, r11, r12, r13 = F[n + 4], F[n + 5], F[n + 6], F[n + 7]
    r20, r21, r22, r23 = F[n + 8], F[n + 9], F[n + 10], F[n + 11]
    for i in range(n):
        v = T[at + i]
        if I[4 + i] == 0:
            sn, cs = T[at + stride + i], T[at + 2 * stride + i]
            r00, r01 = cs * r00 + sn * r01, cs * r01 - sn * r00
            r10, r11 = cs * r10 + sn * r11, cs * r11 - sn * r10
            r20, r21 = cs * r20 + sn * r21, cs * r21 - sn * r20
        else:
            r03 += v * r02
            r13 += v * r12
            r23 += v * r22
        while k < m and I[i_body + k] == i:
            for e in range(2):
                c = f_ca + 3 * k if e == 0 else f_cb + 3 * k
                x, y, z = F[c], F[c + 1], F[c + 2]
                W[6 * k + 3 * e] = r00 * x + r01 * y + r02 * z + r03
                W[6 * k + 3 * e + 1] = r10 * x + r11 * y + r12 * z + r13
                W[6 * k + 3 * e + 2] = r20 * x + r21 * y + r22 * z + r23
            k += 1
        if i + 1 < n:
            lk = f_links + 12 * i
            if I[i_dh + i]:                     # a DH link: Tz(d) Tx(a) Rx(alpha)
                ta, td = F[lk + 3], F[lk + 11]
                r03 += r00 * ta + r02 * td
                r13 += r10 * ta + r12 * td
                r23 += r20 * ta + r22 * td
                sa = F[lk + 9]
                if sa != 0.0:
                    ca = F[lk + 5]
                    r01, r02 = r01 * ca + r02 * sa, r02 * ca - r01 * sa
                    r11, r12 = r11 * ca + r12 * sa, r12 * ca - r11 * sa
                    r21, r22 = r21 * ca + r22 * sa, r22 * ca - r21 * sa
            else:
                r00, r01, r02, r03 = _times_link(r00, r01, r02, r03, F, lk)
                r10, r11, r12, r13 = _times_link(r10, r11, r12, r13, F, lk)
                r20, r21, r22, r23 = _times_link(r20, r21, r22, r23, F, lk)
    # Each capsule's bounding ball (centre, radius: half its length plus its radius, fixed) into
    # W[w_b + 4k : w_b + 4k + 4], its world bounding box (lower corner, upper corner, the radius
    # included) and the box's distance from the scene's box into W[w_box + 7k : w_box + 7k + 7].
    for k in range(m):
        ax, ay, az = W[6 * k], W[6 * k + 1], W[6 * k + 2]
        bx, by, bz = W[6 * k + 3], W[6 * k + 4], W[6 * k + 5]
        W[w_b + 4 * k] = ax + 0.5 * (bx - ax)
        W[w_b + 4 * k + 1] = ay + 0.5 * (by - ay)
        W[w_b + 4 * k + 2] = az + 0.5 * (bz - az)
        W[w_b + 4 * k + 3] = F[f_ball + k]
        radius = F[f_rad + k]
        lx, ly, lz = min(ax, bx) - radius, min(ay, by) - radius, min(az, bz) - radius
        hx, hy, hz = max(ax, bx) + radius, max(ay, by) + radius, max(az, bz) + radius
        kb = w_box + 7 * k
        W[kb], W[kb + 1], W[kb + 2], W[kb + 3], W[kb + 4], W[kb + 5] = lx, ly, lz, hx, hy, hz
        # How far the box is from the scene's box (a lower bound on any obstacle's distance).
        W[kb + 6] = max(max(lx - F[f_union + 3], F[f_union] - hx),
                        max(max(ly - F[f_union + 4], F[f_union + 1] - hy),
                            max(lz - F[f_union + 5], F[f_union + 2] - hz)))
    best = cap
    for s in range(npairs):
        ci, cj = I[i_pairs + 2 * s], I[i_pairs + 2 * s + 1]
        # Bounding boxes, then bounding balls, at least 2 best apart: this pair cannot lower
        # best (its gap is half the distance less the radii).
        i, j = w_box + 7 * ci, w_box + 7 * cj
        x = max(W[i] - W[j + 3], W[j] - W[i + 3])
        y = max(W[i + 1] - W[j + 4], W[j + 1] - W[i + 4])
        z = max(W[i + 2] - W[j + 5], W[j + 2] - W[i + 5])
        if max(x, max(y, z)) >= 2.0 * best:
            continue
        bi, bj = w_b + 4 * ci, w_b + 4 * cj
        x, y, z = W[bi] - W[bj], W[bi + 1] - W[bj + 1], W[bi + 2] - W[bj + 2]
        reach = 2.0 * best + W[bi + 3] + W[bj + 3]
        if reach > 0.0 and x * x + y * y + z * z >= reach * reach:
            continue
        i, j = 6 * ci, 6 * cj
        gap = 0.5 * (_segment_segment(W[i], W[i + 1], W[i + 2], W[i + 3], W[i + 4], W[i + 5],
                                      W[j], W[j + 1], W[j + 2], W[j + 3], W[j + 4], W[j + 5])
                     - F[f_rad + ci] - F[f_rad + cj])
        if gap < best:
            best = gap
            if best <= floor:
                return best
    # Capsule-obstacle pairs, the closest pair of the previous call first (consecutive states
    # on an edge are alike: a small best early lets the bounds skip most other pairs); a
    # capsule whose box is at least best from the scene's box skips every obstacle.
    witness = int(W[w_b + 4 * m])
    next_k, next_o = 0, -1                  # pair step - 1 as (capsule, obstacle): no division
    for step in range(m * nobs + 1):
        if step == 0:
            if witness < 0 or witness >= m * nobs:
                continue
            pair = witness
            k = pair // nobs
            o = pair - k * nobs
        else:
            next_o += 1
            if next_o == nobs:
                next_k, next_o = next_k + 1, 0
            pair = step - 1
            if pair == witness:
                continue
            k, o = next_k, next_o
        kb = w_box + 7 * k
        if W[kb + 6] >= best:
            continue
        # World bounding boxes of capsule and obstacle at least best apart along an axis:
        # skip (no transform to the obstacle's frame).
        ob = f_box + 6 * o
        x = max(W[kb] - F[ob + 3], F[ob] - W[kb + 3])
        y = max(W[kb + 1] - F[ob + 4], F[ob + 1] - W[kb + 4])
        z = max(W[kb + 2] - F[ob + 5], F[ob + 2] - W[kb + 5])
        if max(x, max(y, z)) >= best:
            continue
        # Bounding balls of capsule and obstacle at least best apart: skip.
        bk = w_b + 4 * k
        c = f_cen + 3 * o
        x, y, z = W[bk] - F[c], W[bk + 1] - F[c + 1], W[bk + 2] - F[c + 2]
        reach = best + W[bk + 3] + F[f_bound + o]
        if reach > 0.0 and x * x + y * y + z * z >= reach * reach:
            continue
        radius = F[f_rad + k]
        _to_local(F, f_inv + 12 * o, W[6 * k], W[6 * k + 1], W[6 * k + 2], W[6 * k + 3],
                  W[6 * k + 4], W[6 * k + 5], W, w_p)
        kind, h = I[i_okind + o], f_dims + 3 * o
        if kind == 0:
            apart = 0.0
            for r in range(3):
                e = W[w_p + r] + W[w_p + 3 + r]
                apart = max(apart, min(W[w_p + r], e) - F[h + r],
                            -F[h + r] - max(W[w_p + r], e))
            if apart - radius >= best:
                continue
        gap = _local_distance(kind, F, h, W, w_p) - radius
        if gap < best:
            best = gap
            W[w_b + 4 * m] = pair
            if best <= floor:
                return best
    return best


@_jit
def edge_free(qa, qb, F, I, W, floor, queue, fa_known):
    """Whether the straight joint-space edge qa -> qb (n,) is certified free, the states
    checked, and the free distance found at qb (capped).

    A piece between checked states a and b on which no point of the arm moves more than D
    (`displacement_weights`) is certified when ``f_a + f_b > D + floor`` (f: `free_distance`):
    a configuration a fraction t along it has moved at most tD from a and (1 - t)D from b, so
    it keeps ``(f_a + f_b - D) / 2 > floor / 2`` from every obstacle. Pieces not certified are
    halved, breadth first (the middle, then quarters, ...); the edge fails at the first state
    with f <= floor. Both ends are checked. queue (4, size): work (a larger one is made when
    the edge needs it). fa_known: qa's free distance when known (a tree node's: any lower
    bound of it above floor), else any value <= floor. free_distance is called at one place
    only: the code stays small.
    """
    n = qa.shape[0]
    w = weights_at(I)
    total = 0.0
    for i in range(n):
        total += F[w + i] * abs(qb[i] - qa[i])
    size = 2 * int(math.ceil(total / floor)) + 8
    if size > queue.shape[1]:
        queue = np.empty((4, size))
    else:
        size = queue.shape[1]
    at = state_at(I)
    trig = at + 7 * I[1] + I[0]                  # after q and the capsules' boxes
    head, tail, checked, stage = 0, 0, 0, 0
    a_t = b_t = a_f = b_f = fa = fb = 0.0
    if fa_known > floor:
        fa, stage = fa_known, 1
    while True:
        if stage < 2:                           # qa, qb, then the middle of the next piece
            t, cap = float(stage), total + 2.0 * floor
        else:
            t = -1.0
            while head != tail:
                a_t, b_t, a_f, b_f = queue[0, head], queue[1, head], queue[2, head], \
                    queue[3, head]
                head = head + 1 if head + 1 < size else 0
                span = (b_t - a_t) * total
                if a_f + b_f <= span + floor:
                    t, cap = 0.5 * (a_t + b_t), 0.5 * span + floor
                    break
            if t < 0.0:
                return True, checked, fb
        for j in range(n):
            W[at + j] = qa[j] + t * (qb[j] - qa[j])
        joint_trig(W, at, 1, F, I, W, trig)
        f = free_distance(W, trig, I[0], F, I, W, floor, cap)
        checked += 1
        stage += 1
        if f <= floor:
            return False, checked, f
        if stage == 1:
            fa = f
            continue
        if stage == 2:
            fb = f
            a_t, t, a_f = 0.0, 1.0, fa
        else:
            queue[0, tail], queue[1, tail], queue[2, tail], queue[3, tail] = a_t, t, a_f, f
            tail = tail + 1 if tail + 1 < size else 0
            a_t, t, a_f, f = t, b_t, f, b_f
        queue[0, tail], queue[1, tail], queue[2, tail], queue[3, tail] = a_t, t, a_f, f
        tail = tail + 1 if tail + 1 < size else 0


BATCH_CHUNK = 1024          # states per task of a batch, each with a fresh work array
PARALLEL_FROM = 4096        # states worth starting a thread for (`armkit.threads.threads_for`)
LIGHT_STATES = 1024         # states checked as Python before the kernel is compiled (`armkit.jit`)


@_inline
def _states_span(Q, F, I, floor, cap, out, start, stop):
    """`states_kernel` for the states start .. stop - 1, with work arrays of its own."""
    W = work_array(I)
    ns, count = state_size(I), stop - start
    T = np.empty(3 * I[0] * count)
    joint_trig(Q, start * ns, count, F, I, T, 0)
    f = np.nan
    for s in range(start, stop):
        finite = True
        for j in range(s * ns, (s + 1) * ns):
            if not math.isfinite(Q[j]):
                finite = False
        f = free_distance(T, (s - start) * I[0], I[0] * count, F, I, W, floor,
                          cap) if finite else np.nan
        if out.shape[0]:
            out[s] = f
    return f


@_jit
def states_kernel(Q, F, I, floor, cap, out):
    """`free_distance` (with floor and cap) of the states Q, flat (k * n,), into out (k,), or
    with out empty (0,) only returned (one state, nothing written); NaN for a state with a
    value that is not finite. Returns the last state's. The states go in chunks of
    BATCH_CHUNK, each starting afresh (no closest pair carried over), as in `states_parallel`:
    both give the same values."""
    count = Q.shape[0] // state_size(I)
    f = np.nan
    for start in range(0, count, BATCH_CHUNK):
        f = _states_span(Q, F, I, floor, cap, out, start, min(count, start + BATCH_CHUNK))
    return f


@kernel(cache=True, nogil=True, parallel=True)
def states_parallel(Q, F, I, floor, cap, out):
    """`states_kernel` into out (k,), its chunks spread over numba's threads (compiled at the
    first large batch only)."""
    count = Q.shape[0] // state_size(I)
    for c in prange((count + BATCH_CHUNK - 1) // BATCH_CHUNK):
        _states_span(Q, F, I, floor, cap, out, c * BATCH_CHUNK,
                     min(count, (c + 1) * BATCH_CHUNK))


def states_batch(Q: NDArray, F: NDArray, I: NDArray, floor: float, cap: float,
                 out: NDArray) -> None:
    """`states_kernel` of the states Q, flat (k * n,), into out (k,): serial, or on as many
    threads as the batch's size and the idle cores are worth (`armkit.threads.threads_for`); up
    to LIGHT_STATES states run light (`armkit.jit`)."""
    threads = threads_for(out.shape[0], PARALLEL_FROM)
    if threads == 1:
        states_kernel.sized(out.shape[0], Q, F, I, floor, cap, out, few=LIGHT_STATES)
        return
    with numba_threads(threads):
        states_parallel(Q, F, I, floor, cap, out)


@_jit
def polyline_kernel(P, F, I, floor, queue):
    """Whether every waypoint of P (k, n) and every straight edge between consecutive ones is
    certified free (`edge_free`; one waypoint: its state), and the states checked."""
    W = work_array(I)
    checked = 0
    for i in range(max(P.shape[0] - 1, 1)):          # one waypoint: the edge to itself
        free, c, _ = edge_free(P[i], P[min(i + 1, P.shape[0] - 1)], F, I, W, floor, queue,
                               -1.0)
        checked += c
        if not free:
            return False, checked
    return True, checked


@_jit
def obstacle_distances(kind, inverse, dims, a, b, out):
    """Distance from the segment a-b (3,) to each obstacle: kind (o,), inverse (o, 3, 4),
    dims (o, 3), into out (o,)."""
    W = np.empty(14)
    Fo = np.empty(15)
    for o in range(kind.shape[0]):
        for r in range(3):
            for c in range(4):
                Fo[4 * r + c] = inverse[o, r, c]
            Fo[12 + r] = dims[o, r]
        _to_local(Fo, 0, a[0], a[1], a[2], b[0], b[1], b[2], W, 0)
        out[o] = _local_distance(kind[o], Fo, 12, W, 0)


# --- Python side -------------------------------------------------------------------------------

def segment_distance(a, b, c, e) -> float:
    """Distance (m) between the segments a-b and c-e, each point (3,)."""
    return float(_segment_segment(*np.asarray(a, float), *np.asarray(b, float),
                                  *np.asarray(c, float), *np.asarray(e, float)))


def obstacle_distance(scene: Scene, a: ArrayLike, b: ArrayLike) -> NDArray:
    """Distance (m) from the segment a-b (3,) to each obstacle of the scene, (len(scene),).

    Exact for boxes, spheres and capsules (negative inside spheres and capsules: minus the
    depth), a lower bound within 1e-8 m for cylinders; 0 where the segment meets a box or
    cylinder.
    """
    k = scene_kernel(scene)
    a, b = np.asarray(a, float), np.asarray(b, float)
    out = np.empty(len(scene))
    obstacle_distances.light(k.kind, np.ascontiguousarray(k.inverse), k.dims, a, b, out)
    return out


def arm_capsules(robot: Robot, geometry: ArmGeometry, q: ArrayLike) -> tuple[NDArray, NDArray]:
    """The capsules' segments in the base frame at q (n,): a, b, each (m, 3), m."""
    frames = fk_frames(robot, q)
    a = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.a) + \
        frames[geometry.link, :3, 3]
    b = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.b) + \
        frames[geometry.link, :3, 3]
    return a, b


def displacement_weights(robot: Robot, geometry: ArmGeometry) -> NDArray:
    """Per joint value, how far (m) a point of the arm can move per unit of its motion (rad or
    m): for a revolute joint a bound on the distance of any capsule point riding on it from its
    axis (chain of joint-origin distances), 1 for a prismatic joint; a value that drives mimic
    joints adds theirs, times their multipliers. (n,)."""
    k, nj = robot.chain.kernel, robot.chain.n_joints
    lo, hi = robot.chain.sampling_limits
    travel = np.abs(k.motion_ends(lo, hi)).max(axis=0)
    to_body = link_to_body(robot)
    step = np.empty(nj)                 # bound on |o_{i+1} - o_i|, o_i joint i's origin
    for i in range(nj - 1):
        step[i] = np.linalg.norm(k.links[i][:3, 3]) + (travel[i + 1] if k.kinds[i + 1] else 0.0)
    reach = np.zeros(nj)                # from joint i's origin, per body j >= i
    for c in range(len(geometry)):
        j = geometry.link[c] - 1        # body: joint j's moved frame
        if j < 0:
            continue
        T = to_body[geometry.link[c]]
        extent = max(np.linalg.norm((T @ np.r_[geometry.a[c], 1])[:3]),
                     np.linalg.norm((T @ np.r_[geometry.b[c], 1])[:3]))
        for i in range(j + 1):
            reach[i] = max(reach[i], step[i:j].sum() + extent)
    weights = np.zeros(robot.n)
    np.add.at(weights, k.source, np.abs(k.scale) * np.where(k.kinds == 0, reach, 1.0))
    return weights


def world_half_sizes(scene: SceneKernel) -> NDArray:
    """Half sizes (o, 3) of a box about each obstacle's centre, along the base frame's axes,
    that holds the obstacle (m): its frame's half sizes (a box's, a sphere's radius, a
    cylinder's radius and half length, a capsule's with its caps) through the absolute
    rotation."""
    kind, dims = scene.kind, scene.dims
    local = np.where((kind == SPHERE)[:, None], dims[:, :1], dims[:, [0, 0, 1]])
    local = np.where((kind == BOX)[:, None], dims, local)
    local[kind == CAPSULE, 2] += dims[kind == CAPSULE, 0]
    rotation = np.transpose(scene.inverse[:, :, :3], (0, 2, 1))      # obstacle to base
    return np.einsum("oij,oj->oi", np.abs(rotation), local)


def dh_links(chain: KernelChain) -> NDArray:
    """1 where a link transform (after each moving joint) has a DH link's form, Tz(d) Tx(a)
    Rx(alpha): ``[[1, 0, 0, a], [0, c, -s, 0], [0, s, c, d]]``, whose product with a frame the
    checker takes in 6 to 18 multiplications instead of 36; else 0. (n,) int."""
    L = chain.links[:, :3]
    dh = ((L[:, 0, 0] == 1) & (L[:, 0, 1] == 0) & (L[:, 0, 2] == 0) & (L[:, 1, 0] == 0)
          & (L[:, 2, 0] == 0) & (L[:, 1, 3] == 0) & (L[:, 1, 1] == L[:, 2, 2])
          & (L[:, 1, 2] == -L[:, 2, 1]))
    return dh.astype(np.int64)


def pack_model(chain: KernelChain, body, ca, cb, radius, pairs, weights,
               scene: SceneKernel) -> tuple[NDArray, NDArray]:
    """The checker's arrays as one float array F and one int array I, in the order
    `free_distance` reads them; I ends with the length of a state (`state_size`)."""
    n, m, npairs, nobs = len(chain.kinds), len(body), len(pairs), len(scene.kind)
    half = world_half_sizes(scene)
    boxes = np.hstack([scene.center - half, scene.center + half]).reshape(nobs, 6)
    I = np.concatenate([[n, m, npairs, nobs], chain.kinds, body, np.reshape(pairs, -1),
                        scene.kind, chain.source, dh_links(chain),
                        [len(weights)]]).astype(np.int64)
    F = np.concatenate([chain.offsets, np.reshape(chain.pre[:3], -1),
                        np.reshape(chain.links[:, :3], -1), np.reshape(ca, -1),
                        np.reshape(cb, -1), radius, weights, np.reshape(scene.inverse, -1),
                        np.reshape(scene.dims, -1), np.reshape(scene.center, -1), scene.bound,
                        chain.scale, np.reshape(boxes, -1),
                        0.5 * np.linalg.norm(np.reshape(cb, (-1, 3)) - np.reshape(ca, (-1, 3)),
                                             axis=1) + radius + 1e-12,
                        boxes[:, :3].min(axis=0, initial=np.inf),
                        boxes[:, 3:].max(axis=0, initial=-np.inf)]).astype(float)
    return F, I


_NONE = np.empty(0)       # "one state, return it": nothing is written to it
_NO_QUEUE = np.empty((4, 0))      # the edge test makes its own
QUEUE_SIZE = 1024                 # the planners' edge-test work: longer edges make their own


def _writable(a: NDArray) -> NDArray:
    """a as a C-contiguous writable float array: the kernels' one signature (a read-only
    array would compile them again)."""
    a = np.ascontiguousarray(a, dtype=float)
    return a if a.flags.writeable else a.copy()


@dataclass(frozen=True, eq=False)
class CollisionChecker:
    """One robot's capsules against one scene, compiled; built once, immutable.

    Parameters
    ----------
    robot : Robot
    scene : Scene, optional
        No obstacles if omitted (self-collision only).
    geometry : ArmGeometry, optional
        The robot file's, or the default capsules (`arm_geometry`).
    resolution : float
        r, m: a valid state keeps every capsule more than r from every obstacle (2r from each
        other); every configuration on a certified edge keeps at least r / 2 (r from each
        other), between its checked states too (see the module's note).

    Attributes
    ----------
    weights : ndarray, (n,)
        The displacement bound per unit joint motion (m/rad, or 1 for prismatic joints).
    model : (ndarray, ndarray)
        Everything the kernels take, packed in one float and one int array (`pack_model`).
    """

    robot: Robot
    scene: Scene = field(default_factory=Scene)
    geometry: ArmGeometry | None = None
    resolution: float = 0.005
    weights: NDArray = field(init=False, repr=False)
    model: tuple = field(init=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.scene, Scene):
            raise InputError(f"scene: expected a Scene, found {type(self.scene).__name__}")
        res = float(self.resolution)
        if not (math.isfinite(res) and res > 0):
            raise InputError(f"resolution: expected a positive length (m), found {res:g}")
        object.__setattr__(self, "resolution", res)
        geometry = self.geometry if self.geometry is not None else arm_geometry(self.robot)
        links = self.robot.chain.n_joints
        if len(geometry) and geometry.link.max() > links:
            raise InputError(f"geometry: expected links 0 .. {links} of "
                             f"{self.robot.name}, found link {geometry.link.max()}")
        object.__setattr__(self, "geometry", geometry)
        weights = displacement_weights(self.robot, geometry)
        weights.setflags(write=False)
        object.__setattr__(self, "weights", weights)
        # Kernel form: capsules in their body frames, sorted by body (-1 for the base).
        to_body = link_to_body(self.robot)
        order = np.argsort(geometry.link, kind="stable")
        body = (geometry.link[order] - 1).astype(np.int64)
        T0 = self.robot.chain.T_base
        ca, cb = np.empty((len(order), 3)), np.empty((len(order), 3))
        for row, c in enumerate(order):
            T = T0 if geometry.link[c] == 0 else to_body[geometry.link[c]]
            ca[row] = (T @ np.r_[geometry.a[c], 1])[:3]
            cb[row] = (T @ np.r_[geometry.b[c], 1])[:3]
        rank = np.empty(len(order), np.int64)
        rank[order] = np.arange(len(order))
        pairs = rank[geometry.self_pairs()].reshape(-1, 2)
        F, I = pack_model(self.robot.chain.kernel, body, ca, cb, geometry.radius[order], pairs,
                          weights, scene_kernel(self.scene))
        F.setflags(write=False)
        I.setflags(write=False)
        object.__setattr__(self, "model", (F, I))
        object.__setattr__(self, "_one_shape", (self.robot.n,))
        # A verdict needs the free distance only up to just above the resolution.
        object.__setattr__(self, "_valid_cap", res * (1 + 1e-9) + 1e-12)

    @property
    def n(self) -> int:
        return self.robot.n

    edge_checks_ends = True         # interior_free checks both ends: planners skip their own

    @property
    def lower(self) -> NDArray:
        return self.robot.chain.sampling_limits[0]

    @property
    def upper(self) -> NDArray:
        return self.robot.chain.sampling_limits[1]

    def _free(self, q: NDArray, floor: float, cap: float) -> NDArray:
        """free_distance of the states q (..., n), already a float array; (...,)."""
        F, I = self.model
        if q.shape == (self.n,) and q.flags.c_contiguous and q.flags.writeable:
            # One state: nothing allocated.
            f = states_kernel.light(q, F, I, floor, cap, _NONE)
            if math.isnan(f):
                raise InputError("q: expected finite joint values, found NaN or inf")
            return f
        if q.ndim == 0 or q.shape[-1] != self.n:
            joint_array(self.robot, q)                          # raises the precise error
        q = _writable(q)
        out = np.empty(q.shape[:-1])
        states_batch(q.reshape(-1), F, I, floor, cap, out.reshape(-1))
        if np.isnan(out).any():
            raise InputError("q: expected finite joint values, found NaN or inf")
        return out

    def clearance(self, q: ArrayLike) -> NDArray:
        """Free distance f (m) at q (..., n): the smallest gap between a capsule and an
        obstacle, or half the smallest gap between two capsules of the arm (both can move);
        (...,). <= 0 where they touch or overlap (minus the depth for spheres, capsules)."""
        if not (type(q) is np.ndarray and q.dtype == np.float64):
            q = joint_array(self.robot, q)
        return np.asarray(self._free(q, -np.inf, np.inf))

    def valid(self, q: ArrayLike) -> NDArray:
        """Free distance above the resolution: the states a certified edge may end on.
        (...,) bool."""
        if type(q) is np.ndarray and q.shape == self._one_shape and q.dtype == np.float64:
            flags = q.flags
            if flags.c_contiguous and flags.writeable:           # one state, straight in
                F, I = self.model
                r = self.resolution
                f = states_kernel.light(q, F, I, r, self._valid_cap, _NONE)
                if f > r:
                    return np.True_
                if math.isnan(f):
                    raise InputError("q: expected finite joint values, found NaN or inf")
                return np.False_
        if not (type(q) is np.ndarray and q.dtype == np.float64):
            q = joint_array(self.robot, q)
        return self._free(q, self.resolution, self._valid_cap) > self.resolution

    def __call__(self, q: ArrayLike) -> NDArray:
        """Same as `valid`: a checker is a validity callable on a batch of states."""
        return self.valid(q)

    def valid_states(self, Q: NDArray) -> NDArray:
        """`valid` for states (k, n) already checked for shape (the planners' call)."""
        Q = _writable(Q)
        out = np.empty(Q.shape[0])
        states_batch(Q.reshape(-1), self.model[0], self.model[1], self.resolution,
                     self._valid_cap, out)
        return out > self.resolution

    def polyline_free(self, path: NDArray) -> tuple[bool, int]:
        """Whether every waypoint of path (k, n) and every edge between them is certified free
        (no shape checks: the planners' call), and the states checked."""
        path = _writable(path)
        free, checked = polyline_kernel.light(path, self.model[0], self.model[1], self.resolution,
                                        _NO_QUEUE)
        return bool(free), int(checked)

    def interior_free(self, qa: NDArray, qb: NDArray) -> tuple[bool, int]:
        """Whether the edge qa -> qb (n,) is certified free (the planners' call; its endpoints
        are checked again), and the states checked."""
        return self.polyline_free(np.vstack([qa, qb]))

    def edge_valid(self, qa: ArrayLike, qb: ArrayLike) -> tuple[bool, int]:
        """Whether the straight joint-space edge qa -> qb (n,) is certified free, endpoints
        included, and the number of states checked."""
        qa, qb = joint_array(self.robot, qa, "qa"), joint_array(self.robot, qb, "qb")
        if qa.shape != (self.n,) or qb.shape != (self.n,):
            raise InputError(f"qa, qb: expected one configuration each ({self.n},), found "
                             f"{qa.shape} and {qb.shape}")
        return self.interior_free(qa, qb)

    def path_valid(self, path: ArrayLike) -> bool:
        """Every waypoint of path (k, n) and every edge between them certified free."""
        path = joint_array(self.robot, path, "path")
        return self.polyline_free(path.reshape(-1, self.n))[0]
