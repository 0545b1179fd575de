"""The collision checker: the arm's spheres and capsules against a scene and against each other.

A `CollisionModel` is what a robot's collision geometry is, derived once (like Pinocchio's
Model): the spheres and capsules in the frames the kinematic core moves them with, a bounding
sphere per link, the pairs of the arm's own parts that are tested (grouped by link pair), and
the displacement weights. A `CollisionChecker` puts a model in a scene; building one for a new
scene costs little (the scene's arrays only).

The link frames come from the kinematic core (`armkit.kinematics.core`: `pose_start`, `move`,
`then` on the chain's own packed arrays): the checker keeps no forward kinematics of its own.

Clearance and validity. The clearance f(q) of a state is the smallest gap between a part of the
arm and an obstacle, or half the smallest gap between two parts of the arm that are tested
against each other (both may move); negative where they overlap. A state is valid when
``f > padding`` (0 unless asked): nothing overlaps. Each link's bounding sphere is tested first,
against each obstacle's box and against the other links' spheres, and only a link that comes
within reach has its own parts tested.

Certification. Between two configurations on a straight joint-space line, a point of the arm
moves at most ``D = sum_i w_i |dq_i|`` (`displacement_weights`). A piece of an edge between
checked states a and b is certified when ``f_a + f_b > D_ab + 2 padding``: every configuration
on it keeps ``(f_a + f_b - D_ab) / 2 > padding``, between its checked states too. Pieces that
fail the test are halved (coarse to fine, breadth first), so states are dense only near
obstacles: a valid state with a tiny clearance makes its edges check more finely. A piece whose
D is already below the checker's `resolution` and still not certified, or an invalid state,
fails the edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.jit import kernel, numba_threads, prange
from armkit.kinematics.core import (
    joint_count,
    joint_kind,
    joint_value,
    link_at,
    move,
    pose_start,
    pre_at,
    then,
)
from armkit.kinematics.forward import fk_frames
from armkit.model.robot import Robot, joint_array
from armkit.planning.clock import clock_gettime, expired, timer
from armkit.planning.distances import local_distance, point_distance, segment_segment, to_local
from armkit.planning.geometry import ArmGeometry, arm_geometry, link_to_body
from armkit.planning.scene import BOX, CAPSULE, SPHERE, Scene, SceneKernel, scene_kernel
from armkit.threads import threads_for

_jit = kernel(cache=True, nogil=True)
_inline = kernel(cache=True, nogil=True, inline="always")

RESOLUTION = 1e-3           # m: the default smallest piece an edge is split into
FREE, BLOCKED, TIMED_OUT = 1, 0, 2      # what `edge_free` found
_ABOVE = 1e-12              # m: a clearance asked for up to a bound is asked a little above it

# --- the model's arrays -----------------------------------------------------------------------
#
# G (float) and H (int), built once per robot (`CollisionModel`), read through the accessors
# below. m parts (spheres and capsules) on L links, in C clusters (a few parts of one link near
# each other); LP link pairs, CP cluster pairs and P part pairs tested against each other:
#
#   H: m, L, C, LP, CP, P, then per link (body, first cluster, cluster count), per cluster
#      (body, first part, part count), per link pair (link a, link b, first cluster pair, count),
#      per cluster pair (cluster a, cluster b, first part pair, count), per part pair (i, j), per
#      part 1 if a sphere. A body is the moving joint whose frame (after its motion) carries the
#      link, -1 for the base (its parts are stored in world coordinates).
#   G: per part a, b (3 each, in its body's frame) and radius; per link and per cluster its
#      bounding sphere (centre in its body's frame, radius); the displacement weights (one per
#      joint value).
#
# S (float) and K (int), per scene: K is the obstacle count then their kinds; S per obstacle its
# inverse pose (3 x 4), dimensions (3), bounding ball (centre 3, radius), box in the world
# (lower and upper corners), then the box of the whole scene.
#
# W (float), work per call: the bodies' frames (12 each), the links' world centres (3 each), the
# clusters' world centres and whether their parts are placed (1) or not (0), the parts' world
# ends (6 each), scratch (14), the cluster and obstacle of the last closest pair found (-1: none;
# consecutive states are alike, and a small best early lets the bounds skip more), a state (n).

PART, SPHERE_ROW, OBSTACLE = 7, 4, 25


@_inline
def link_row(H, k):
    """Where link k's (body, first cluster, cluster count) start in H."""
    return 6 + 3 * k


@_inline
def cluster_row(H, c):
    """Where cluster c's (body, first part, part count) start in H."""
    return 6 + 3 * H[1] + 3 * c


@_inline
def link_pair_row(H, k):
    """Where link pair k's (link a, link b, first cluster pair, count) start in H."""
    return 6 + 3 * H[1] + 3 * H[2] + 4 * k


