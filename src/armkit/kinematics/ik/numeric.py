"""Numeric inverse kinematics for any chain: Newton-Raphson and Levenberg-Marquardt.

Each target is solved by its own iterations inside one numba kernel, and the targets run in
parallel (``prange``): a batch never loops in Python. Per iteration: tool pose and Jacobian
(one kernel pass), the task residual ``e = (p_target - p, log(R^T R_target))`` (position in the
base frame, rotation about the tool's axes) restricted to the mask's rows, and the step

- ``newton`` (the inspection-robot paper's method): the least-norm solution of ``A dq = e``,
  taken whole; done when the pose is within the tolerances, stuck when no step is left
  (below 1e-15);
- ``lm`` (Levenberg-Marquardt): ``(A^T A + lambda I) dq = A^T e``, kept only if it lowers
  ``|e|^2``, with lambda divided by 10 after a kept step and multiplied by 10 after a refused one.

Joint limits: a revolute joint whose range spans a full turn wraps (its angle is taken modulo
2 pi into the range); any other joint that a step would push past a limit is held there and the
step is taken with the others (a bound-constrained Gauss-Newton step). An attempt that has not
reached the tolerances after ``max_iter`` iterations, whose lambda grows past 1e8, or that
stalls (after six iterations, three more have not cut the squared residual to a quarter: it has
settled in a local minimum, as the nearest start of about one ur5 target in ten does) starts
again: from the next of the given starts, then from configurations drawn uniformly inside the
limits (a splitmix64 stream per target, seeded from ``seed`` and the target's index, so results
do not depend on thread scheduling). If every attempt fails, the best point found gets one
last run of ten times ``max_iter`` (near a singularity convergence is slow, not absent).
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

from armkit.kinematics._kernels import pose_jacobian_one
from armkit.kinematics.forward import fk
from armkit.kinematics.ik.task import task_errors_one

_jit = numba.njit(cache=True, nogil=True)
_pjit = numba.njit(cache=True, nogil=True, parallel=True)
# Reassociation lets LLVM vectorise the small dense algebra; a step only proposes q, which
# exact forward kinematics then judges, so the last bits of a step do not matter.
_fast = numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "arcp", "nsz"})

NEWTON, LM = 0, 1
MAX_LAMBDA = 1e8
STALL_AFTER, STALL_WINDOW, STALL_FACTOR = 6, 3, 0.25


@_jit
def _random(state):
    """splitmix64: the next state and a float in [0, 1)."""
    state = state + np.uint64(0x9E3779B97F4A7C15)
    z = state
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return state, float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@_jit
def _log_rotation(E, out):
    """Rotation vector (3,) of the rotation E (3, 3) into out; accurate near 0 and pi."""
    sx, sy, sz = E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]
    s = 0.5 * math.sqrt(sx * sx + sy * sy + sz * sz)
    c = 0.5 * (E[0, 0] + E[1, 1] + E[2, 2] - 1.0)
    angle = math.atan2(s, c)
    if angle < 1e-6:
        f = 0.5 * (1.0 + angle * angle / 6.0)           # angle / (2 sin angle), series
        out[0], out[1], out[2] = f * sx, f * sy, f * sz
    elif angle < math.pi - 1e-6:
        f = angle / (2.0 * s)
        out[0], out[1], out[2] = f * sx, f * sy, f * sz
    else:
        # Near pi the skew part vanishes: take the axis from the diagonal of (E + I) / 2.
        k = 0
        if E[1, 1] > E[k, k]:
            k = 1
        if E[2, 2] > E[k, k]:
            k = 2
        v0, v1, v2 = E[0, k], E[1, k], E[2, k]
        if k == 0:
            v0 += 1.0
        elif k == 1:
            v1 += 1.0
        else:
            v2 += 1.0
        norm = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        sign = 1.0 if (v0 * sx + v1 * sy + v2 * sz) >= 0.0 else -1.0
        f = sign * angle / norm
        out[0], out[1], out[2] = f * v0, f * v1, f * v2


@_jit
def _residual(T, J, Tt, rows, e, A, E, w):
    """Masked residual e (m,) and its Jacobian A (m, n) at tool pose T with Jacobian J."""
    for r in range(3):
        for c in range(3):
            E[r, c] = T[0, r] * Tt[0, c] + T[1, r] * Tt[1, c] + T[2, r] * Tt[2, c]
    _log_rotation(E, w)
    n = J.shape[1]
    for i in range(rows.shape[0]):
        r = rows[i]
        if r < 3:
            e[i] = Tt[r, 3] - T[r, 3]
            for j in range(n):
                A[i, j] = J[r, j]
        else:
            k = r - 3
            e[i] = w[k]
            for j in range(n):                          # R^T J_w: about the tool's axes
                A[i, j] = T[0, k] * J[3, j] + T[1, k] * J[4, j] + T[2, k] * J[5, j]
    cost = 0.0
    for i in range(rows.shape[0]):
        cost += e[i] * e[i]
    return cost


@_fast
def _solve_spd(H, g, x):
    """Solve H x = g for a symmetric positive definite H (k, k) by Cholesky, in place on H."""
    k = H.shape[0]
    for j in range(k):
        s = H[j, j]
        for m in range(j):
            s -= H[j, m] * H[j, m]
        if s <= 0.0:
            return False
        d = math.sqrt(s)
        H[j, j] = d
        for i in range(j + 1, k):
            s = H[i, j]
            for m in range(j):
                s -= H[i, m] * H[j, m]
            H[i, j] = s / d
    for i in range(k):
        s = g[i]
        for m in range(i):
            s -= H[i, m] * x[m]
        x[i] = s / H[i, i]
    for i in range(k - 1, -1, -1):
        s = x[i]
        for m in range(i + 1, k):
            s -= H[m, i] * x[m]
        x[i] = s / H[i, i]
    return True


@_fast
def _step(A, e, lam, free, dq, Hn, gn, Hm, gm, y):
    """dq from the damped normal equations, in the smaller of the joint or task space.

    Joints with ``free[j] == False`` are held (their column left out); lam is relative to the
    largest diagonal entry of ``A^T A``, so prismatic (m) and revolute (rad) joints damp alike.
    """
    m, n = A.shape
    if n <= m:                                          # (A^T A + lam I) dq = A^T e
        for i in range(n):                              # lower triangle and right-hand side
            s = 0.0
            for r in range(m):
                s += A[r, i] * e[r]
            gn[i] = s
            for j in range(i + 1):
                s = 0.0
                for r in range(m):
                    s += A[r, i] * A[r, j]
                Hn[i, j] = s
        scale = 0.0
        for i in range(n):
            if free[i]:
                scale = max(scale, Hn[i, i])
        damping = lam * max(scale, 1e-300)
        for i in range(n):
            if free[i]:
                Hn[i, i] += damping
            else:                                       # a held joint: dq_i = 0
                gn[i] = 0.0
                for j in range(n):
                    Hn[max(i, j), min(i, j)] = 0.0
                Hn[i, i] = 1.0
        return _solve_spd(Hn, gn, dq)
    scale = 0.0                                         # dq = A^T (A A^T + lam I)^-1 e
    for c in range(n):
        if free[c]:
            s = 0.0
            for r in range(m):
                s += A[r, c] * A[r, c]
            scale = max(scale, s)
    for i in range(m):
        for j in range(i + 1):
            s = 0.0
            for c in range(n):
                if free[c]:
                    s += A[i, c] * A[j, c]
            Hm[i, j] = s
        gm[i] = e[i]
    damping = lam * max(scale, 1e-300)
    for i in range(m):
        Hm[i, i] += damping
    if not _solve_spd(Hm, gm, y):
        return False
    for c in range(n):
        s = 0.0
        if free[c]:
            for r in range(m):
                s += A[r, c] * y[r]
        dq[c] = s
    return True


@_jit
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
            v = min(max(v, lower[j]), upper[j])
        q_new[j] = v
        size = max(size, abs(v - q[j]))
    return size


@_jit
def workspace(n, m):
    """Scratch arrays for solve_one, allocated once per chunk of targets."""
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_),
            np.empty((4, 4)), np.empty((6, n)), np.empty((4, 4)), np.empty((6, n)),
            np.empty(m), np.empty((m, n)), np.empty(m), np.empty((m, n)),
            np.empty((3, 3)), np.empty(3),
            np.empty((n, n)), np.empty(n), np.empty((m, m)), np.empty(m), np.empty(m),
            np.empty(STALL_WINDOW))


@_jit
def _descend(q, Tt, kinds, offsets, pre, links, lower, upper, turn, mask, rows, tol_p, tol_r,
             iterations, method, stall, ws):
    """One attempt from q (updated in place to where it ends): (converged, cost, iterations).

    LM only keeps steps that lower the cost, so it ends at its best point; Newton takes every
    step and stops when the step vanishes. With `stall`, an attempt that stops making progress
    ends early.
    """
    n = q.shape[0]
    _, q_new, dq, free, T, J, T2, J2, e, A, e2, A2, E, w, Hn, gn, Hm, gm, y, earlier = ws
    pose_jacobian_one(q, kinds, offsets, pre, links, T, J)
    cost = _residual(T, J, Tt, rows, e, A, E, w)
    lam = 1e-3 if method == LM else 1e-15
    earlier[:] = np.inf                                 # the cost 1, 2, 3 iterations ago
    for it in range(iterations):
        ep, er = task_errors_one(T, Tt, mask)
        if ep < tol_p and er < tol_r:
            return True, cost, it
        if stall and it >= STALL_AFTER and cost > STALL_FACTOR * earlier[it % STALL_WINDOW]:
            return False, cost, it
        earlier[it % STALL_WINDOW] = cost
        for j in range(n):
            free[j] = True
        if not _step(A, e, lam, free, dq, Hn, gn, Hm, gm, y):
            lam *= 10.0
            if lam > MAX_LAMBDA:
                return False, cost, it + 1
            continue
        # Hold the joints this step pushes past a limit, and step with the others.
        held = False
        for j in range(n):
            if not turn[j] and ((q[j] <= lower[j] and dq[j] < 0.0)
                                or (q[j] >= upper[j] and dq[j] > 0.0)):
                free[j] = False
                held = True
        if held and not _step(A, e, lam, free, dq, Hn, gn, Hm, gm, y):
            lam *= 10.0
            if lam > MAX_LAMBDA:
                return False, cost, it + 1
            continue
        size = _bounded(q, dq, lower, upper, turn, q_new)
        pose_jacobian_one(q_new, kinds, offsets, pre, links, T2, J2)
        new_cost = _residual(T2, J2, Tt, rows, e2, A2, E, w)
        if method == NEWTON or new_cost < cost:
            for j in range(n):
                q[j] = q_new[j]
            T, T2, J, J2, e, e2, A, A2 = T2, T, J2, J, e2, e, A2, A
            cost = new_cost
            lam = max(lam / 10.0, 1e-15)
            if method == NEWTON and size < 1e-15:       # no step left: a stationary point
                return False, cost, it + 1
        else:
            lam *= 10.0
            if lam > MAX_LAMBDA:
                return False, cost, it + 1
    ep, er = task_errors_one(T, Tt, mask)
    return ep < tol_p and er < tol_r, cost, iterations


@_jit
def solve_one(Tt, starts, kinds, offsets, pre, links, lower, upper, turn, sample_lo, sample_hi,
              mask, rows, tol_p, tol_r, max_iter, restarts, method, state, q_out, ws):
    """Solve one target from starts (S, n), then random restarts, then a long polish of the
    best point found; q_out gets the solution or that best point. Returns
    (converged, iterations)."""
    n = starts.shape[1]
    q, dq = ws[0], ws[2]
    best, total = np.inf, 0
    for attempt in range(restarts + 1):
        for j in range(n):
            if attempt < starts.shape[0]:
                q[j] = starts[attempt, j]
            else:
                state, u = _random(state)
                q[j] = sample_lo[j] + u * (sample_hi[j] - sample_lo[j])
            dq[j] = 0.0
        _bounded(q, dq, lower, upper, turn, q)
        ok, cost, its = _descend(q, Tt, kinds, offsets, pre, links, lower, upper, turn, mask,
                                 rows, tol_p, tol_r, max_iter, method, True, ws)
        total += its
        if ok or cost < best:
            best = cost
            for j in range(n):
                q_out[j] = q[j]
        if ok:
            return True, total
    # Near a singularity convergence slows down: an attempt may end (or be judged stalled)
    # close to a solution it had no time to reach. Give the best point a long last run.
    for j in range(n):
        q[j] = q_out[j]
    ok, cost, its = _descend(q, Tt, kinds, offsets, pre, links, lower, upper, turn, mask, rows,
                             tol_p, tol_r, 10 * max_iter, method, False, ws)
    total += its
    if ok or cost < best:
        for j in range(n):
            q_out[j] = q[j]
    return ok, total


@_jit
def _solve_range(first, last, Tt, starts, kinds, offsets, pre, links, lower, upper, turn,
                 sample_lo, sample_hi, mask, rows, tol_p, tol_r, max_iter, restarts, method,
                 seed, q_out, converged, iterations):
    ws = workspace(starts.shape[2], rows.shape[0])
    for k in range(first, last):
        state = np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(k)
        converged[k], iterations[k] = solve_one(
            Tt[k], starts[k], kinds, offsets, pre, links, lower, upper, turn, sample_lo,
            sample_hi, mask, rows, tol_p, tol_r, max_iter, restarts, method, state, q_out[k], ws)


@_pjit
def solve_parallel(chunk, Tt, starts, kinds, offsets, pre, links, lower, upper, turn, sample_lo,
                   sample_hi, mask, rows, tol_p, tol_r, max_iter, restarts, method, seed, q_out,
                   converged, iterations):
    """Targets in chunks of `chunk`, the chunks in parallel (one workspace per chunk)."""
    N = Tt.shape[0]
    for c in numba.prange((N + chunk - 1) // chunk):
        _solve_range(c * chunk, min(N, (c + 1) * chunk), Tt, starts, kinds, offsets, pre, links,
                     lower, upper, turn, sample_lo, sample_hi, mask, rows, tol_p, tol_r,
                     max_iter, restarts, method, seed, q_out, converged, iterations)


def solve(robot, targets: np.ndarray, starts: np.ndarray, mask: np.ndarray, method: str,
          tol_position: float, tol_rotation: float, max_iter: int, restarts: int,
          seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Numeric IK for targets (N, 4, 4), trying starts (N, S, n) first, then random ones.

    Returns
    -------
    q : ndarray, shape (N, n)
        Best configuration found for each target (within the limits).
    converged : ndarray of bool, shape (N,)
    iterations : ndarray of int, shape (N,)
        Iterations summed over all attempts.
    """
    chain, k = robot.chain, robot.chain.kernel
    lower, upper = chain.lower, chain.upper
    # A revolute joint whose range is a full turn or more wraps instead of stopping.
    turn = chain.revolute & (upper - lower >= 2 * np.pi - 1e-12)
    sample_lo, sample_hi = chain.sampling_limits
    lower_w = np.where(turn & ~np.isfinite(lower), -np.pi, lower)
    N = targets.shape[0]
    q = np.empty((N, robot.n))
    converged = np.zeros(N, dtype=np.bool_)
    iterations = np.zeros(N, dtype=np.int64)
    # Chunks small enough to share the work out evenly, large enough that a workspace per
    # chunk costs nothing; a single chunk runs without starting threads.
    chunk = max(8, N // (4 * numba.get_num_threads()))
    args = (np.ascontiguousarray(targets), np.ascontiguousarray(starts), k.kinds, k.offsets,
            k.pre, k.links, lower_w, upper, turn, sample_lo, sample_hi, mask.astype(np.int64),
            np.flatnonzero(mask).astype(np.int64), float(tol_position), float(tol_rotation),
            int(max_iter), int(restarts), {"newton": NEWTON, "lm": LM}[method], int(seed), q,
            converged, iterations)
    if N <= chunk:
        _solve_range(0, N, *args)
    else:
        solve_parallel(chunk, *args)
    return q, converged, iterations


def _features(T: np.ndarray, mask: np.ndarray, length: float) -> np.ndarray:
    """Pose features (..., d) whose distances approximate the task error: the position, and
    the tool axes the mask constrains, times a length (m per rad)."""
    flags = np.flatnonzero(mask[3:])
    if flags.size == 3:
        axes = [0, 2]                       # two axes fix an orientation
    elif flags.size == 2:
        axes = [3 - flags.sum()]            # the pointing axis
    elif flags.size == 1:
        axes = [(flags[0] + 1) % 3]         # an axis the rotation about flags[0] turns
    else:
        axes = []
    return np.concatenate([T[..., :3, 3]] + [length * T[..., :3, a] for a in axes], axis=-1)


@_jit
def _cell(p, lo, inv, G):
    """Grid cell (i, j, k) of the point p (3,), clipped to the G x G x G grid."""
    return (min(max(int((p[0] - lo[0]) * inv[0]), 0), G - 1),
            min(max(int((p[1] - lo[1]) * inv[1]), 0), G - 1),
            min(max(int((p[2] - lo[2]) * inv[2]), 0), G - 1))


@_jit
def _grid(P, lo, inv, G):
    """Points P (S, 3) sorted by grid cell: (order (S,), start (G^3 + 1,)); the points of cell
    c are ``order[start[c]:start[c + 1]]``."""
    S = P.shape[0]
    cells = np.empty(S, dtype=np.int64)
    start = np.zeros(G * G * G + 1, dtype=np.int64)
    for s in range(S):
        i, j, k = _cell(P[s], lo, inv, G)
        cells[s] = (i * G + j) * G + k
        start[cells[s] + 1] += 1
    for c in range(G * G * G):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(S, dtype=np.int64)
    for s in range(S):
        order[fill[cells[s]]] = s
        fill[cells[s]] += 1
    return order, start


@_jit
def _nearest_one(p, f, F, lo, inv, G, order, start, best, dist):
    """The len(best) samples nearest the features f (d,) into best, searched cell shell by cell
    shell around the position p (3,) until enough are found."""
    count = best.shape[0]
    dist[:] = np.inf
    found = 0
    ci, cj, ck = _cell(p, lo, inv, G)
    for r in range(G):
        for i in range(max(ci - r, 0), min(ci + r, G - 1) + 1):
            for j in range(max(cj - r, 0), min(cj + r, G - 1) + 1):
                for k in range(max(ck - r, 0), min(ck + r, G - 1) + 1):
                    if max(abs(i - ci), abs(j - cj), abs(k - ck)) != r:
                        continue                        # scanned in an earlier shell
                    c = (i * G + j) * G + k
                    for a in range(start[c], start[c + 1]):
                        s = order[a]
                        d = 0.0
                        for m in range(f.shape[0]):
                            d += (F[s, m] - f[m]) ** 2
                        if d < dist[count - 1]:         # insert into the sorted shortlist
                            b = count - 1
                            while b > 0 and dist[b - 1] > d:
                                dist[b], best[b] = dist[b - 1], best[b - 1]
                                b -= 1
                            dist[b], best[b] = d, s
                        found += 1
        if found >= count and r >= 1:
            return


@_jit
def _nearest(P_targets, F_targets, F, lo, inv, G, order, start, best):
    for t in range(P_targets.shape[0]):
        _nearest_one(P_targets[t], F_targets[t], F, lo, inv, G, order, start, best[t],
                     np.empty(best.shape[1]))


@_pjit
def _nearest_parallel(P_targets, F_targets, F, lo, inv, G, order, start, best):
    for t in numba.prange(P_targets.shape[0]):
        _nearest_one(P_targets[t], F_targets[t], F, lo, inv, G, order, start, best[t],
                     np.empty(best.shape[1]))


@functools.lru_cache(maxsize=8)
def _bank(robot, flags: tuple[bool, ...], length: float, samples: int, seed: int):
    """A robot's seed bank for a task: configurations Q (S, n) drawn inside the limits, their
    `_features` F (S, d), and their tool positions sorted into a grid of about S cells
    (lo (3,), inv (3,) cells per m, G cells a side, order, start: see `_grid`).

    About 1 ms for 4096 samples of a 6-DOF arm, paid on the first call for a robot, task and
    seed; the bank is read-only after.
    """
    rng = np.random.default_rng([seed, 0x5EED])
    Q = rng.uniform(*robot.chain.sampling_limits, (samples, robot.n))
    T = fk(robot, Q)
    P = np.ascontiguousarray(T[:, :3, 3])
    G = max(1, round(samples ** (1 / 3)))
    lo = P.min(axis=0)
    inv = G / np.maximum(P.max(axis=0) - lo, 1e-12)
    order, start = _grid(P, lo, inv, G)
    bank = (Q, _features(T, np.array(flags), length), lo, inv, G, order, start)
    for a in bank:
        if isinstance(a, np.ndarray):
            a.setflags(write=False)
    return bank


def seed_starts(robot, targets: np.ndarray, mask: np.ndarray, length: float, count: int = 4,
                samples: int = 4096, seed: int = 0) -> np.ndarray:
    """Starts (N, count, n) for targets (N, 4, 4): the joint vectors of `count` of `samples`
    configurations drawn inside the limits (see `_bank`), those nearest the target by
    `_features`.

    Each target ranks the samples whose tool positions lie in the grid cells around its own
    (and further out until it has `count`), so the starts are near in position first, then in
    the constrained tool axes. A start near the target turns most solves into a few
    Gauss-Newton steps.
    """
    Q, F, lo, inv, G, order, start = _bank(robot, tuple(bool(f) for f in mask), float(length),
                                           samples, seed)
    best = np.empty((targets.shape[0], min(count, samples)), dtype=np.int64)
    nearest = _nearest_parallel if targets.shape[0] >= 64 else _nearest
    nearest(np.ascontiguousarray(targets[:, :3, 3]), _features(targets, mask, length), F, lo,
            inv, G, order, start, best)
    return Q[best]
