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

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk_frames
from armkit.model.robot import Robot, joint_array
from armkit.planning.geometry import ArmGeometry, arm_geometry, link_to_body
from armkit.planning.scene import Scene, SceneKernel, scene_kernel

_jit = numba.njit(cache=True, nogil=True)

GOLDEN_STEPS = 40           # bracket 0.618**40 ~ 4e-9 of the segment; its slack is subtracted


# --- distances in an obstacle's frame (scalars, inlined) ---------------------------------------

@_jit
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
def _segment_box(p, d, h, ts):
    """Distance from the segment p + t d (t in [0, 1]) to the box |x_k| <= h_k (arrays (3,));
    ts (8,) scratch.

    Along the segment the squared distance is a sum over axes of squared excesses, each zero or
    linear in t between the crossings of the box's face planes: a quadratic per piece.
    """
    ts[0], ts[1] = 0.0, 1.0
    m = 2
    for k in range(3):
        if d[k] != 0.0:
            for sgn in (-1.0, 1.0):
                t = (sgn * h[k] - p[k]) / d[k]
                if 0.0 < t < 1.0:
                    ts[m] = t
                    m += 1
    for i in range(1, m):                       # insertion sort, at most 8 values
        v, j = ts[i], i - 1
        while j >= 0 and ts[j] > v:
            ts[j + 1] = ts[j]
            j -= 1
        ts[j + 1] = v
    best = np.inf
    for i in range(m - 1):
        t0, t1 = ts[i], ts[i + 1]
        tm = 0.5 * (t0 + t1)
        qa, qb, qc = 0.0, 0.0, 0.0              # excess^2 = (alpha + beta t)^2 summed
        for k in range(3):
            x = p[k] + tm * d[k]
            if x > h[k]:
                alpha, beta = p[k] - h[k], d[k]
            elif x < -h[k]:
                alpha, beta = -h[k] - p[k], -d[k]
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


@_jit
def _point_cylinder(x, y, z, radius, half):
    dr = max(math.sqrt(x * x + y * y) - radius, 0.0)
    dz = max(abs(z) - half, 0.0)
    return math.sqrt(dr * dr + dz * dz)


@_jit
def _segment_cylinder(p, d, radius, half):
    """A lower bound (within 1e-8 of the segment's length) on the distance from the segment
    p + t d to the solid cylinder of `radius` and half length `half` about z: golden-section
    search of the convex distance along the segment, minus its Lipschitz slack."""
    length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
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
        f = _point_cylinder(p[0] + t * d[0], p[1] + t * d[1], p[2] + t * d[2], radius, half)
        best = min(best, f)
        if t == c:
            fc = f
        if t == e:
            fe = f
    return max(best - length * (hi - lo), 0.0)


@_jit
def _obstacle_distance(kind, inverse, dims, a, b, p, d):
    """Distance from the world segment a-b (3,) to one obstacle (see scene.SceneKernel);
    p (3,), d (11,) are scratch. Negative (penetration) for spheres and capsules."""
    for r in range(3):
        p[r] = inverse[r, 0] * a[0] + inverse[r, 1] * a[1] + inverse[r, 2] * a[2] + inverse[r, 3]
        d[r] = (inverse[r, 0] * b[0] + inverse[r, 1] * b[1] + inverse[r, 2] * b[2]
                + inverse[r, 3] - p[r])
    if kind == 0:
        return _segment_box(p, d, dims, d[3:11])
    if kind == 1:
        return _segment_point(p[0], p[1], p[2], p[0] + d[0], p[1] + d[1], p[2] + d[2],
                              0.0, 0.0, 0.0) - dims[0]
    if kind == 2:
        return _segment_cylinder(p, d, dims[0], dims[1])
    return _segment_segment(p[0], p[1], p[2], p[0] + d[0], p[1] + d[1], p[2] + d[2],
                            0.0, 0.0, -dims[1], 0.0, 0.0, dims[1]) - dims[0]


# --- the arm and one state ---------------------------------------------------------------------