@_inline
def cluster_pair_row(H, k):
    """Where cluster pair k's (cluster a, cluster b, first part pair, count) start in H."""
    return 6 + 3 * H[1] + 3 * H[2] + 4 * H[3] + 4 * k


@_inline
def part_pair_row(H, p):
    """Where part pair p's (i, j) start in H."""
    return 6 + 3 * H[1] + 3 * H[2] + 4 * H[3] + 4 * H[4] + 2 * p


@_inline
def is_sphere(H, e):
    """Whether part e is a sphere (its ends coincide)."""
    return H[6 + 3 * H[1] + 3 * H[2] + 4 * H[3] + 4 * H[4] + 2 * H[5] + e] != 0


@_inline
def link_sphere_at(H, k):
    """Where link k's bounding sphere (centre, radius) starts in G."""
    return PART * H[0] + SPHERE_ROW * k


@_inline
def cluster_sphere_at(H, c):
    """Where cluster c's bounding sphere (centre, radius) starts in G."""
    return PART * H[0] + SPHERE_ROW * (H[1] + c)


@_inline
def weights_at(H):
    """Where the displacement weights start in G."""
    return PART * H[0] + SPHERE_ROW * (H[1] + H[2])


@_inline
def scene_box_at(K):
    """Where the box holding the whole scene starts in S."""
    return OBSTACLE * K[0]


@_inline
def work_size(I, H, n):
    """The length of the work array W for a state of n values."""
    return 12 * joint_count(I) + 3 * H[1] + 4 * H[2] + 6 * H[0] + 16 + n


@_inline
def new_work(M, n):
    """A work array W for the model and scene M and states of n values, with no closest pair
    known yet."""
    W = np.empty(work_size(M[1], M[3], n))
    at = W.shape[0] - n - 2
    W[at], W[at + 1] = -1.0, -1.0
    return W


@_inline
def _box_gap(x, y, z, S, at):
    """Distance from the point (x, y, z) to the axis-aligned box S[at:at + 6] (lower corner,
    upper corner); 0 inside."""
    dx = max(max(S[at] - x, x - S[at + 3]), 0.0)
    dy = max(max(S[at + 1] - y, y - S[at + 4]), 0.0)
    dz = max(max(S[at + 2] - z, z - S[at + 5]), 0.0)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@_inline
def _to_world(W, f, x, y, z, o):
    """The point (x, y, z) of the body whose frame is W[f:f + 12] into W[o:o + 3]."""
    W[o] = W[f] * x + W[f + 1] * y + W[f + 2] * z + W[f + 3]
    W[o + 1] = W[f + 4] * x + W[f + 5] * y + W[f + 6] * z + W[f + 7]
    W[o + 2] = W[f + 8] * x + W[f + 9] * y + W[f + 10] * z + W[f + 11]


@_inline
def _apart(W, a, b, reach):
    """Whether the points W[a:a + 3] and W[b:b + 3] are at least reach apart (reach > 0)."""
    dx, dy, dz = W[a] - W[b], W[a + 1] - W[b + 1], W[a + 2] - W[b + 2]
    return reach > 0.0 and dx * dx + dy * dy + dz * dz >= reach * reach


