"""Numeric inverse kinematics for any chain: Newton-Raphson and Levenberg-Marquardt.

Each target is solved by its own iterations inside one numba kernel (``solve_targets``); a
large batch is split over threads (the kernels release the GIL), a small one runs on the
calling thread. Per iteration: tool pose and Jacobian (one kernel pass), the task residual and
its Jacobian (`armkit.kinematics.ik.masks.task_residual`), and the step

- ``newton`` (the inspection-robot paper's method): the least-norm solution of ``A dq = e``,
  taken whole; done when the pose is within the tolerances, stuck when no step is left
  (below 1e-15);
- ``lm`` (Levenberg-Marquardt): ``(A^T A + lambda I) dq = A^T e``, or in the task space
  ``dq = A^T (A A^T + lambda I)^-1 e`` when the task has fewer rows than the arm has joints
  (the damped minimum-norm step: a redundant task leaves the null space free), kept only if it
  lowers ``|e|^2``, with lambda divided by 10 after a kept step and multiplied by 10 after a
  refused one.

Joint limits: a revolute joint whose range spans a full turn wraps (its angle is taken modulo
2 pi into the range); any other joint that a step would push past a limit is held there and the
step is taken with the others (a bound-constrained Gauss-Newton step). An attempt that has not
reached the tolerances after ``max_iter`` iterations, whose lambda grows past 1e8, or that
stalls (after six iterations, three more have not cut the squared residual to a quarter: it has
settled in a local minimum) starts again: from the next of the given starts, then from
configurations drawn uniformly inside the limits (a splitmix64 stream per target, seeded from
``seed`` and the target's index, so results do not depend on threads). If every attempt fails,
the best point found gets one last run of ten times ``max_iter`` (near a singularity
convergence is slow, not absent).

The kernels take their arguments in groups (see `KernelArgs`): ``chain = (floats, ints)``
(`KernelChain`'s packed arrays), ``limits`` (5, n) with rows lower, upper, turn, sample_lo,
sample_hi, ``task = (mask, rows, tol_position, tol_rotation)`` and
``budget = (max_iter, restarts, method, seed, follow, max_step, polish)``. Few arrays cross
numba's dispatcher, whose cost grows with each one: for one target it is a good part of the
call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armkit.jit import kernel
from armkit.kinematics.core import pose_jacobian_one
from armkit.kinematics.ik.masks import mask_forms, task_errors_one, task_residual
from armkit.threads import in_ranges, threads_for

# error_model="numpy": no exception paths for a division by zero (smaller code, faster
# compiles); the kernels guard their divisions themselves.
_jit = kernel(cache=True, nogil=True, error_model="numpy")
# Kernels only ever called from another kernel: not cached on their own (a cached caller carries
# their code), which saves writing and looking up cache entries when the first call compiles.
_inner = kernel(nogil=True, error_model="numpy")
# The kernels spell min and max as conditional expressions (Python's and numba's choice: the
# second argument only if strictly greater, or smaller) and fill with loops rather than
# np.zeros: each builtin overload is one more function the first call compiles.

NEWTON, LM = 0, 1
METHOD_CODES = {"newton": NEWTON, "lm": LM}
MAX_LAMBDA = 1e8
STALL_AFTER, STALL_WINDOW, STALL_FACTOR = 6, 3, 0.25
TARGETS_PER_THREAD = 256    # below this many targets per thread, threads cost more than they save


def thread_count(targets: int, threads: int | None = None) -> int:
    """Threads for a batch of `targets`: one per `TARGETS_PER_THREAD` targets, at most
    `threads` (default: `armkit.threads`' choice, the idle cores or the bound the user set),
    so a small batch, or one on a busy machine, runs on the calling thread."""
    return threads_for(targets, TARGETS_PER_THREAD, threads)


# --- kernels ----------------------------------------------------------------------------------

@_inner
def _random(state):
    """splitmix64: the next state and a float in [0, 1)."""
    state = state + np.uint64(0x9E3779B97F4A7C15)
    z = state
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return state, float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@_inner
def _step(A, e, lam, free, dq, H, g, y):
    """dq (n,) from the damped normal equations, in the smaller of the joint or task space;
    False if the system is not positive definite.

    Joints with ``free[j] == False`` are held (their column left out); lam is relative to the
    largest squared column norm of A, so prismatic (m) and revolute (rad) joints damp alike.
    H (k, k), g (k,) and y (k,) are scratch, k = min(m, n).
    """
    m, n = A.shape
    joint_space = n <= m
    k = n if joint_space else m
    scale = 0.0
    for c in range(n):
        if free[c]:
            s = 0.0
            for r in range(m):
                s += A[r, c] * A[r, c]
            scale = s if s > scale else scale
    damping = lam * (scale if scale > 1e-300 else 1e-300)
    # Lower triangle of H and the right-hand side g.
    for i in range(k):
        for j in range(i + 1):
            s = 0.0
            if joint_space:                             # A^T A, held joints left out
                if free[i] and free[j]:
                    for r in range(m):
                        s += A[r, i] * A[r, j]
            else:                                       # A A^T over the free joints
                for c in range(n):
                    if free[c]:
                        s += A[i, c] * A[j, c]
            H[i, j] = s
        if joint_space:
            s = 0.0
            if free[i]:
                for r in range(m):
                    s += A[r, i] * e[r]
            g[i] = s
            H[i, i] += damping if free[i] else 1.0      # a held joint: dq_i = 0
        else:
            g[i] = e[i]
            H[i, i] += damping
    # Cholesky in place, then the two triangular solves.
    for j in range(k):
        s = H[j, j]
        for p in range(j):
            s -= H[j, p] * H[j, p]
        if s <= 0.0:
            return False
        d = math.sqrt(s)
        H[j, j] = d
        for i in range(j + 1, k):
            s = H[i, j]
            for p in range(j):
                s -= H[i, p] * H[j, p]
            H[i, j] = s / d
    for i in range(k):
        s = g[i]
        for p in range(i):
            s -= H[i, p] * y[p]
        y[i] = s / H[i, i]
    for i in range(k - 1, -1, -1):
        s = y[i]
        for p in range(i + 1, k):
            s -= H[p, i] * y[p]
        y[i] = s / H[i, i]
    if joint_space:
        for c in range(n):
            dq[c] = y[c]
    else:
        for c in range(n):
            s = 0.0
            if free[c]:
                for r in range(m):
                    s += A[r, c] * y[r]
            dq[c] = s
    return True


@_inner
def _bounded(q, dq, lower, upper, turn, q_new):
    """q + dq kept in the limits: a joint with a full turn of range that leaves it comes back
    by whole turns, others stop at their limit. Returns the largest change."""
    size = 0.0
    for j in range(q.shape[0]):
        v = q[j] + dq[j]
        if turn[j]:
            if v < lower[j]:
                v += 2.0 * math.pi * math.ceil((lower[j] - v) / (2.0 * math.pi))
            elif v > upper[j]:
                v -= 2.0 * math.pi * math.ceil((v - upper[j]) / (2.0 * math.pi))
        else:
            v = lower[j] if lower[j] > v else v
            v = upper[j] if upper[j] < v else v
        q_new[j] = v
        change = abs(v - q[j])
        size = change if change > size else size
    return size


@_inner
def _descend(q, Tt, chain, limits, task, method, iterations, stall, poses, jacobians, residuals,
             task_jacobians, joints, vectors, H, free, earlier, errors):
    """One attempt from q (updated in place to where it ends): (converged, cost, iterations);
    errors (2,) gets the position and rotation error at q.

    LM only keeps steps that lower the cost, so it ends at its best point; Newton takes every
    step and stops when the step vanishes. With `stall`, an attempt that stops making progress
    ends early. The arrays after `stall` are scratch (see `solve_targets`).

    Each kernel it calls is called from one place (the trial point is evaluated at the top of
    the loop, the held-joint step is the second pass of one loop): the compiled code inlines
    every call, so each call site costs compile time.
    """
    F, I = chain
    lower, upper, turn = limits[0], limits[1], limits[2]
    mask, rows, tol_p, tol_r = task
    n = q.shape[0]
    q_try, dq, g, y = joints[0], joints[1], vectors[0], vectors[1]
    E, w = poses[2, :3, :3], poses[2, 3, :3]
    T, T2, J, J2 = poses[0], poses[1], jacobians[0], jacobians[1]
    e, e2, A, A2 = residuals[0], residuals[1], task_jacobians[0], task_jacobians[1]
    for j in range(n):
        q_try[j] = q[j]
    for j in range(STALL_WINDOW):                       # the cost 1, 2, 3 iterations ago
        earlier[j] = np.inf
    lam = 1e-3 if method == LM else 1e-15
    cost, size, first, evaluate = np.inf, np.inf, True, True
    for it in range(iterations + 1):
        if evaluate:                                    # the trial point q_try
            pose_jacobian_one(q_try, F, I, T2, J2)
            new_cost = task_residual(T2, J2, Tt, mask, rows, e2, A2, E, w)
            if first or method == NEWTON or new_cost < cost:
                for j in range(n):
                    q[j] = q_try[j]
                T, T2, J, J2, e, e2, A, A2 = T2, T, J2, J, e2, e, A2, A
                cost = new_cost
                if not first:
                    lam = lam / 10.0 if lam / 10.0 > 1e-15 else 1e-15
            else:
                lam *= 10.0
        errors[0], errors[1] = task_errors_one(T, Tt, mask)
        if errors[0] < tol_p and errors[1] < tol_r:
            return True, cost, it
        if it == iterations or lam > MAX_LAMBDA:
            return False, cost, it
        if method == NEWTON and not first and size < 1e-15:
            return False, cost, it                      # no step left: a stationary point
        first = False
        if stall and it >= STALL_AFTER and cost > STALL_FACTOR * earlier[it % STALL_WINDOW]:
            return False, cost, it
        earlier[it % STALL_WINDOW] = cost
        for j in range(n):
            free[j] = True
        # The step; a second pass holds the joints it pushes past a limit and steps with the
        # others.
        ok = False
        for attempt in range(2):
            ok = _step(A, e, lam, free, dq, H, g, y)
            held = False
            if ok and attempt == 0:
                for j in range(n):
                    if not turn[j] and ((q[j] <= lower[j] and dq[j] < 0.0)
                                        or (q[j] >= upper[j] and dq[j] > 0.0)):
                        free[j] = False
                        held = True
            if not held:
                break
        evaluate = ok
        if not ok:
            lam *= 10.0
            continue
        size = _bounded(q, dq, lower, upper, turn, q_try)
    return False, cost, iterations


@_jit
def solve_targets(first, last, targets, starts, chain, limits, task, budget, q_out, converged,
                  iterations, errors):
    """Solve targets[first:last] (N, 4, 4). Writes q_out (N, n), converged (N,), iterations
    (N,) summed over attempts, and errors (N, 2): position (m) and rotation (rad) error of
    q_out under the task, by forward kinematics. Returns (targets done, cause).

    budget = (max_iter, restarts, method, seed, follow, max_step, polish). Solving (follow
    0): each target from its starts (N, S, n), then random restarts, then (if polish) a long
    run from its best point; returns (last, 0). Following (follow 1): target t starts from the
    solution of t - 1 (the first from starts[first, 0]), with no restart; stops at the first
    target not solved (cause 1) or, after the first, whose solution moved a joint by more than
    max_step (cause 2); returns (first target not followed, cause), (last, 0) when all were.
    One kernel does both so that the first call compiles the solver once.
    """
    lower, upper, turn, sample_lo, sample_hi = (limits[0], limits[1], limits[2], limits[3],
                                                limits[4])
    max_iter, restarts, method, seed, follow, max_step, polish = budget
    n, m = starts.shape[2], task[1].shape[0]
    k = m if m < n else n                               # scratch for _descend
    k = k if k > 1 else 1
    poses, jacobians, residuals = np.empty((3, 4, 4)), np.empty((2, 6, n)), np.empty((2, m))
    task_jacobians, joints, vectors = np.empty((2, m, n)), np.empty((2, n)), np.empty((2, k))
    H, free, earlier = np.empty((k, k)), np.empty(n, dtype=np.bool_), np.empty(STALL_WINDOW)
    q, previous, zero, found = np.empty(n), np.empty(n), np.empty(n), np.empty(2)
    for j in range(n):
        zero[j] = 0.0
    attempts = 1 if follow else restarts + 1
    for t in range(first, last):
        # The stream's start, scrambled: a start of seed * step + t would make seed s + 1
        # replay seed s's stream one draw later (the stream adds step per draw).
        z = np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(t)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        state = z ^ (z >> np.uint64(31))
        best, total, done = np.inf, 0, False
        for j in range(n):
            previous[j] = q[j]
        # Attempts from the starts, then random ones; the one after the last is the long run
        # from the best point (near a singularity convergence slows down: an attempt may end,
        # or be judged stalled, close to a solution it had no time to reach).
        for attempt in range(attempts + (0 if follow else polish)):
            long_run = attempt == attempts
            for j in range(n):
                if long_run:
                    q[j] = q_out[t, j]
                elif follow:
                    q[j] = starts[first, 0, j] if t == first else previous[j]
                elif attempt < starts.shape[1]:
                    q[j] = starts[t, attempt, j]
                else:
                    state, u = _random(state)
                    q[j] = sample_lo[j] + u * (sample_hi[j] - sample_lo[j])
            _bounded(q, zero, lower, upper, turn, q)
            ok, cost, its = _descend(q, targets[t], chain, limits, task, method,
                                     10 * max_iter if long_run else max_iter,
                                     not (long_run or follow), poses, jacobians, residuals,
                                     task_jacobians, joints, vectors, H, free, earlier, found)
            total += its
            if ok or cost < best or follow:
                best = cost
                for j in range(n):
                    q_out[t, j] = q[j]
                errors[t, 0], errors[t, 1] = found[0], found[1]
            if ok:
                done = True
                break
        converged[t], iterations[t] = done, total
        if follow:
            if not done:
                return t, 1
            step = 0.0
            for j in range(n):
                d = q[j] - previous[j]
                if turn[j]:                  # a wrapping joint: the short way round
                    d = (d + math.pi) % (2.0 * math.pi) - math.pi
                d = abs(d)
                step = d if d > step else step
            if t > first and step > max_step:
                return t, 2
    return last, 0


# --- the Python side --------------------------------------------------------------------------

def _writable(a, dtype=float) -> np.ndarray:
    """a as a C-contiguous writable array (a copy only if needed): the kernels see one type
    whatever the caller passed, and compile once."""
    return np.require(a, dtype=dtype, requirements=("C", "W"))


@dataclass(frozen=True)
class KernelArgs:
    """A robot's arrays as the numeric kernels take them, built once per solver.

    chain: `KernelChain`'s packed (floats, ints); limits (5, n): lower, upper, turn,
    sample_lo, sample_hi, where turn is 1.0 for revolute joints whose range is a full turn or
    more (they wrap instead of stopping) and the sample range is `Chain.sampling_limits`.
    """

    chain: tuple
    limits: np.ndarray

    @classmethod
    def of(cls, robot) -> "KernelArgs":
        """The robot's chain packed (`KernelChain.floats`, `KernelChain.ints`) and its
        `Chain.kernel_limits`: arrays the model computes once."""
        k = robot.chain.kernel
        return cls((k.F, k.I), robot.chain.kernel_limits)


def task_args(mask: np.ndarray, tol_position: float, tol_rotation: float) -> tuple:
    """The task group of the kernels: (mask (6,) int, rows (m,) int, tol_p, tol_r)."""
    forms = mask_forms(mask)
    return (forms.ints, forms.rows, float(tol_position), float(tol_rotation))


def solve(kernel_args: KernelArgs, targets: np.ndarray, starts: np.ndarray, task: tuple,
          method: str, max_iter: int, restarts: int, seed: int, threads: int | None = None,
          polish: bool = True):
    """Numeric IK for targets (N, 4, 4), trying starts (N, S, n) first, then random ones,
    then (with `polish`) a long run from the best point found.

    Returns
    -------
    q : ndarray, shape (N, n)
        Best configuration found for each target (within the limits).
    converged : ndarray of bool, shape (N,)
    iterations : ndarray of int, shape (N,)
        Iterations summed over all attempts.
    errors : ndarray, shape (N, 2)
        Position (m) and rotation (rad) error of q under the task, by forward kinematics.
    """
    N, n = targets.shape[0], starts.shape[2]
    q = np.empty((N, n))
    converged = np.zeros(N, dtype=np.bool_)
    iterations = np.zeros(N, dtype=np.int64)
    errors = np.empty((N, 2))
    args = (_writable(targets), _writable(starts), kernel_args.chain,
            kernel_args.limits, task, (int(max_iter), int(restarts), METHOD_CODES[method],
                                       int(seed), 0, 0.0, int(polish)), q, converged,
            iterations, errors)
    in_ranges(lambda first, last: solve_targets(first, last, *args), N,
              thread_count(N, threads))
    return q, converged, iterations, errors


def track(kernel_args: KernelArgs, targets: np.ndarray, q_start: np.ndarray, task: tuple,
          max_iter: int, max_step: float) -> tuple[np.ndarray, int, int]:
    """Follow targets (K, 4, 4) from q_start (n,) with Levenberg-Marquardt: (q (followed, n),
    followed, cause); see `solve_targets`."""
    K, n = targets.shape[0], q_start.shape[0]
    q = np.empty((K, n))
    starts = _writable(np.broadcast_to(q_start, (K, 1, n)))
    followed, cause = solve_targets(
        0, K, _writable(targets), starts, kernel_args.chain, kernel_args.limits, task,
        (int(max_iter), 0, LM, 0, 1, float(max_step), 0), q, np.zeros(K, dtype=np.bool_),
        np.zeros(K, dtype=np.int64), np.empty((K, 2)))
    return q[:followed], int(followed), int(cause)