@_jit
def _segments(q, kinds, offsets, pre, links, body, ca, cb, seg, T, L):
    """World segments (m, 6) of the capsules at q; capsules sorted by body (-1 = fixed)."""
    m, n = body.shape[0], q.shape[0]
    k = 0
    while k < m and body[k] < 0:
        for r in range(3):
            seg[k, r], seg[k, 3 + r] = ca[k, r], cb[k, r]
        k += 1
    for r in range(3):
        for c in range(4):
            T[r, c] = pre[r, c]
    for i in range(n):
        v = q[i] + offsets[i]
        if kinds[i] == 0:
            cs, sn = math.cos(v), math.sin(v)
            for r in range(3):
                x, y = T[r, 0], T[r, 1]
                T[r, 0], T[r, 1] = cs * x + sn * y, cs * y - sn * x
        else:
            for r in range(3):
                T[r, 3] += v * T[r, 2]
        while k < m and body[k] == i:
            for r in range(3):
                seg[k, r] = T[r, 0] * ca[k, 0] + T[r, 1] * ca[k, 1] + T[r, 2] * ca[k, 2] + T[r, 3]
                seg[k, 3 + r] = (T[r, 0] * cb[k, 0] + T[r, 1] * cb[k, 1] + T[r, 2] * cb[k, 2]
                                 + T[r, 3])
            k += 1
        if i + 1 < n:
            for r in range(3):
                for c in range(4):
                    L[r, c] = T[r, 0] * links[i, 0, c] + T[r, 1] * links[i, 1, c] + \
                        T[r, 2] * links[i, 2, c]
                L[r, 3] += T[r, 3]
            for r in range(3):
                for c in range(4):
                    T[r, c] = L[r, c]


@_jit
def free_distance(q, kinds, offsets, pre, links, body, ca, cb, radius, pairs, okind, oinv, odims,
                  ocenter, obound, floor, cap, seg, T, L, p, d):
    """How far (m) every point of the arm may move from q without contact:
    ``min(gap to any obstacle, gap between two non-adjacent capsules / 2)`` (both may move),
    returned as ``min(that, cap)``; it stops early, with some value <= floor, once a pair is
    within floor. Pairs the broad phase puts beyond the best so far are skipped.
    seg (m, 6), T, L (3, 4), p, d (3,): scratch."""
    _segments(q, kinds, offsets, pre, links, body, ca, cb, seg, T, L)
    best = cap
    for s in range(pairs.shape[0]):
        i, j = pairs[s, 0], pairs[s, 1]
        gap = 0.5 * (_segment_segment(seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4],
                                      seg[i, 5], seg[j, 0], seg[j, 1], seg[j, 2], seg[j, 3],
                                      seg[j, 4], seg[j, 5]) - radius[i] - radius[j])
        if gap < best:
            best = gap
            if best <= floor:
                return best
    for k in range(body.shape[0]):
        a, b = seg[k, 0:3], seg[k, 3:6]
        for o in range(okind.shape[0]):
            c = ocenter[o]
            lower = _segment_point(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]) \
                - obound[o] - radius[k]
            if lower >= best:
                continue
            gap = _obstacle_distance(okind[o], oinv[o], odims[o], a, b, p, d) - radius[k]
            if gap < best:
                best = gap
                if best <= floor:
                    return best
    return best


