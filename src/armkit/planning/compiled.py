"""The planning loop compiled, for armkit's own `CollisionChecker`: RRT, RRT-Connect and RRT*
and shortcutting, with the certified edge test (`collision.edge_free`) called inside the
kernel, no Python call per state.

Trees live in preallocated arrays (nodes (2, capacity, n): tree 0 grows from the start, tree 1
from the goals in RRT-Connect; with each node its free distance, so an edge from it does not
check it again), the nearest neighbour is a brute-force scan of the contiguous node array (a
few hundred nodes at most on the shelf: a spatial index does not pay), and the random numbers
come from a seeded splitmix64 generator whose state is an array: the same seed gives the same
path. The kernel runs until it finds a path, spends its iterations, passes its deadline (read
inside the loop through `armkit.planning.clock`) or pauses: as Python, a loop pauses every
`SLICE` s so that a kernel compiled meanwhile takes over. Python calls it again (growing the
arrays when a tree is full) until it is done; the state between calls is all in the arrays, so a
path does not depend on how the iterations were split.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from armkit.jit import kernel
from armkit.planning.clock import clock_gettime, expired, left, paused, paused_after
from armkit.planning.collision import (
    FREE,
    QUEUE_SIZE,
    TIMED_OUT,
    CollisionChecker,
    edge_free,
    new_work,
)

_jit = kernel(cache=True, nogil=True)

TRAPPED, ADVANCED, REACHED = 0, 1, 2
RUNNING, FOUND, FULL, PAUSED = 0, 1, 2, 3
# Counters (int64): iterations, states checked, the tree RRT-Connect extends next, the goal
# nodes of RRT* so far, and the path found: tree-0 node, tree-1 node or goal index.
ITERATIONS, CHECKED, SIDE, GOAL_NODES, END_A, END_B = range(6)


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)


@_jit
def _uniform(rng):
    """A float in [0, 1) from the splitmix64 generator whose state is rng[0] (uint64)."""
    s = rng[0] + _GOLDEN
    rng[0] = s
    z = (s ^ (s >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    z = z ^ (z >> _S31)
    return float(z >> _S11) * (1.0 / 9007199254740992.0)


@_jit
def _sample(out, lower, upper, goals, goal_bias, rng):
    """A uniform state inside the limits into out, or with probability goal_bias a goal."""
    if goal_bias > 0.0 and _uniform(rng) < goal_bias:
        g = min(int(_uniform(rng) * goals.shape[0]), goals.shape[0] - 1)
        _copy(out, goals[g])
    else:
        for j in range(out.shape[0]):
            out[j] = lower[j] + (upper[j] - lower[j]) * _uniform(rng)


@_jit
def _copy(dst, src):
    """dst[:] = src, as a loop (a slice assignment compiles numba's error formatting too)."""
    for j in range(dst.shape[0]):
        dst[j] = src[j]


@_jit
def _order(keys, count, idx):
    """idx[:count] = the indices 0 .. count - 1 sorted by keys, stable (insertion sort: the
    lists are short)."""
    for i in range(count):
        v, j = keys[i], i - 1
        while j >= 0 and keys[idx[j]] > v:
            idx[j + 1] = idx[j]
            j -= 1
        idx[j + 1] = i


@_jit
def _distance(a, b):
    s = 0.0
    for j in range(a.shape[0]):
        e = a[j] - b[j]
        s += e * e
    return math.sqrt(s)


@_jit
def _nearest(nodes, size, q):
    best, arg = np.inf, 0
    n = q.shape[0]
    for i in range(size):
        s = 0.0
        for j in range(n):
            e = nodes[i, j] - q[j]
            s += e * e
        if s < best:
            best, arg = s, i
    return arg


@_jit
def _extend(nodes, parent, cost, clear, size, t, target, step, q_new, M, W, padding, resolution,
            queue, counters, clock, deadline, every):
    """One step of tree t from its node nearest to target toward it: (status, new node)."""
    near = _nearest(nodes[t], size[t], target)
    q_near = nodes[t, near]
    dist = _distance(q_near, target)
    reached = dist <= step
    if reached:
        _copy(q_new, target)
    else:
        for j in range(q_new.shape[0]):
            q_new[j] = q_near[j] + (target[j] - q_near[j]) * (step / dist)
    status, checked, f_new = edge_free(q_near, q_new, M, W, padding, resolution, queue,
                                       clear[t, near], clock, deadline, every)
    counters[CHECKED] += checked
    if status != FREE:
        return TRAPPED, -1
    i = size[t]
    _copy(nodes[t, i], q_new)
    parent[t, i] = near
    cost[t, i] = cost[t, near] + min(dist, step)
    clear[t, i] = f_new
    size[t] += 1
    return (REACHED if reached else ADVANCED), i


# The planners' kernels share one signature (`plan_compiled` calls one of them until it is
# done): run until counters[ITERATIONS] reaches stop; return FOUND (counters END_A, END_B say
# where), RUNNING (the budget of this call spent) or FULL (a tree has fewer than margin free
# rows: grow the arrays, call again).

@_jit
def grow_rrt(stop, margin, step, goal_bias, gamma, padding, resolution, goals, lower, upper,
             nodes, parent, cost, clear, size, child, sibling, goal_of, goal_nodes, counters,
             best, rng, queue, M, clock, deadline, every):
    """RRT with a fixed step: toward a sample (a goal with probability goal_bias); done when a
    new node joins a goal within a step by a certified edge (END_A the node, END_B the
    goal)."""
    n = goals.shape[1]
    W = new_work(M, n)
    capacity = nodes.shape[1]
    q_rand, q_new = np.empty(n), np.empty(n)
    start_tree = counters[SIDE] * 0                   # 0, not a literal: one _extend compiled
    goal_dist = np.empty(goals.shape[0])
    goal_ids = np.empty(goals.shape[0], np.int64)
    while counters[ITERATIONS] < stop:
        if size[0] + margin > capacity or size[1] + margin > capacity:
            return FULL
        if paused(clock, deadline):
            return PAUSED
        counters[ITERATIONS] += 1
        _sample(q_rand, lower, upper, goals, goal_bias, rng)
        status, new = _extend(nodes, parent, cost, clear, size, start_tree, q_rand, step, q_new,
                              M, W, padding, resolution, queue, counters, clock, deadline, every)
        if status == TRAPPED:
            continue
        q = nodes[0, new]
        for g in range(goals.shape[0]):
            goal_dist[g] = _distance(goals[g], q)
        _order(goal_dist, goals.shape[0], goal_ids)
        for s in range(goals.shape[0]):
            g = goal_ids[s]
            dg = goal_dist[g]
            if dg > step:
                break
            free = dg == 0.0
            if not free:
                status, checked, _ = edge_free(q, goals[g], M, W, padding, resolution, queue,
                                               -1.0, clock, deadline, every)
                free = status == FREE
                counters[CHECKED] += checked
            if free:
                counters[END_A], counters[END_B] = new, g
                return FOUND
    return RUNNING


@_jit
def grow_connect(stop, margin, step, goal_bias, gamma, padding, resolution, goals, lower, upper,
                 nodes, parent, cost, clear, size, child, sibling, goal_of, goal_nodes, counters,
                 best, rng, queue, M, clock, deadline, every):
    """RRT-Connect: tree SIDE extends toward a sample, the other connects greedily toward the
    new node; the trees swap (tree 0 from the start, tree 1 from the goals; END_A and END_B
    the nodes where they met)."""
    n = goals.shape[1]
    W = new_work(M, n)
    capacity = nodes.shape[1]
    q_rand, q_new = np.empty(n), np.empty(n)
    while counters[ITERATIONS] < stop:
        if size[0] + margin > capacity or size[1] + margin > capacity:
            return FULL
        if paused(clock, deadline):
            return PAUSED
        counters[ITERATIONS] += 1
        a = counters[SIDE]
        counters[SIDE] = 1 - a
        _sample(q_rand, lower, upper, goals, 0.0, rng)
        status, new = _extend(nodes, parent, cost, clear, size, a, q_rand, step, q_new, M, W,
                              padding, resolution, queue, counters, clock, deadline, every)
        if status == TRAPPED:
            continue
        target = nodes[a, new]
        status_b, last = ADVANCED, -1
        while status_b == ADVANCED:
            status_b, j = _extend(nodes, parent, cost, clear, size, 1 - a, target, step, q_new,
                                  M, W, padding, resolution, queue, counters, clock, deadline,
                                  every)
            if j >= 0:
                last = j
        if status_b == REACHED:
            counters[END_A] = new if a == 0 else last
            counters[END_B] = last if a == 0 else new
            return FOUND
    return RUNNING


@_jit
def grow_star(stop, margin, step, goal_bias, gamma, padding, resolution, goals, lower, upper,
              nodes, parent, cost, clear, size, child, sibling, goal_of, goal_nodes, counters,
              best, rng, queue, M, clock, deadline, every):
    """RRT*: each new node takes the cheapest certified parent among its neighbours within the
    shrinking radius and rewires them through itself (costs of their subtrees lowered through
    the child / sibling lists); it runs to stop, keeping the cheapest node joined to a goal
    (best[0] its cost, END_A the node, END_B the goal)."""
    n = goals.shape[1]
    W = new_work(M, n)
    capacity = nodes.shape[1]
    q_rand, q_new = np.empty(n), np.empty(n)
    dist = np.empty(capacity)
    near_ids = np.empty(capacity, np.int64)
    stack = np.empty(capacity, np.int64)
    keys = np.empty(capacity)
    key_ids = np.empty(capacity, np.int64)
    while counters[ITERATIONS] < stop:
        if size[0] + margin > capacity or size[1] + margin > capacity:
            return FULL
        if paused(clock, deadline):
            return PAUSED
        counters[ITERATIONS] += 1
        _sample(q_rand, lower, upper, goals, goal_bias, rng)
        # RRT*
        k = size[0]
        near = _nearest(nodes[0], k, q_rand)
        q_near = nodes[0, near]
        d_near = _distance(q_near, q_rand)
        if d_near <= step:
            _copy(q_new, q_rand)
        else:
            for j in range(n):
                q_new[j] = q_near[j] + (q_rand[j] - q_near[j]) * (step / d_near)
        status, checked, f_new = edge_free(q_near, q_new, M, W, padding, resolution, queue,
                                           clear[0, near], clock, deadline, every)
        free = status == FREE
        counters[CHECKED] += checked
        if not free:
            continue
        radius = min(gamma * (math.log(k + 1) / (k + 1)) ** (1.0 / n), step)
        count = 0
        for i in range(k):
            dist[i] = _distance(nodes[0, i], q_new)
            if dist[i] <= radius:
                near_ids[count] = i
                count += 1
        chosen, c_new = near, cost[0, near] + dist[near]
        for s in range(count):
            keys[s] = cost[0, near_ids[s]] + dist[near_ids[s]]
        _order(keys, count, key_ids)
        for r in range(count):
            s = key_ids[r]
            if keys[s] >= c_new:
                break
            j = near_ids[s]
            status, checked, _ = edge_free(nodes[0, j], q_new, M, W, padding, resolution,
                                           queue, -1.0, clock, deadline, every)
            free = status == FREE
            counters[CHECKED] += checked
            if free:
                chosen, c_new = j, keys[s]
                break
        new = k
        _copy(nodes[0, new], q_new)
        parent[0, new], cost[0, new], clear[0, new] = chosen, c_new, f_new
        child[new], goal_of[new] = -1, -1
        sibling[new] = child[chosen]
        child[chosen] = new
        size[0] += 1
        for s in range(count):
            j = near_ids[s]
            c = c_new + dist[j]
            if j == chosen or c >= cost[0, j]:
                continue
            status, checked, _ = edge_free(q_new, nodes[0, j], M, W, padding, resolution,
                                           queue, -1.0, clock, deadline, every)
            free = status == FREE
            counters[CHECKED] += checked
            if not free:
                continue
            old = parent[0, j]                      # j leaves its parent's child list
            if child[old] == j:
                child[old] = sibling[j]
            else:
                m = child[old]
                while sibling[m] != j:
                    m = sibling[m]
                sibling[m] = sibling[j]
            parent[0, j] = new
            sibling[j] = child[new]
            child[new] = j
            delta = c - cost[0, j]
            stack[0] = j                            # the subtree gets cheaper too
            top = 1
            while top > 0:
                top -= 1
                m = stack[top]
                cost[0, m] += delta
                m = child[m]
                while m >= 0:
                    stack[top] = m
                    top += 1
                    m = sibling[m]
        for g in range(goals.shape[0]):
            dg = _distance(goals[g], q_new)
            if dg > step:
                continue
            free = dg == 0.0
            if not free:
                status, checked, _ = edge_free(q_new, goals[g], M, W, padding, resolution,
                                               queue, -1.0, clock, deadline, every)
                free = status == FREE
                counters[CHECKED] += checked
            if free:
                goal_of[new] = g
                goal_nodes[counters[GOAL_NODES]] = new
                counters[GOAL_NODES] += 1
                break
        for s in range(counters[GOAL_NODES]):
            m = goal_nodes[s]
            c = cost[0, m] + _distance(goals[goal_of[m]], nodes[0, m])
            if c < best[0]:
                best[0] = c
                counters[END_A], counters[END_B] = m, goal_of[m]
    return RUNNING


@_jit
def shortcut_kernel(P, tries, min_gain, rng, padding, resolution, queue, M, counters, clock,
                    deadline, every, reduce):
    """Random shortcuts (two points drawn along the path by arc length, joined straight where
    the edge is certified), then greedy vertex reduction (each kept vertex joined to the
    farthest later vertex it reaches by a certified edge). P (k, n), no repeated rows. A draw
    whose shortcut would save less than min_gain times the path's length is not checked (it
    counts as a try): certifying a long edge near obstacles costs many states, and late draws
    mostly straighten what is nearly straight already. At the timer's pause it stops trying
    (counters[1] counts the tries made: a call with the path so far, the tries left and the
    same rng goes on as if never stopped); past the deadline the path so far, certified, is
    the result. The vertex reduction runs only if `reduce`. Returns the new path; states
    checked added to counters[0]. A piece of a certified edge is certified: the spliced ends
    need no check."""
    n = P.shape[1]
    W = new_work(M, n)
    cap = P.shape[0] + tries + 2
    p = np.empty((cap, n))
    k = P.shape[0]
    for i in range(k):
        _copy(p[i], P[i])
    cum = np.empty(cap)
    tmp = np.empty((cap, n))
    a, b = np.empty(n), np.empty(n)
    for _ in range(tries):
        if k < 3 or paused(clock, deadline):
            break
        counters[1] += 1
        cum[0] = 0.0
        for i in range(1, k):
            cum[i] = cum[i - 1] + _distance(p[i], p[i - 1])
        s1, s2 = _uniform(rng) * cum[k - 1], _uniform(rng) * cum[k - 1]
        if s1 > s2:
            s1, s2 = s2, s1
        i1 = _point_at(p, cum, k, s1, a)
        i2 = _point_at(p, cum, k, s2, b)
        if i1 == i2 or (s2 - s1) - _distance(a, b) < min_gain * cum[k - 1]:
            continue
        status, checked, _ = edge_free(a, b, M, W, padding, resolution, queue, -1.0, clock,
                                       deadline, every)
        counters[0] += checked
        if status == TIMED_OUT:
            break
        if status != FREE:
            continue
        # p[:i1 + 1], a, b, p[i2 + 1:], repeats dropped
        m = 0
        for i in range(i1 + 1):
            m = _push(tmp, m, p[i])
        m = _push(tmp, m, a)
        m = _push(tmp, m, b)
        for i in range(i2 + 1, k):
            m = _push(tmp, m, p[i])
        for i in range(m):
            _copy(p[i], tmp[i])
        k = m
    m = _reduce(p, k, tmp, M, W, padding, resolution, queue, counters, clock, deadline,
                every) if reduce else k
    result = np.empty((m, n))
    for i in range(m):
        _copy(result[i], p[i])
    return result


@_jit
def _reduce(p, k, tmp, M, W, padding, resolution, queue, counters, clock, deadline, every):
    """Greedy vertex reduction of p[:k] in place (each kept vertex joined to the farthest
    later vertex it reaches by a certified edge; past the deadline, to the next one); the new
    count."""
    _copy(tmp[0], p[0])
    m, i = 1, 0
    late = False
    while i < k - 1:
        for j in range(k - 1, i, -1):
            free = j == i + 1
            if not (free or late):
                late = expired(clock, deadline)
            if not (free or late):
                status, checked, _ = edge_free(p[i], p[j], M, W, padding, resolution, queue,
                                               -1.0, clock, deadline, every)
                free = status == FREE
                late = status == TIMED_OUT
                counters[0] += checked
            if free:
                _copy(tmp[m], p[j])
                m += 1
                i = j
                break
    for i in range(m):
        _copy(p[i], tmp[i])
    return m


@_jit
def _push(out, m, row):
    """Append row to out[:m] unless it repeats out[m - 1]; the new count."""
    if m > 0:
        same = True
        for j in range(row.shape[0]):
            if out[m - 1, j] != row[j]:
                same = False
                break
        if same:
            return m
    _copy(out[m], row)
    return m + 1


@_jit
def _point_at(p, cum, k, s, out):
    """The segment i (p[i] -> p[i + 1]) holding arc length s, and the point there into out."""
    i = 0
    while i < k - 2 and cum[i + 1] <= s:
        i += 1
    seg = cum[i + 1] - cum[i]
    t = 0.0 if seg == 0.0 else (s - cum[i]) / seg
    for j in range(out.shape[0]):
        out[j] = p[i, j] + t * (p[i + 1, j] - p[i, j])
    return i


# --- Python side -------------------------------------------------------------------------------

def rng_state(seed: int | None) -> NDArray:
    """The generator's state (1,) uint64 from a seed, mixed by splitmix64's finaliser (None:
    fresh entropy)."""
    if seed is None:
        return np.random.SeedSequence().generate_state(1, np.uint64)
    mask = (1 << 64) - 1
    z = (int(seed) * 0x9E3779B97F4A7C15 + 0x632BE59BD9B4E019) & mask
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & mask
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & mask
    return np.array([z ^ (z >> 31)], dtype=np.uint64)


def _branch(nodes: NDArray, parent: NDArray, i: int) -> NDArray:
    """The rows of nodes from the root to node i, following parent."""
    chain = []
    while i >= 0:
        chain.append(i)
        i = int(parent[i])
    return nodes[chain[::-1]]


_NO_LIST = np.full(1, -1, np.int64)       # RRT and RRT-Connect keep no child lists
SLICE = 0.005       # s: how long a loop runs as Python before its driver looks again whether
#                     its compiled version is ready


def plan_compiled(checker: CollisionChecker, start: NDArray, goals: NDArray, planner, *,
                  step: float, seed: int | None, max_iterations: int, deadline: NDArray,
                  goal_bias: float = 0.05, capacity: int = 1024):
    """Run a planner's compiled loop (`planner`: an entry of `armkit.planning.planners.PLANNERS`)
    until it finds a path, spends `max_iterations` or passes the deadline (a
    `armkit.planning.clock.timer`, read inside the loop): ``(path or None, iterations,
    states_checked, reason)``, as the Python planners of `armkit.planning.rrt`. capacity: the
    trees' first size (rows; doubled whenever full)."""
    n = checker.n
    lower = np.array(checker.lower, dtype=float)      # writable: the kernels' one signature
    upper = np.array(checker.upper, dtype=float)
    goals = np.ascontiguousarray(goals, dtype=float).reshape(-1, n)
    extent = upper - lower
    margin = int(math.ceil(math.sqrt(float(extent @ extent)) / step)) + 4
    capacity = max(int(capacity), len(goals) + margin + 1)
    nodes = np.empty((2, capacity, n))
    parent = np.empty((2, capacity), np.int64)      # rows past size are written before read
    cost = np.empty((2, capacity))
    clear = np.empty((2, capacity))                 # each node's clearance (capped)
    size = np.zeros(2, np.int64)
    nodes[0, 0] = start
    parent[0, 0], cost[0, 0], clear[0, 0] = -1, 0.0, -1.0       # -1: not known
    size[0] = 1
    if planner.trees == 2:
        g = len(goals)
        nodes[1, :g] = goals
        parent[1, :g], cost[1, :g], clear[1, :g] = -1, 0.0, -1.0
        size[1] = g
    if planner.rewires:
        child = np.full(capacity, -1, np.int64)
        sibling = np.full(capacity, -1, np.int64)
        goal_of = np.full(capacity, -1, np.int64)
        goal_nodes = np.empty(capacity, np.int64)
        volume = float(np.prod(extent))
        unit_ball = math.pi ** (n / 2) / math.gamma(n / 2 + 1)
        gamma = 2.0 * ((1 + 1 / n) * volume / unit_ball) ** (1 / n)
    else:
        child = sibling = goal_of = goal_nodes = _NO_LIST
        gamma = 0.0
    counters = np.zeros(6, np.int64)
    counters[END_A] = counters[END_B] = -1
    best = np.array([np.inf])
    rng = rng_state(seed)
    queue = np.empty((4, QUEUE_SIZE))
    grow = planner.kernel
    while True:
        # The Python tier pauses every SLICE s, so that a loop compiled meanwhile takes over;
        # its edge checks read the clock at every state, the compiled loop's every 16.
        compiled = grow.is_compiled
        status = grow.light(max_iterations, margin, step, goal_bias, gamma, checker.padding,
                            checker.resolution, goals, lower, upper, nodes, parent, cost, clear,
                            size, child, sibling, goal_of, goal_nodes, counters, best, rng,
                            queue, checker.arrays, clock_gettime,
                            deadline if compiled else paused_after(deadline, SLICE),
                            16 if compiled else 1)
        if status == FULL:
            nodes = np.concatenate([nodes, np.empty_like(nodes)], axis=1)
            parent = np.concatenate([parent, np.full_like(parent, -1)], axis=1)
            cost = np.concatenate([cost, np.zeros_like(cost)], axis=1)
            clear = np.concatenate([clear, np.full_like(clear, -1.0)], axis=1)
            if planner.rewires:
                child, sibling, goal_of = (np.concatenate([x, np.full_like(x, -1)])
                                           for x in (child, sibling, goal_of))
                goal_nodes = np.concatenate([goal_nodes, np.empty_like(goal_nodes)])
        elif status != PAUSED or left(deadline) <= 0:
            break
    iterations, checked = int(counters[ITERATIONS]), int(counters[CHECKED])
    end_a, end_b = int(counters[END_A]), int(counters[END_B])
    if status == FOUND and planner.trees == 2:
        pa = _branch(nodes[0], parent[0], end_a)
        pb = _branch(nodes[1], parent[1], end_b)
        return np.concatenate([pa, pb[-2::-1]]), iterations, checked, "ok"
    if end_a >= 0 and planner.trees == 1:
        path = _branch(nodes[0], parent[0], end_a)
        if not np.array_equal(path[-1], goals[end_b]):
            path = np.vstack([path, goals[end_b]])
        return path, iterations, checked, "ok"
    spent = "time limit" if status == PAUSED else "iteration budget"
    return None, iterations, checked, f"no path within the {spent} ({iterations} iterations)"


def shortcut_compiled(checker: CollisionChecker, path: NDArray, *, seed: int | None,
                      tries: int, min_gain: float = 0.01, deadline: NDArray
                      ) -> tuple[NDArray, int]:
    """`shortcut_kernel` on a path (k, n) without repeated rows, until the deadline (a
    `armkit.planning.clock.timer`): (path, states checked). min_gain: the least saving worth
    checking a shortcut for, a fraction of the path's length."""
    counters = np.zeros(2, np.int64)
    rng = rng_state(seed)
    queue = np.empty((4, QUEUE_SIZE))
    path = np.ascontiguousarray(path, dtype=float)
    while True:
        compiled = shortcut_kernel.is_compiled
        # Compiled, one call does it all; as Python, the tries pause every SLICE s (so that a
        # kernel compiled meanwhile takes over), and the reduction is a call of its own.
        reduce = compiled or counters[1] >= tries or len(path) < 3
        path = shortcut_kernel.light(path, int(tries - counters[1]), float(min_gain), rng,
                                     checker.padding, checker.resolution, queue, checker.arrays,
                                     counters, clock_gettime,
                                     deadline if compiled else paused_after(deadline, SLICE),
                                     16 if compiled else 1, reduce)
        if reduce or left(deadline) <= 0:
            return path, int(counters[0])