@_jit
def free_distance(q, M, W, floor, cap):
    """The clearance (m) of the state q (n,): ``min(gap to any obstacle, gap between two tested
    parts / 2)``, returned as ``min(that, cap)``; it stops early, with some value <= floor,
    once a pair is within floor. M: (F, I, G, H, S, K), the chain (`KernelChain.floats`,
    `.ints`), the model and the scene (`CollisionChecker.arrays`); W: work (`work_size`).

    Bounding spheres first: a link pair (then a cluster pair) whose spheres are more than
    2 best apart cannot lower best, nor a link (then a cluster) more than best from an
    obstacle's box; part pairs are compared by squared distance before a square root."""
    F, I, G, H, S, K = M
    nj = joint_count(I)
    m, L, C, LP = H[0], H[1], H[2], H[3]
    wl = 12 * nj
    wc = wl + 3 * L
    we = wc + 4 * C
    ws = we + 6 * m
    bodies = H[link_row(H, L - 1)] + 1 if L > 0 else 0        # links are ordered by body
    T = pose_start(F, pre_at(nj))
    for i in range(bodies):
        T = move(T, joint_kind(I, i), joint_value(q, F, I, nj, i))
        f = 12 * i
        (W[f], W[f + 1], W[f + 2], W[f + 3], W[f + 4], W[f + 5], W[f + 6], W[f + 7], W[f + 8],
         W[f + 9], W[f + 10], W[f + 11]) = T
        if i + 1 < bodies:
            T = then(T, F, link_at(nj, i))
    for k in range(L):
        body, g, o = H[link_row(H, k)], link_sphere_at(H, k), wl + 3 * k
        if body < 0:
            W[o], W[o + 1], W[o + 2] = G[g], G[g + 1], G[g + 2]
        else:
            _to_world(W, 12 * body, G[g], G[g + 1], G[g + 2], o)
    for c in range(C):
        at, g, o = cluster_row(H, c), cluster_sphere_at(H, c), wc + 4 * c
        if H[at] < 0:
            W[o], W[o + 1], W[o + 2] = G[g], G[g + 1], G[g + 2]
        else:
            _to_world(W, 12 * H[at], G[g], G[g + 1], G[g + 2], o)
        W[o + 3] = 0.0                      # its parts not placed yet
    best = cap
    # Row offsets read once: the loops below are the hot ones.
    h_cp, h_pp, h_sphere = cluster_pair_row(H, 0), part_pair_row(H, 0), part_pair_row(H, H[5])
    g_link, g_cluster = link_sphere_at(H, 0), cluster_sphere_at(H, 0)
    # The arm against the scene first: an obstacle is most often what is nearest, and a small
    # best early lets the bounds skip more pairs. Pass k = -1 tries the last closest pair
    # (W[wt]: its cluster and obstacle) before every link's.
    nobs = K[0]
    union = scene_box_at(K)
    wt = ws + 14
    for k in range(-1, L if nobs > 0 else 0):
        x = y = z = 0.0
        radius = np.inf                     # pass -1 passes the links' bounds
        if k < 0:
            if W[wt] < 0.0:
                continue
            cfirst, ccount, ob0, ob1 = int(W[wt]), 1, int(W[wt + 1]), int(W[wt + 1]) + 1
        else:
            o = wl + 3 * k
            x, y, z, radius = W[o], W[o + 1], W[o + 2], G[g_link + 4 * k + 3]
            if _box_gap(x, y, z, S, union) - radius >= best:
                continue
            at = link_row(H, k)
            cfirst, ccount, ob0, ob1 = H[at + 1], H[at + 2], 0, nobs
        for ob in range(ob0, ob1):
            s = OBSTACLE * ob
            if _box_gap(x, y, z, S, s + 19) - radius >= best:
                continue
            kind = K[1 + ob]
            for ca in range(cfirst, cfirst + ccount):
                oc = wc + 4 * ca
                if _box_gap(W[oc], W[oc + 1], W[oc + 2], S, s + 19) - \
                        G[g_cluster + 4 * ca + 3] >= best:
                    continue
                cb = ca
                # Their parts placed (once per state). (Written out here, not a helper: numba
                # calls a helper that takes arrays instead of inlining it.)
                for c in (ca, cb):
                    if W[wc + 4 * c + 3] == 0.0:
                        at = cluster_row(H, c)
                        body, e0, e1 = H[at], H[at + 1], H[at + 1] + H[at + 2]
                        for e in range(e0, e1):
                            ge, o = PART * e, we + 6 * e
                            if body < 0:
                                for j in range(6):
                                    W[o + j] = G[ge + j]
                            else:
                                _to_world(W, 12 * body, G[ge], G[ge + 1], G[ge + 2], o)
                                if H[h_sphere + e] != 0:
                                    W[o + 3], W[o + 4], W[o + 5] = W[o], W[o + 1], W[o + 2]
                                else:
                                    _to_world(W, 12 * body, G[ge + 3], G[ge + 4], G[ge + 5],
                                              o + 3)
                        W[wc + 4 * c + 3] = 1.0
                at = cluster_row(H, ca)
                for e in range(H[at + 1], H[at + 1] + H[at + 2]):
                    u = we + 6 * e
                    if H[h_sphere + e] != 0:
                        px, py, pz = W[u], W[u + 1], W[u + 2]
                        d = point_distance(
                            kind, S, s + 12,
                            S[s] * px + S[s + 1] * py + S[s + 2] * pz + S[s + 3],
                            S[s + 4] * px + S[s + 5] * py + S[s + 6] * pz + S[s + 7],
                            S[s + 8] * px + S[s + 9] * py + S[s + 10] * pz + S[s + 11])
                    else:
                        to_local(S, s, W[u], W[u + 1], W[u + 2], W[u + 3], W[u + 4],
                                 W[u + 5], W, ws)
                        d = local_distance(kind, S, s + 12, W, ws)
                    d -= G[PART * e + 6]
                    if d < best:
                        best = d
                        W[wt], W[wt + 1] = ca, ob
                        if best <= floor:
                            return best
    # The arm against itself.
    for k in range(LP):
        at = link_pair_row(H, k)
        la, lb, first, count = H[at], H[at + 1], H[at + 2], H[at + 3]
        if _apart(W, wl + 3 * la, wl + 3 * lb, 2.0 * best + G[g_link + 4 * la + 3]
                  + G[g_link + 4 * lb + 3]):
            continue
        for cp in range(first, first + count):
            at = h_cp + 4 * cp
            ca, cb, pfirst, pcount = H[at], H[at + 1], H[at + 2], H[at + 3]
            if _apart(W, wc + 4 * ca, wc + 4 * cb, 2.0 * best + G[g_cluster + 4 * ca + 3]
                      + G[g_cluster + 4 * cb + 3]):
                continue
            # Their parts placed (once per state). (Written out here, not a helper: numba
            # calls a helper that takes arrays instead of inlining it.)
            for c in (ca, cb):
                if W[wc + 4 * c + 3] == 0.0:
                    at = cluster_row(H, c)
                    body, e0, e1 = H[at], H[at + 1], H[at + 1] + H[at + 2]
                    for e in range(e0, e1):
                        ge, o = PART * e, we + 6 * e
                        if body < 0:
                            for j in range(6):
                                W[o + j] = G[ge + j]
                        else:
                            _to_world(W, 12 * body, G[ge], G[ge + 1], G[ge + 2], o)
                            if H[h_sphere + e] != 0:
                                W[o + 3], W[o + 4], W[o + 5] = W[o], W[o + 1], W[o + 2]
                            else:
                                _to_world(W, 12 * body, G[ge + 3], G[ge + 4], G[ge + 5],
                                          o + 3)
                    W[wc + 4 * c + 3] = 1.0
            for p in range(pfirst, pfirst + pcount):
                i, j = H[h_pp + 2 * p], H[h_pp + 2 * p + 1]
                u, v = we + 6 * i, we + 6 * j
                ri, rj = G[PART * i + 6], G[PART * j + 6]
                if H[h_sphere + i] != 0 and H[h_sphere + j] != 0:
                    if _apart(W, u, v, 2.0 * best + ri + rj):
                        continue
                    dx, dy, dz = W[u] - W[v], W[u + 1] - W[v + 1], W[u + 2] - W[v + 2]
                    d = math.sqrt(dx * dx + dy * dy + dz * dz)
                else:
                    d = segment_segment(W[u], W[u + 1], W[u + 2], W[u + 3], W[u + 4], W[u + 5],
                                        W[v], W[v + 1], W[v + 2], W[v + 3], W[v + 4], W[v + 5])
                gap = 0.5 * (d - ri - rj)
                if gap < best:
                    best = gap
                    if best <= floor:
                        return best
    return best


