"""Sampling planners in joint space: RRT with a fixed step, RRT-Connect and RRT*.

The planners know no geometry (like OMPL's planners and its StateValidityChecker): they take a
*validity* object with ``lower``, ``upper`` (n,), ``valid_states(Q (k, n)) -> (k,) bool`` and
``interior_free(qa, qb) -> (free, states_checked)`` for the inside of a straight edge whose
endpoints are valid. `ValidityFunction` makes one from any Python callable on a batch of states;
`armkit.planning.CollisionChecker` is one, compiled and certified.

Each planner returns ``(path or None, iterations, states_checked, reason)``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError

TRAPPED, ADVANCED, REACHED = 0, 1, 2


@dataclass(frozen=True, eq=False)
class ValidityFunction:
    """A user's validity callable as the planners take it.

    Parameters
    ----------
    function : callable
        ``function(Q)`` with Q (k, n) returns k booleans: True where the state is valid.
    lower, upper : array_like, (n,)
        The joint limits the planners sample within.
    resolution : float
        Largest joint step (rad or m, any one joint) between two states checked on an edge.
    """

    function: object
    lower: NDArray
    upper: NDArray
    resolution: float = 0.01

    def __post_init__(self):
        if not callable(self.function):
            raise InputError(f"checker: expected a callable on states (k, n), found "
                             f"{type(self.function).__name__}")
        lower = np.array(self.lower, dtype=float).reshape(-1)
        upper = np.array(self.upper, dtype=float).reshape(-1)
        if lower.shape != upper.shape or not np.all(np.isfinite(lower) & np.isfinite(upper)) \
                or not np.all(upper > lower):
            raise InputError(f"limits: expected finite lower < upper of one length, found "
                             f"{lower.tolist()} and {upper.tolist()}")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise InputError(f"resolution: expected a positive joint step, found "
                             f"{self.resolution}")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        object.__setattr__(self, "resolution", float(self.resolution))

    @property
    def n(self) -> int:
        return self.lower.shape[0]

    def valid_states(self, Q: NDArray) -> NDArray:
        Q = np.ascontiguousarray(np.reshape(Q, (-1, self.n)), dtype=float)
        out = np.asarray(self.function(Q), dtype=bool).reshape(-1)
        if out.shape != (Q.shape[0],):
            raise InputError(f"checker: expected {Q.shape[0]} booleans for {Q.shape[0]} "
                             f"states, found shape {out.shape}")
        return out

    def interior_free(self, qa: NDArray, qb: NDArray) -> tuple[bool, int]:
        steps = int(math.ceil(np.abs(qb - qa).max() / self.resolution))
        if steps <= 1:
            return True, 0
        order = coarse_to_fine(steps)
        Q = qa + (order / steps)[:, None] * (qb - qa)
        return bool(self.valid_states(Q).all()), len(order)


def coarse_to_fine(steps: int) -> NDArray:
    """The interior indices 1 .. steps-1 in bisection order: the middle first, then quarters."""
    top = 1 << max(steps - 1, 1).bit_length()
    out, stride = [], top
    while stride >= 1:
        out.extend(range(stride, steps, 2 * stride))
        stride //= 2
    return np.array(out, dtype=float)


class _Tree:
    """Nodes (grown in blocks), parents and costs."""

    def __init__(self, n: int, roots: NDArray):
        self.q = np.empty((max(1024, 2 * len(roots)), n))
        self.parent = np.empty(self.q.shape[0], np.int64)
        self.cost = np.empty(self.q.shape[0])
        self.size = 0
        for r in roots:
            self.add(r, -1, 0.0)

    def add(self, q: NDArray, parent: int, cost: float) -> int:
        if self.size == self.q.shape[0]:
            self.q = np.concatenate([self.q, np.empty_like(self.q)])
            self.parent = np.concatenate([self.parent, np.empty_like(self.parent)])
            self.cost = np.concatenate([self.cost, np.empty_like(self.cost)])
        i = self.size
        self.q[i], self.parent[i], self.cost[i] = q, parent, cost
        self.size += 1
        return i

    def distances(self, q: NDArray) -> NDArray:
        d = self.q[:self.size] - q
        return np.sqrt(np.einsum("ij,ij->i", d, d))

    def nearest(self, q: NDArray) -> int:
        d = self.q[:self.size] - q
        return int(np.argmin(np.einsum("ij,ij->i", d, d)))

    def branch(self, i: int) -> NDArray:
        """The nodes from the root to node i, (k, n)."""
        out = []
        while i >= 0:
            out.append(self.q[i])
            i = self.parent[i]
        return np.array(out[::-1])


class _Budget:
    """Iterations left and the deadline (a `armkit.planning.clock.timer`), read at every
    iteration."""

    def __init__(self, max_iterations: int, deadline: NDArray):
        self.max_iterations, self.deadline = max_iterations, int(deadline[2])
        self.start = time.perf_counter()
        self.iterations = 0
        self.late = False

    def more(self) -> bool:
        if self.iterations >= self.max_iterations:
            return False
        if time.monotonic_ns() >= self.deadline:
            self.late = True
            return False
        self.iterations += 1
        return True

    def reason(self) -> str:
        spent = "time limit" if self.late else "iteration budget"
        return f"no path within the {spent} ({self.iterations} iterations)"


class _Sampler:
    """Uniform states inside the limits, drawn in blocks (one generator call per 256)."""

    def __init__(self, rng: np.random.Generator, lower: NDArray, upper: NDArray):
        self.rng, self.lower, self.upper = rng, lower, upper
        self.block, self.i = np.empty((0, lower.shape[0])), 0

    def __call__(self) -> NDArray:
        if self.i == self.block.shape[0]:
            self.block = self.rng.uniform(self.lower, self.upper, (256, self.lower.shape[0]))
            self.i = 0
        self.i += 1
        return self.block[self.i - 1]


def _steer(q_from: NDArray, q_to: NDArray, step: float) -> tuple[NDArray, bool]:
    d = q_to - q_from
    dist = math.sqrt(float(d @ d))
    if dist <= step:
        return q_to.copy(), True
    return q_from + d * (step / dist), False


class _Counter:
    def __init__(self, validity):
        self.validity, self.checked = validity, 0
        # A checker whose edge test checks both ends (armkit's) needs no separate state test.
        self.ends_in_edge = bool(getattr(validity, "edge_checks_ends", False))

    def state(self, q: NDArray) -> bool:
        if self.ends_in_edge:
            return True
        self.checked += 1
        return bool(self.validity.valid_states(q[None])[0])

    def edge(self, qa: NDArray, qb: NDArray) -> bool:
        free, checked = self.validity.interior_free(qa, qb)
        self.checked += checked
        return free


def _extend(tree: _Tree, q_target: NDArray, step: float, check: _Counter) -> tuple[int, int]:
    near = tree.nearest(q_target)
    q_new, reached = _steer(tree.q[near], q_target, step)
    if not check.state(q_new) or not check.edge(tree.q[near], q_new):
        return TRAPPED, -1
    dist = float(np.linalg.norm(q_new - tree.q[near]))
    i = tree.add(q_new, near, tree.cost[near] + dist)
    return (REACHED if reached else ADVANCED), i


def rrt_connect(validity, start: NDArray, goals: NDArray, *, step: float, rng,
                max_iterations: int, deadline: NDArray, **_):
    """RRT-Connect (Kuffner and LaValle 2000): a tree from the start and one from the goals,
    each extension answered by the other tree connecting greedily toward the new node."""
    check = _Counter(validity)
    budget = _Budget(max_iterations, deadline)
    sample = _Sampler(rng, validity.lower, validity.upper)
    a, b = _Tree(start.shape[0], start[None]), _Tree(start.shape[0], goals)
    a_is_start = True
    while budget.more():
        status, new = _extend(a, sample(), step, check)
        if status != TRAPPED:
            target = a.q[new]
            status_b, last = ADVANCED, -1
            while status_b == ADVANCED:
                status_b, j = _extend(b, target, step, check)
                last = j if j >= 0 else last
            if status_b == REACHED:
                pa, pb = a.branch(new), b.branch(last)
                path = np.vstack([pa, pb[::-1][1:]]) if a_is_start else \
                    np.vstack([pb, pa[::-1][1:]])
                return path, budget.iterations, check.checked, "ok"
        a, b, a_is_start = b, a, not a_is_start
    return None, budget.iterations, check.checked, budget.reason()


def _goal_sample(sample, goals, rng, goal_bias):
    if goal_bias > 0 and rng.random() < goal_bias:
        return goals[rng.integers(len(goals))]
    return sample()


def rrt(validity, start: NDArray, goals: NDArray, *, step: float, rng, max_iterations: int,
        deadline: NDArray, goal_bias: float = 0.05, **_):
    """RRT with a fixed step (LaValle 1998; paper 1): grow from the start toward samples (a goal
    with probability goal_bias); done when a new node connects straight to a goal."""
    check = _Counter(validity)
    budget = _Budget(max_iterations, deadline)
    sample = _Sampler(rng, validity.lower, validity.upper)
    tree = _Tree(start.shape[0], start[None])
    while budget.more():
        status, new = _extend(tree, _goal_sample(sample, goals, rng, goal_bias), step, check)
        if status == TRAPPED:
            continue
        q = tree.q[new]
        d = np.linalg.norm(goals - q, axis=1)
        for g in np.argsort(d):
            if d[g] > step:
                break
            if d[g] == 0.0 or check.edge(q, goals[g]):
                path = tree.branch(new)
                if d[g] > 0:
                    path = np.vstack([path, goals[g]])
                return path, budget.iterations, check.checked, "ok"
    return None, budget.iterations, check.checked, budget.reason()


def rrt_star(validity, start: NDArray, goals: NDArray, *, step: float, rng, max_iterations: int,
             deadline: NDArray, goal_bias: float = 0.05, **_):
    """RRT* (Karaman and Frazzoli 2011): each new node takes the cheapest parent among its
    neighbours and rewires them through itself; runs the whole budget and returns the
    shortest path found (joint-space length)."""
    check = _Counter(validity)
    budget = _Budget(max_iterations, deadline)
    sample = _Sampler(rng, validity.lower, validity.upper)
    n = start.shape[0]
    tree = _Tree(n, start[None])
    children: list[list[int]] = [[]]
    volume = float(np.prod(validity.upper - validity.lower))
    unit_ball = math.pi ** (n / 2) / math.gamma(n / 2 + 1)
    gamma = 2.0 * ((1 + 1 / n) * volume / unit_ball) ** (1 / n)
    best_cost, best_node, best_goal = math.inf, -1, -1
    goal_nodes: dict[int, int] = {}                       # tree node -> goal index it reaches
    while budget.more():
        q_rand = _goal_sample(sample, goals, rng, goal_bias)
        near = tree.nearest(q_rand)
        q_new, _ = _steer(tree.q[near], q_rand, step)
        if not check.state(q_new) or not check.edge(tree.q[near], q_new):
            continue
        k = tree.size
        radius = min(gamma * (math.log(k + 1) / (k + 1)) ** (1 / n), step)
        d = tree.distances(q_new)
        neighbours = np.flatnonzero(d <= radius)
        parent, cost = near, tree.cost[near] + d[near]
        for j in neighbours[np.argsort(tree.cost[neighbours] + d[neighbours])]:
            c = tree.cost[j] + d[j]
            if c >= cost:
                break
            if check.edge(tree.q[j], q_new):
                parent, cost = int(j), c
                break
        new = tree.add(q_new, parent, cost)
        children.append([])
        children[parent].append(new)
        for j in neighbours:
            c = cost + d[j]
            if j != parent and c < tree.cost[j] and check.edge(q_new, tree.q[j]):
                children[tree.parent[j]].remove(j)
                tree.parent[j] = new
                children[new].append(j)
                delta = c - tree.cost[j]
                stack = [int(j)]
                while stack:                                # the subtree gets cheaper too
                    m = stack.pop()
                    tree.cost[m] += delta
                    stack.extend(children[m])
        dg = np.linalg.norm(goals - q_new, axis=1)
        for g in np.flatnonzero(dg <= step):
            if dg[g] == 0.0 or check.edge(q_new, goals[g]):
                goal_nodes[new] = int(g)
                break
        for node, g in goal_nodes.items():
            c = tree.cost[node] + float(np.linalg.norm(goals[g] - tree.q[node]))
            if c < best_cost:
                best_cost, best_node, best_goal = c, node, g
    if best_node < 0:
        return None, budget.iterations, check.checked, budget.reason()
    path = tree.branch(best_node)
    if not np.array_equal(path[-1], goals[best_goal]):
        path = np.vstack([path, goals[best_goal]])
    return path, budget.iterations, check.checked, "ok"