@_jit
def check(Q, weights, floor, cap, edge, kinds, offsets, pre, links, body, ca, cb, radius, pairs,
          okind, oinv, odims, ocenter, obound, out):
    """The one compiled entry point.

    With edge false: `free_distance` (with floor and cap) of every row of Q (N, n) into out (N,).

    With edge true: whether the straight joint-space edge Q[0] -> Q[1] is certified free, into
    out[0] (1 or 0), and the states checked into out[1]. A piece between checked states a and b
    on which no point of the arm moves more than D (`displacement_weights`) is certified when
    ``f_a + f_b > D + floor`` (f: `free_distance`): a configuration a fraction t along it has
    moved at most tD from a and (1 - t)D from b, so it keeps ``(f_a + f_b - D) / 2 > floor / 2``
    from every obstacle. Pieces not certified are halved, breadth first (the middle, then
    quarters, ...); the edge fails at the first state with f <= floor. Both ends are checked.

    free_distance is called at one place only: the compiled code stays small.
    """
    n = Q.shape[1]
    seg = np.empty((body.shape[0], 6))
    T, L, p, d = np.empty((3, 4)), np.empty((3, 4)), np.empty(3), np.empty(11)
    q = np.empty(n)
    total = 0.0
    size = 1
    if edge:
        for i in range(n):
            total += weights[i] * abs(Q[1, i] - Q[0, i])
        size = 2 * int(math.ceil(total / floor)) + 8
    t0, t1, f0, f1 = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    head, tail, checked, fa = 0, 0, 0, 0.0
    a_t = b_t = a_f = b_f = 0.0
    while True:
        if not edge:
            if checked == Q.shape[0]:
                return
            t, cap_here = 0.0, cap
            for j in range(n):
                q[j] = Q[checked, j]
        else:
            # The next state: Q[0], Q[1], then the middle of the next piece not certified.
            if checked < 2:
                t, cap_here = float(checked), total + floor
            else:
                t = -1.0
                while head != tail:
                    a_t, b_t, a_f, b_f = t0[head], t1[head], f0[head], f1[head]
                    head = (head + 1) % size
                    span = (b_t - a_t) * total
                    if a_f + b_f <= span + floor:
                        t, cap_here = 0.5 * (a_t + b_t), 0.5 * span + floor
                        break
                if t < 0.0:
                    out[0], out[1] = 1.0, checked
                    return
            for j in range(n):
                q[j] = Q[0, j] + t * (Q[1, j] - Q[0, j])
        f = free_distance(q, kinds, offsets, pre, links, body, ca, cb, radius, pairs, okind,
                          oinv, odims, ocenter, obound, floor, cap_here, seg, T, L, p, d)
        checked += 1
        if not edge:
            out[checked - 1] = f
            continue
        if f <= floor:
            out[0], out[1] = 0.0, checked
            return
        if checked == 1:
            fa = f
        elif checked == 2:
            t0[tail], t1[tail], f0[tail], f1[tail] = 0.0, 1.0, fa, f
            tail = (tail + 1) % size
        else:
            t0[tail], t1[tail], f0[tail], f1[tail] = a_t, t, a_f, f
            tail = (tail + 1) % size
            t0[tail], t1[tail], f0[tail], f1[tail] = t, b_t, f, b_f
            tail = (tail + 1) % size


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
    p, d = np.empty(3), np.empty(11)
    return np.array([_obstacle_distance(k.kind[o], k.inverse[o], k.dims[o], a, b, p, d)
                     for o in range(len(scene))])


def arm_capsules(robot: Robot, geometry: ArmGeometry, q: ArrayLike) -> tuple[NDArray, NDArray]:
    """The capsules' segments in the base frame at q (n,): a, b, each (m, 3), m."""
    frames = fk_frames(robot, q)
    a = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.a) + \
        frames[geometry.link, :3, 3]
    b = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.b) + \
        frames[geometry.link, :3, 3]
    return a, b