@_jit
def edge_free(qa, qb, M, W, padding, resolution, queue, fa_known, clock, deadline, every):
    """Whether the straight joint-space edge qa -> qb (n,) is certified free: (FREE, BLOCKED
    or TIMED_OUT, states checked, qb's clearance found (capped)).

    See the module's note: a piece between checked states a and b on which no point of the
    arm moves more than D is certified when ``f_a + f_b > D + 2 padding``; pieces not
    certified are halved, breadth first, down to `resolution` (m). Both ends are checked
    (qa not when fa_known, a lower bound of its clearance, is above padding). queue (4, size):
    work (a larger one is made when the edge needs it). The clock (`armkit.planning.clock`) is
    read every `every` states (0: never); past the deadline the edge is TIMED_OUT.
    """
    n = qa.shape[0]
    G, H = M[2], M[3]
    w = weights_at(H)
    total = 0.0
    for i in range(n):
        total += G[w + i] * abs(qb[i] - qa[i])
    size = 2 * int(math.ceil(total / resolution)) + 8
    if size > queue.shape[1]:
        queue = np.empty((4, size))
    else:
        size = queue.shape[1]
    q = W[W.shape[0] - n:]
    end_cap = total + 2.0 * padding + _ABOVE
    checked = 0
    fa = fa_known
    if not fa > padding:
        for j in range(n):
            q[j] = qa[j]
        fa = free_distance(q, M, W, padding, end_cap)
        checked += 1
        if fa <= padding:
            return BLOCKED, checked, fa
    for j in range(n):
        q[j] = qb[j]
    fb = free_distance(q, M, W, padding, end_cap)
    checked += 1
    if fb <= padding:
        return BLOCKED, checked, fb
    queue[0, 0], queue[1, 0], queue[2, 0], queue[3, 0] = 0.0, 1.0, fa, fb
    head, tail = 0, 1
    while head != tail:
        a_t, b_t, a_f, b_f = queue[0, head], queue[1, head], queue[2, head], queue[3, head]
        head = head + 1 if head + 1 < size else 0
        span = (b_t - a_t) * total
        if a_f + b_f > span + 2.0 * padding:
            continue
        if span <= resolution:
            return BLOCKED, checked, fb
        if every > 0 and checked % every == 0 and expired(clock, deadline):
            return TIMED_OUT, checked, fb
        t = 0.5 * (a_t + b_t)
        for j in range(n):
            q[j] = qa[j] + t * (qb[j] - qa[j])
        f = free_distance(q, M, W, padding, 0.5 * span + 2.0 * padding + _ABOVE)
        checked += 1
        if f <= padding:
            return BLOCKED, checked, f
        queue[0, tail], queue[1, tail], queue[2, tail], queue[3, tail] = a_t, t, a_f, f
        tail = tail + 1 if tail + 1 < size else 0
        queue[0, tail], queue[1, tail], queue[2, tail], queue[3, tail] = t, b_t, f, b_f
        tail = tail + 1 if tail + 1 < size else 0
    return FREE, checked, fb


