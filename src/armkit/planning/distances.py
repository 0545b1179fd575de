"""Distances between a segment (a capsule's axis, or a point: a sphere's centre) and the obstacles
of a scene, and between two segments, as the collision checker's kernels take them.

Exact for a segment against a sphere, a capsule, another segment and a box (the squared
distance from a segment to a box is piecewise quadratic along the segment: minimised piece by
piece); against a cylinder a lower bound within 1e-8 m of the segment's length (golden-section
search of the convex distance, minus the search's Lipschitz slack), exact for a point.
Distances are negative inside spheres and capsules (minus the depth), 0 where a segment meets a
box or a cylinder.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.jit import kernel
from armkit.planning.scene import Scene, scene_kernel

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
def segment_point(ax, ay, az, bx, by, bz, px, py, pz):
    """Distance from the segment a-b to the point p."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    dd = dx * dx + dy * dy + dz * dz
    t = 0.0
    if dd > 0.0:
        t = _clamp01(((px - ax) * dx + (py - ay) * dy + (pz - az) * dz) / dd)
    ex, ey, ez = ax + t * dx - px, ay + t * dy - py, az + t * dz - pz
    return math.sqrt(ex * ex + ey * ey + ez * ez)


@_jit
def segment_segment(ax, ay, az, bx, by, bz, cx, cy, cz, ex, ey, ez):
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
def segment_box(W, o, F, h):
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
def point_cylinder(x, y, z, radius, half):
    dr = max(math.sqrt(x * x + y * y) - radius, 0.0)
    dz = max(abs(z) - half, 0.0)
    return math.sqrt(dr * dr + dz * dz)


@_jit
def segment_cylinder(px, py, pz, dx, dy, dz, radius, half):
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
        f = point_cylinder(px + t * dx, py + t * dy, pz + t * dz, radius, half)
        best = min(best, f)
        if t == c:
            fc = f
        if t == e:
            fe = f
    return max(best - length * (hi - lo), 0.0)


@_inline
def local_distance(kind, F, h, W, o):
    """Distance from the segment p + t d in an obstacle's frame (p = W[o:o+3], d =
    W[o+3:o+6], W[o+6:o+14] scratch) to the obstacle of kind and dimensions F[h:h+3].
    Negative (penetration) for spheres and capsules."""
    px, py, pz, dx, dy, dz = W[o], W[o + 1], W[o + 2], W[o + 3], W[o + 4], W[o + 5]
    if kind == 0:
        return segment_box(W, o, F, h)
    if kind == 1:
        return segment_point(px, py, pz, px + dx, py + dy, pz + dz, 0.0, 0.0, 0.0) - F[h]
    if kind == 2:
        return segment_cylinder(px, py, pz, dx, dy, dz, F[h], F[h + 1])
    return segment_segment(px, py, pz, px + dx, py + dy, pz + dz, 0.0, 0.0, -F[h + 1], 0.0,
                            0.0, F[h + 1]) - F[h]


@_inline
def to_local(F, v, ax, ay, az, bx, by, bz, W, o):
    """The world segment a-b in the frame whose inverse is F[v:v+12] (3, 4): p into W[o:o+3],
    d into W[o+3:o+6]."""
    for r in range(3):
        i = v + 4 * r
        pr = F[i] * ax + F[i + 1] * ay + F[i + 2] * az + F[i + 3]
        W[o + r] = pr
        W[o + 3 + r] = F[i] * bx + F[i + 1] * by + F[i + 2] * bz + F[i + 3] - pr


@_inline
def point_distance(kind, F, h, x, y, z):
    """Distance from the point (x, y, z) in an obstacle's frame to the obstacle of kind and
    dimensions F[h:h+3]: exact; negative inside spheres and capsules, 0 inside boxes and
    cylinders."""
    if kind == 0:
        ex = max(abs(x) - F[h], 0.0)
        ey = max(abs(y) - F[h + 1], 0.0)
        ez = max(abs(z) - F[h + 2], 0.0)
        return math.sqrt(ex * ex + ey * ey + ez * ez)
    if kind == 1:
        return math.sqrt(x * x + y * y + z * z) - F[h]
    if kind == 2:
        return point_cylinder(x, y, z, F[h], F[h + 1])
    zc = min(max(z, -F[h + 1]), F[h + 1])          # a capsule: its axis on z
    return math.sqrt(x * x + y * y + (z - zc) * (z - zc)) - F[h]


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
        to_local(Fo, 0, a[0], a[1], a[2], b[0], b[1], b[2], W, 0)
        out[o] = local_distance(kind[o], Fo, 12, W, 0)


# --- Python side -------------------------------------------------------------------------------

def segment_distance(a, b, c, e) -> float:
    """Distance (m) between the segments a-b and c-e, each point (3,)."""
    return float(segment_segment(*np.asarray(a, float), *np.asarray(b, float),
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