def displacement_weights(robot: Robot, geometry: ArmGeometry) -> NDArray:
    """Per joint, how far (m) a point of the arm can move per unit of that joint's motion (rad
    or m): for a revolute joint a bound on the distance of any capsule point riding on it from
    its axis (chain of joint-origin distances), 1 for a prismatic joint. (n,)."""
    k, n = robot.chain.kernel, robot.n
    lo, hi = robot.chain.sampling_limits
    to_body = link_to_body(robot)
    step = np.empty(n)                  # bound on |o_{i+1} - o_i|, o_i joint i's origin
    for i in range(n - 1):
        step[i] = np.linalg.norm(k.links[i][:3, 3])
        if k.kinds[i + 1] == 1:
            step[i] += max(abs(lo[i + 1] + k.offsets[i + 1]), abs(hi[i + 1] + k.offsets[i + 1]))
    reach = np.zeros(n)                 # from joint i's origin, per body j >= i
    for c in range(len(geometry)):
        j = geometry.link[c] - 1        # body: joint j's moved frame
        if j < 0:
            continue
        T = to_body[geometry.link[c]]
        extent = max(np.linalg.norm((T @ np.r_[geometry.a[c], 1])[:3]),
                     np.linalg.norm((T @ np.r_[geometry.b[c], 1])[:3]))
        for i in range(j + 1):
            reach[i] = max(reach[i], step[i:j].sum() + extent)
    return np.where(robot.chain.revolute, reach, 1.0)


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
    kernel_args : tuple
        Everything the kernels take, in their order.
    """

    robot: Robot
    scene: Scene = field(default_factory=Scene)
    geometry: ArmGeometry | None = None
    resolution: float = 0.005
    weights: NDArray = field(init=False, repr=False)
    kernel_args: tuple = field(init=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.scene, Scene):
            raise InputError(f"scene: expected a Scene, found {type(self.scene).__name__}")
        res = float(self.resolution)
        if not (math.isfinite(res) and res > 0):
            raise InputError(f"resolution: expected a positive length (m), found {res:g}")
        object.__setattr__(self, "resolution", res)
        geometry = self.geometry if self.geometry is not None else arm_geometry(self.robot)
        if len(geometry) and geometry.link.max() > self.robot.n:
            raise InputError(f"geometry: expected links 0 .. {self.robot.n} of "
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
        pairs = np.ascontiguousarray(rank[geometry.self_pairs()].reshape(-1, 2))
        k = self.robot.chain.kernel
        sk: SceneKernel = scene_kernel(self.scene)
        args = (np.ascontiguousarray(k.kinds), np.ascontiguousarray(k.offsets),
                np.ascontiguousarray(k.pre), np.ascontiguousarray(k.links), body, ca, cb,
                np.ascontiguousarray(geometry.radius[order]), pairs, sk.kind,
                np.ascontiguousarray(sk.inverse), sk.dims, sk.center, sk.bound)
        for a in args:
            a.setflags(write=False)
        object.__setattr__(self, "kernel_args", args)

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

    def clearance(self, q: ArrayLike) -> NDArray:
        """Free distance f (m) at q (..., n): the smallest gap between a capsule and an
        obstacle, or half the smallest gap between two capsules of the arm (both can move);
        (...,). <= 0 where they touch or overlap (minus the depth for spheres, capsules)."""
        q = joint_array(self.robot, q)
        flat = q.reshape(-1, self.n)
        out = np.empty(flat.shape[0])
        check(flat, self.weights, -np.inf, np.inf, False, *self.kernel_args, out)
        return out.reshape(q.shape[:-1])

    def valid(self, q: ArrayLike) -> NDArray:
        """Free distance above the resolution: the states a certified edge may end on.
        (...,) bool."""
        q = joint_array(self.robot, q)
        return self.valid_states(q.reshape(-1, self.n)).reshape(q.shape[:-1])

    def __call__(self, q: ArrayLike) -> NDArray:
        """Same as `valid`: a checker is a validity callable on a batch of states."""
        return self.valid(q)

    def valid_states(self, Q: NDArray) -> NDArray:
        """`valid` for states (k, n) already checked for shape (the planners' call)."""
        Q = np.ascontiguousarray(Q, dtype=float)
        out = np.empty(Q.shape[0])
        r = self.resolution
        check(Q, self.weights, r, r * (1 + 1e-9) + 1e-12, False, *self.kernel_args, out)
        return out > r

    def interior_free(self, qa: NDArray, qb: NDArray) -> tuple[bool, int]:
        """Whether the edge qa -> qb (n,) is certified free (the planners' call; its endpoints
        are checked again), and the states checked."""
        out = np.empty(2)
        check(np.vstack([qa, qb]), self.weights, self.resolution, 0.0, True, *self.kernel_args,
              out)
        return bool(out[0]), int(out[1])

    def edge_valid(self, qa: ArrayLike, qb: ArrayLike) -> tuple[bool, int]:
        """Whether the straight joint-space edge qa -> qb (n,) is certified free, endpoints
        included, and the number of states checked."""
        qa, qb = joint_array(self.robot, qa, "qa"), joint_array(self.robot, qb, "qb")
        return self.interior_free(qa, qb)

    def path_valid(self, path: ArrayLike) -> bool:
        """Every waypoint of path (k, n) and every edge between them certified free."""
        path = joint_array(self.robot, path, "path")
        if not self.valid_states(path.reshape(-1, self.n)).all():
            return False
        return all(self.interior_free(a, b)[0] for a, b in zip(path[:-1], path[1:]))