BATCH_CHUNK = 1024          # states per task of a parallel batch
PARALLEL_FROM = 4096        # states worth starting a thread for (`armkit.threads.threads_for`)
LIGHT_STATES = 1024         # states checked as Python before the kernel is compiled (`armkit.jit`)


@_inline
def _states_span(Q, M, floor, cap, out, start, stop):
    """`states_kernel` for the states start .. stop - 1 of Q (k, n), with work of its own."""
    W = new_work(M, 0)
    f = np.nan
    for s in range(start, stop):
        finite = True
        for j in range(Q.shape[1]):
            if not math.isfinite(Q[s, j]):
                finite = False
        f = free_distance(Q[s], M, W, floor, cap) if finite else np.nan
        if out.shape[0]:
            out[s] = f
    return f


@_jit
def states_kernel(Q, M, floor, cap, out):
    """`free_distance` (with floor and cap) of the states Q (k, n) into out (k,), or with out
    empty (0,) only returned (one state, nothing written); NaN for a state with a value that
    is not finite. Returns the last state's. The states go in chunks of BATCH_CHUNK, each
    starting afresh (no closest pair carried over), as in `states_parallel`: both give the
    same values, early verdicts included."""
    f = np.nan
    for start in range(0, Q.shape[0], BATCH_CHUNK):
        f = _states_span(Q, M, floor, cap, out, start, min(Q.shape[0], start + BATCH_CHUNK))
    return f


@kernel(cache=True, nogil=True, parallel=True)
def states_parallel(Q, M, floor, cap, out):
    """`states_kernel` into out (k,), in chunks spread over numba's threads (compiled at the
    first large batch only)."""
    count = Q.shape[0]
    for c in prange((count + BATCH_CHUNK - 1) // BATCH_CHUNK):
        _states_span(Q, M, floor, cap, out, c * BATCH_CHUNK,
                     min(count, (c + 1) * BATCH_CHUNK))


@_jit
def polyline_kernel(P, M, padding, resolution, queue, clock, deadline, every):
    """Whether every waypoint of P (k, n) and every straight edge between consecutive ones is
    certified free (`edge_free`; one waypoint: its state): (FREE, BLOCKED or TIMED_OUT,
    states checked)."""
    W = new_work(M, P.shape[1])
    checked = 0
    for i in range(max(P.shape[0] - 1, 1)):          # one waypoint: the edge to itself
        status, c, _ = edge_free(P[i], P[min(i + 1, P.shape[0] - 1)], M, W, padding,
                                 resolution, queue, -1.0, clock, deadline, every)
        checked += c
        if status != FREE:
            return status, checked
    return FREE, checked


# --- Python side -------------------------------------------------------------------------------

def arm_capsules(robot: Robot, geometry: ArmGeometry, q: ArrayLike) -> tuple[NDArray, NDArray]:
    """The parts' segments in the base frame at q (n,): a, b, each (m, 3), m (a sphere's two
    ends coincide)."""
    frames = fk_frames(robot, q)
    a = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.a) + \
        frames[geometry.link, :3, 3]
    b = np.einsum("mij,mj->mi", frames[geometry.link, :3, :3], geometry.b) + \
        frames[geometry.link, :3, 3]
    return a, b


def displacement_weights(robot: Robot, geometry: ArmGeometry) -> NDArray:
    """Per joint value, how far (m) a point of the arm can move per unit of its motion (rad or
    m): for a revolute joint a bound on the distance of any part's point riding on it from its
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
    moving = geometry.link > 0
    ends = np.concatenate([geometry.a, geometry.b])[np.r_[moving, moving]]
    links = np.r_[geometry.link[moving], geometry.link[moving]]
    # Each part's axis end from its body's origin (a gap is its axis's distance less its
    # radius: the axis's displacement bounds the gap's change).
    extent = np.linalg.norm(np.einsum("kij,kj->ki", to_body[links, :3, :3], ends)
                            + to_body[links, :3, 3], axis=1)
    for j in range(nj):
        here = extent[links - 1 == j]
        if len(here):
            for i in range(j + 1):
                reach[i] = max(reach[i], step[i:j].sum() + here.max())
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


def scene_arrays(scene: Scene) -> tuple[NDArray, NDArray]:
    """The scene as the kernels take it: S (float) and K (int) (see the layout above)."""
    k = scene_kernel(scene)
    nobs = len(k.kind)
    half = world_half_sizes(k)
    boxes = np.hstack([k.center - half, k.center + half]).reshape(nobs, 6)
    per = np.hstack([k.inverse.reshape(nobs, 12), k.dims, k.center, k.bound[:, None], boxes])
    union = np.r_[boxes[:, :3].min(axis=0, initial=np.inf),
                  boxes[:, 3:].max(axis=0, initial=-np.inf)]
    S = np.r_[per.reshape(-1), union].astype(float)
    K = np.r_[nobs, k.kind].astype(np.int64)
    return S, K


def _bounding_spheres(a: NDArray, b: NDArray, radius: NDArray) -> tuple[NDArray, float]:
    """A sphere (centre (3,), radius) holding the parts (capsules a-b of radius, each (k, 3)):
    centred on the middle of their box."""
    lo = np.minimum(a, b) - radius[:, None]
    hi = np.maximum(a, b) + radius[:, None]
    c = 0.5 * (lo.min(axis=0) + hi.max(axis=0))
    r = np.max(np.maximum(np.linalg.norm(a - c, axis=1), np.linalg.norm(b - c, axis=1))
               + radius)
    return c, float(r) * (1 + 1e-12) + 1e-12


CLUSTER = 4                 # parts per cluster (a few parts near each other on one link)


def _clusters(link: NDArray, centres: NDArray) -> list[NDArray]:
    """The parts' indices in clusters of at most CLUSTER, each on one link, the links in order:
    the parts of a link sorted along the main axis of their centres (m, 3), then cut."""
    out = []
    for k in np.unique(link):
        idx = np.flatnonzero(link == k)
        if len(idx) > CLUSTER:
            c = centres[idx] - centres[idx].mean(axis=0)
            axis = np.linalg.svd(c, full_matrices=False)[2][0]
            idx = idx[np.argsort(c @ axis, kind="stable")]
        out.extend(idx[i:i + CLUSTER] for i in range(0, len(idx), CLUSTER))
    return out


@dataclass(frozen=True, eq=False)
class CollisionModel:
    """A robot's collision geometry in the checker's kernel form, built once per robot.

    Parameters
    ----------
    robot : Robot
    geometry : ArmGeometry, optional
        Default: `arm_geometry(robot)` (the robot file's parts, its URDF's, or capsules).

    Attributes
    ----------
    weights : ndarray, (n,)
        The displacement bound per unit joint motion (m/rad, or 1 for prismatic joints).
    arrays : (ndarray, ndarray)
        G (float) and H (int), as the kernels read them.
    link_pairs, part_pairs : int
        The link pairs and the part pairs tested for self-collision.
    """

    robot: Robot
    geometry: ArmGeometry | None = None
    weights: NDArray = field(init=False, repr=False)
    arrays: tuple = field(init=False, repr=False)
    link_pairs: int = field(init=False)
    part_pairs: int = field(init=False)

    def __post_init__(self):
        if not isinstance(self.robot, Robot):
            raise InputError(f"robot: expected a Robot, found {type(self.robot).__name__}")
        geometry = self.geometry if self.geometry is not None else arm_geometry(self.robot)
        if not isinstance(geometry, ArmGeometry):
            raise InputError(f"geometry: expected an ArmGeometry, found "
                             f"{type(geometry).__name__}")
        last = self.robot.chain.n_joints
        if len(geometry) and geometry.link.max() > last:
            raise InputError(f"geometry: expected links 0 .. {last} of "
                             f"{self.robot.name}, found link {geometry.link.max()}")
        weights = displacement_weights(self.robot, geometry)
        # Parts in their bodies' frames, ordered by link and by cluster within a link (the
        # base's in world coordinates).
        to_body = link_to_body(self.robot)
        link = geometry.link
        T = np.where((link == 0)[:, None, None], self.robot.chain.T_base, to_body[link])
        a = np.einsum("kij,kj->ki", T[:, :3, :3], geometry.a) + T[:, :3, 3]
        b = np.einsum("kij,kj->ki", T[:, :3, :3], geometry.b) + T[:, :3, 3]
        clusters = _clusters(link, 0.5 * (geometry.a + geometry.b))
        order = np.concatenate(clusters) if clusters else np.empty(0, np.int64)
        a, b, radius, link = a[order], b[order], geometry.radius[order], link[order]
        sphere = np.all(geometry.a[order] == geometry.b[order], axis=1)
        sizes = np.array([len(c) for c in clusters], dtype=np.int64)
        first = np.cumsum(sizes) - sizes
        cluster_link = link[first]
        links, link_first, link_count = np.unique(cluster_link, return_index=True,
                                                  return_counts=True)
        link_of = np.searchsorted(links, cluster_link)              # per cluster
        cluster_of = np.repeat(np.arange(len(clusters)), sizes)     # per part
        link_spheres = [_bounding_spheres(a[link == k], b[link == k], radius[link == k])
                        for k in links]
        cluster_spheres = [_bounding_spheres(a[f:f + c], b[f:f + c], radius[f:f + c])
                           for f, c in zip(first, sizes)]
        rank = np.empty(len(order), np.int64)
        rank[order] = np.arange(len(order))
        pairs = np.sort(rank[geometry.self_pairs()].reshape(-1, 2), axis=1)
        # Part pairs sorted by link pair, then cluster pair: each a contiguous run.
        C, L = max(len(clusters), 1), max(len(links), 1)
        ci, cj = cluster_of[pairs[:, 0]], cluster_of[pairs[:, 1]]
        key = (link_of[ci] * L + link_of[cj]) * C * C + ci * C + cj
        sort = np.lexsort((pairs[:, 1], pairs[:, 0], key))
        pairs, key = pairs[sort], key[sort]
        cp_keys, cp_first, cp_count = np.unique(key, return_index=True, return_counts=True)
        cp_a, cp_b = (cp_keys % (C * C)) // C, cp_keys % C
        lp_keys, lp_first, lp_count = np.unique(cp_keys // (C * C), return_index=True,
                                                return_counts=True)
        H = np.concatenate([
            [len(order), len(links), len(clusters), len(lp_keys), len(cp_keys), len(pairs)],
            np.column_stack([links - 1, link_first, link_count]).reshape(-1),
            np.column_stack([cluster_link - 1, first, sizes]).reshape(-1),
            np.column_stack([lp_keys // L, lp_keys % L, lp_first, lp_count]).reshape(-1),
            np.column_stack([cp_a, cp_b, cp_first, cp_count]).reshape(-1),
            pairs.reshape(-1), sphere.astype(np.int64)]).astype(np.int64)
        G = np.concatenate([np.column_stack([a, b, radius]).reshape(-1),
                            np.array([[*c, r] for c, r in link_spheres + cluster_spheres]
                                     ).reshape(-1), weights]).astype(float)
        for x in (weights, G, H):
            x.setflags(write=False)
        for name, value in (("geometry", geometry), ("weights", weights), ("arrays", (G, H)),
                            ("link_pairs", len(lp_keys)), ("part_pairs", len(pairs))):
            object.__setattr__(self, name, value)


_NONE = np.empty(0)               # "one state, return it": nothing is written to it
QUEUE_SIZE = 1024                 # the planners' edge-test work: longer edges make their own
_NO_DEADLINE = timer(math.inf)


def _writable(a: NDArray) -> NDArray:
    """a as a C-contiguous writable float array: the kernels' one signature (a read-only
    array would compile them again)."""
    a = np.ascontiguousarray(a, dtype=float)
    return a if a.flags.writeable else a.copy()


@dataclass(frozen=True, eq=False)
class CollisionChecker:
    """A robot's collision model in one scene; immutable, cheap to build for a new scene.

    Parameters
    ----------
    robot : Robot or CollisionModel
        A robot (its model is built here), or a model built once for many scenes.
    scene : Scene, optional
        No obstacles if omitted (self-collision only).
    geometry : ArmGeometry, optional
        With a robot: its parts (default `arm_geometry`).
    resolution : float
        m: the smallest piece (in arm displacement) an edge is split into while certifying
        it (see the module's note); default 1 mm.
    padding : float
        m: a valid state keeps every part more than this from every obstacle (twice this from
        the arm's other tested parts); default 0, nothing overlaps.

    Attributes
    ----------
    model : CollisionModel
    weights : ndarray, (n,)
        The displacement bound per unit joint motion (m/rad, or 1 for prismatic joints).
    arrays : tuple
        What the kernels take: the chain (F, I), the model (G, H), the scene (S, K).
    """

    robot: Robot
    scene: Scene = field(default_factory=Scene)
    geometry: ArmGeometry | None = None
    resolution: float = RESOLUTION
    padding: float = 0.0
    model: CollisionModel = field(init=False, repr=False)
    weights: NDArray = field(init=False, repr=False)
    arrays: tuple = field(init=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.scene, Scene):
            raise InputError(f"scene: expected a Scene, found {type(self.scene).__name__}")
        for name, what in (("resolution", "a positive"), ("padding", "a non-negative")):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.integer, np.floating))
                    and math.isfinite(value) and (value > 0 or name == "padding" and value == 0)):
                raise InputError(f"{name}: expected {what} length (m), found {value!r}")
            object.__setattr__(self, name, float(value))
        if isinstance(self.robot, CollisionModel):
            model = self.robot
            if self.geometry is not None and self.geometry is not model.geometry:
                raise InputError("geometry: expected none with a CollisionModel (it holds its "
                                 "geometry), found one")
        else:
            model = CollisionModel(self.robot, self.geometry)
        chain = model.robot.chain.kernel
        S, K = scene_arrays(self.scene)
        for name, value in (("robot", model.robot), ("geometry", model.geometry),
                            ("model", model), ("weights", model.weights),
                            ("arrays", (chain.floats, chain.ints, *model.arrays, S, K))):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "_one_shape", (model.robot.n,))
        # A verdict needs the clearance only up to just above the padding.
        object.__setattr__(self, "_valid_cap", self.padding * (1 + 1e-9) + _ABOVE)

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
        if q.ndim == 0 or q.shape[-1] != self.n:
            joint_array(self.robot, q)                          # raises the precise error
        Q = _writable(q.reshape(-1, self.n))
        out = np.empty(Q.shape[0])
        threads = threads_for(Q.shape[0], PARALLEL_FROM)
        if threads == 1:
            states_kernel.sized(Q.shape[0], Q, self.arrays, floor, cap, out, few=LIGHT_STATES)
        else:
            with numba_threads(threads):
                states_parallel(Q, self.arrays, floor, cap, out)
        if np.isnan(out).any():
            raise InputError("q: expected finite joint values, found NaN or inf")
        return out.reshape(q.shape[:-1])

    def clearance(self, q: ArrayLike) -> NDArray:
        """Clearance f (m) at q (..., n): the smallest gap between a part of the arm and an
        obstacle, or half the smallest gap between two tested parts of the arm (both can
        move); (...,). <= 0 where they touch or overlap (minus the depth for spheres and
        capsules)."""
        if not (type(q) is np.ndarray and q.dtype == np.float64):
            q = joint_array(self.robot, q)
        return np.asarray(self._free(q, -np.inf, np.inf))

    def valid(self, q: ArrayLike) -> NDArray:
        """Clearance above the padding: nothing overlaps. (...,) bool."""
        if type(q) is np.ndarray and q.shape == self._one_shape and q.dtype == np.float64:
            flags = q.flags
            if flags.c_contiguous and flags.writeable:           # one state, straight in
                f = states_kernel.light(q[None], self.arrays, self.padding, self._valid_cap,
                                        _NONE)
                if f > self.padding:
                    return np.True_
                if math.isnan(f):
                    raise InputError("q: expected finite joint values, found NaN or inf")
                return np.False_
        if not (type(q) is np.ndarray and q.dtype == np.float64):
            q = joint_array(self.robot, q)
        return self._free(q, self.padding, self._valid_cap) > self.padding

    def __call__(self, q: ArrayLike) -> NDArray:
        """Same as `valid`: a checker is a validity callable on a batch of states."""
        return self.valid(q)

    def valid_states(self, Q: NDArray) -> NDArray:
        """`valid` for states (k, n) already checked for shape and values (the planners'
        call)."""
        if Q.shape[0] > LIGHT_STATES or not (Q.dtype == np.float64 and Q.flags.c_contiguous):
            return self._free(np.asarray(Q, dtype=float), self.padding, self._valid_cap) > \
                self.padding
        out = np.empty(Q.shape[0])
        states_kernel.light(Q, self.arrays, self.padding, self._valid_cap, out)
        return out > self.padding

    def polyline_free(self, path: NDArray, deadline: NDArray = _NO_DEADLINE
                      ) -> tuple[bool, int]:
        """Whether every waypoint of path (k, n) and every edge between them is certified free
        (no shape checks: the planners' call), and the states checked. An edge not finished
        by the deadline (`armkit.planning.clock.timer`) is not free."""
        status, checked = polyline_kernel.light(
            path if path.flags.writeable and path.flags.c_contiguous else _writable(path),
            self.arrays, self.padding, self.resolution, np.empty((4, QUEUE_SIZE)),
            clock_gettime, deadline,
            0 if deadline is _NO_DEADLINE else (16 if polyline_kernel.is_compiled else 1))
        return status == FREE, int(checked)

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
