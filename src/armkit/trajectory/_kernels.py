"""numba kernels of the trajectory package: piecewise-polynomial evaluation, rest-to-rest
profile timing, and the TOPP-RA passes.

Evaluation comes twice, serial for small batches (no thread start-up) and parallel over chunks
of samples, as in `armkit.kinematics._kernels`. A light evaluation or retiming (`armkit.jit`)
runs the same arithmetic as NumPy over all samples or grid stages at once (`_evaluate_numpy`,
`_topp_numpy`), not the kernels' loops as Python. benchmarks/trajectory.py measures each
against scipy, ruckig, toppra or a vectorised NumPy version of the same work.
"""

from __future__ import annotations

import math

import numpy as np

from armkit.jit import kernel, numba_threads, prange
from armkit.threads import threads_for

_jit = kernel(cache=True, nogil=True)
# The profile kernels divide only by numbers they have checked or tested for zero: under
# NumPy's error model numba leaves out its division-by-zero checks and compiles them faster.
_profile_jit = kernel(cache=True, nogil=True, error_model="numpy")
_pjit = kernel(cache=True, nogil=True, parallel=True)
_inline = kernel(inline="always")

PARALLEL_FROM = 4096        # samples; below this, thread start-up costs more than it saves
_CHUNK = 16384              # samples per parallel task
LIGHT_SAMPLES = 4096        # samples an evaluation runs in NumPy before its kernel is compiled
_BLOCK = 256                # samples of one piece evaluated together
_RUN = 8                    # shorter runs of samples in one piece go one by one


@_jit
def _piece(breaks, t, guess):
    """Index i of the piece with breaks[i] <= t < breaks[i + 1] (the last piece takes the end)."""
    m = breaks.shape[0] - 1
    if breaks[guess] <= t and (t < breaks[guess + 1] or guess == m - 1):
        return guess
    lo, hi = 0, m - 1
    while lo < hi:                      # largest i with breaks[i] <= t, clipped to [0, m - 1]
        mid = (lo + hi + 1) // 2
        if breaks[mid] <= t:
            lo = mid
        else:
            hi = mid - 1
    return lo


@_jit
def _span(breaks, table, t, out, start, stop):
    """Samples start..stop-1: out[r, s, j] = derivative r of joint j at t[s].

    table[i, r, k, j] holds coefficient k of derivative r on piece i (falling factorials
    applied, powers above K - 1 - r zero), so each derivative is one Horner pass; a derivative
    above the degree (r >= K) is its zero row k = 0. Sorted times
    come in runs that share a piece; a run is evaluated with the samples in the innermost
    loop, which the compiler vectorises (a Horner chain per sample and joint would wait on
    itself). Times in no order fall back to one sample at a time.
    """
    nder, K, n = table.shape[1], table.shape[2], table.shape[3]
    last = breaks.shape[0] - 2
    tau, acc = np.empty(_BLOCK), np.empty(_BLOCK)
    i, s = 0, start
    while s < stop:
        i = _piece(breaks, t[s], i)
        top = breaks[i + 1] if i < last else np.inf
        e, limit = s + 1, min(stop, s + _BLOCK)
        while e < limit and breaks[i] <= t[e] < top:
            e += 1
        if e - s < _RUN:
            x = t[s] - breaks[i]
            for r in range(nder):
                top = max(K - 1 - r, 0)
                for j in range(n):
                    v = table[i, r, top, j]
                    for k in range(top - 1, -1, -1):
                        v = v * x + table[i, r, k, j]
                    out[r, s, j] = v
            s += 1
            continue
        count = e - s
        for q in range(count):
            tau[q] = t[s + q] - breaks[i]
        for r in range(nder):
            top = max(K - 1 - r, 0)
            for j in range(n):
                c = table[i, r, top, j]
                for q in range(count):
                    acc[q] = c
                for k in range(top - 1, -1, -1):
                    c = table[i, r, k, j]
                    for q in range(count):
                        acc[q] = acc[q] * tau[q] + c
                for q in range(count):
                    out[r, s + q, j] = acc[q]
        s = e


def _evaluate_numpy(breaks, table, t, out):
    """`evaluate` as NumPy over all samples at once, each value by the same Horner pass (the
    same bits): what a light evaluation runs instead of the kernel's loops."""
    piece = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, breaks.shape[0] - 2)
    x = (t - breaks[piece])[:, None]
    nder, K = table.shape[1], table.shape[2]
    for r in range(nder):
        top = max(K - 1 - r, 0)
        value = table[piece, r, top]
        for k in range(top - 1, -1, -1):
            value = value * x + table[piece, r, k]
        out[r] = value


@kernel(cache=True, nogil=True, python=_evaluate_numpy)
def evaluate(breaks, table, t, out):
    _span(breaks, table, t, out, 0, t.shape[0])


@_pjit
def evaluate_parallel(breaks, table, t, out):
    N = t.shape[0]
    chunks = (N + _CHUNK - 1) // _CHUNK
    for c in prange(chunks):
        _span(breaks, table, t, out, c * _CHUNK, min(N, (c + 1) * _CHUNK))


def run_evaluate(breaks: np.ndarray, table: np.ndarray, t: np.ndarray, out: np.ndarray) -> None:
    """Call the serial evaluation, or the parallel one on as many threads as the number of
    samples and the idle cores are worth (`armkit.threads.threads_for`); up to LIGHT_SAMPLES
    samples run light (`armkit.jit`)."""
    threads = threads_for(t.shape[0], PARALLEL_FROM)
    if threads == 1:
        evaluate.sized(t.shape[0], breaks, table, t, out, few=LIGHT_SAMPLES)
        return
    with numba_threads(threads):
        evaluate_parallel(breaks, table, t, out)


# --- rest-to-rest profile timing (profiles.py) ------------------------------------------------
# Each returns the phase times of one joint moving a distance D >= 0 from rest to rest:
# (tj, ta, tv) = jerk time, accelerating time (= decelerating time), cruise time; a trapezoid
# has tj = 0. Biagiotti & Melchiorri (2008), sections 3.2.2 and 3.4, zero end velocities.

@_profile_jit
def _trapezoid_shortest(D, V, A):
    if D * A >= V * V:                          # cruise phase exists
        return 0.0, V / A, D / V - V / A
    return 0.0, math.sqrt(D / A), 0.0


@_profile_jit
def _trapezoid_within(D, V, A, T):
    """The trapezoid taking exactly T (>= its shortest), keeping A: the cruise velocity is the
    smaller root of v^2 - A T v + A D = 0, written 2 D / (T + sqrt(T^2 - 4 D / A))."""
    if D <= 0.0:                                # no motion: rest for T (T may be 0)
        return 0.0, 0.0, T
    v = 2.0 * D / (T + math.sqrt(max(T * T - 4.0 * D / A, 0.0)))
    return 0.0, v / A, max(T - 2.0 * v / A, 0.0)


@_profile_jit
def _double_s_shortest(D, V, A, J):
    if V * J >= A * A:                          # amax reached on the way to vmax
        tj, ta = A / J, A / J + V / A
    else:
        tj = math.sqrt(V / J)
        ta = 2.0 * tj
    tv = D / V - ta if V < math.inf else -1.0
    if tv >= 0.0:
        return tj, ta, tv
    if D >= 2.0 * A * A * A / (J * J):          # vmax never reached, amax reached
        tj = A / J
        return tj, 0.5 * (tj + math.sqrt(tj * tj + 4.0 * D / A)), 0.0
    tj = (D / (2.0 * J)) ** (1.0 / 3.0)
    return tj, 2.0 * tj, 0.0


@_profile_jit
def _double_s_within(D, V, A, J, T):
    """The double S taking exactly T (>= its shortest), keeping A and J.

    T = D / v + Ta(v) falls as the cruise velocity v rises, so one v fits. With amax reached
    (v >= A^2 / J), Ta = v / A + A / J and v is the smaller root of a quadratic. Otherwise
    Ta = 2 Tj, v = J Tj^2 and 2 Tj^3 - T Tj^2 + D / J = 0, whose root in (0, T/3] is
    T/6 + T/3 cos(theta/3 - 2 pi/3) with cos(theta) = 1 - 54 D / (J T^3) (the trigonometric
    solution of a cubic with three real roots), polished by two Newton steps.
    """
    if D <= 0.0:
        return 0.0, 0.0, T
    if D >= 2.0 * A * A * A / (J * J) and T <= D * J / (A * A) + 2.0 * A / J:
        b = T - A / J
        v = 2.0 * D / (b + math.sqrt(max(b * b - 4.0 * D / A, 0.0)))
        ta = v / A + A / J
        return A / J, ta, max(T - 2.0 * ta, 0.0)
    c = min(max(1.0 - 54.0 * D / (J * T * T * T), -1.0), 1.0)
    u = T / 6.0 + T / 3.0 * math.cos(math.acos(c) / 3.0 - 2.0 * math.pi / 3.0)
    for _ in range(2):
        df = 6.0 * u * u - 2.0 * T * u
        if df != 0.0:
            u -= (2.0 * u * u * u - T * u * u + D / J) / df
    u = min(max(u, 0.0), T / 3.0)
    return u, 2.0 * u, max(T - 4.0 * u, 0.0)


@_profile_jit
def _phases(kind, D, sign, tj, ta, tv, times, values):
    """One joint's phase start times (from 0) and signed top derivative per phase.

    Peak values come from the timing so that the distance is exact: for these symmetric
    rest-to-rest profiles D = v (ta + tv), v = a (ta - tj) and a = j tj.
    """
    v = D / (ta + tv) if ta + tv > 0.0 else 0.0
    a = v / (ta - tj) if ta - tj > 0.0 else 0.0
    if kind == 2:
        # A loop, not three calls with constant k: numba would compile _put once per constant.
        for k, (duration, top) in enumerate(((ta, sign * a), (tv, 0.0), (ta, -sign * a))):
            _put(times, values, k, duration, top)
        return
    j = sign * a / tj if tj > 0.0 else 0.0
    for k, (duration, top) in enumerate(((tj, j), (ta - 2.0 * tj, 0.0), (tj, -j), (tv, 0.0),
                                         (tj, -j), (ta - 2.0 * tj, 0.0), (tj, j))):
        _put(times, values, k, duration, top)


@_profile_jit
def _put(times, values, k, duration, top):
    if k == 0:
        times[0] = 0.0
    times[k + 1] = times[k] + max(duration, 0.0)
    values[k] = top


@_profile_jit
def _limit(per_joint, number, n, i, k):
    """The limit of joint k of a problem of n joints, flat index i: per_joint[i] (one value per
    joint of every problem), per_joint[k] (one per joint, the same for every problem), the
    one value of a length-1 array, or the number when per_joint is empty. (Branches, not
    i % length: an integer remainder per limit and joint slowed the batch by a fifth.)"""
    length = per_joint.shape[0]
    if length > n:
        return per_joint[i]
    if length > 1:
        return per_joint[k]
    return per_joint[0] if length else number


@_profile_jit
def profile_timing(kind, n, q0, qf, V, A, J, v, a, j, phase, times, values):
    """Phases of every joint of every problem; kind 2 trapezoid, 3 double S.

    q0, qf (P n,): start and goal of P problems of n joints, flat. V, A, J: the limits, each
    one value per joint (length n, for every problem; or P n), or empty for the number v, a or
    j that holds for every joint (a trapezoid's J is unused: any positive value). Out: times
    (P n, K + 1), the start of each phase and the end, and values (P n, K), the signed top
    derivative of each phase (K = 3 or 7). Returns 0, or the first bad input: 1 q0 or qf not
    finite, 2 V, 3 A, 4 J not a valid limit, 5 lengths that are not P problems of n >= 1
    joints (nothing is written then; the caller broadcasts). One problem and a batch take the
    same call, and a limit given as a number needs no array.

    With phase sync, one shape over a unit distance under the tightest limit per unit distance,
    scaled by each joint's distance; with time sync, the slowest joint's shortest duration for
    every joint.
    """
    N = q0.shape[0]
    if not (n > 0 and N % n == 0 and qf.shape[0] == N and times.shape[0] >= N
            and values.shape[0] >= N):
        return 5
    for L in (V.shape[0], A.shape[0], J.shape[0]):
        if not (L <= 1 or L == n or L == N):
            return 5
    P = N // n
    for p in range(P):                          # checks first: 1 q, 2 V, 3 A, 4 J is bad
        for k in range(n):
            i = p * n + k
            if not (math.isfinite(q0[i]) and math.isfinite(qf[i])):
                return 1
            if not _limit(V, v, n, i, k) > 0.0:
                return 2
            Ai = _limit(A, a, n, i, k)
            if not (Ai > 0.0 and (kind == 3 or Ai < math.inf)):
                return 3
            if not (0.0 < _limit(J, j, n, i, k) < math.inf):
                return 4
    # Per joint of the problem at hand: its limits V, A, J, then its own (tj, ta, tv).
    own = np.empty((n, 6))
    for p in range(P):
        first = p * n
        for k in range(n):
            i = first + k
            own[k, 0], own[k, 1] = _limit(V, v, n, i, k), _limit(A, a, n, i, k)
            own[k, 2] = _limit(J, j, n, i, k)
        if phase:
            v1 = a1 = j1 = math.inf
            for k in range(n):
                D = abs(qf[first + k] - q0[first + k])
                if D > 0.0:
                    v1, a1, j1 = (min(v1, own[k, 0] / D), min(a1, own[k, 1] / D),
                                  min(j1, own[k, 2] / D))
            if v1 == a1 == j1 == math.inf:
                tj = ta = tv = 0.0
            elif kind == 2:
                tj, ta, tv = _trapezoid_shortest(1.0, v1, a1)
            else:
                tj, ta, tv = _double_s_shortest(1.0, v1, a1, j1)
            for i in range(first, first + n):
                d = qf[i] - q0[i]
                _phases(kind, abs(d), math.copysign(1.0, d), tj, ta, tv, times[i], values[i])
            continue
        T = 0.0
        for k in range(n):
            D = abs(qf[first + k] - q0[first + k])
            if kind == 2:
                own[k, 3], own[k, 4], own[k, 5] = _trapezoid_shortest(D, own[k, 0], own[k, 1])
            else:
                own[k, 3], own[k, 4], own[k, 5] = _double_s_shortest(D, own[k, 0], own[k, 1],
                                                                     own[k, 2])
            if D > 0.0:
                T = max(T, 2.0 * own[k, 4] + own[k, 5])
        for k in range(n):
            i = first + k
            d = qf[i] - q0[i]
            tj, ta, tv = own[k, 3], own[k, 4], own[k, 5]
            if d == 0.0 or 2.0 * ta + tv < T * (1.0 - 1e-12):
                # Solving for T = the joint's own shortest would amplify rounding through a
                # square root near zero, so the slowest joint keeps its own profile.
                if kind == 2:
                    tj, ta, tv = _trapezoid_within(abs(d), own[k, 0], own[k, 1], T)
                else:
                    tj, ta, tv = _double_s_within(abs(d), own[k, 0], own[k, 1], own[k, 2], T)
            _phases(kind, abs(d), math.copysign(1.0, d), tj, ta, tv, times[i], values[i])
    return 0


@_profile_jit
def profile_pieces(order, times, values, q0, tol):
    """One problem's profile as one piecewise polynomial: breaks (m + 1,) merged over the
    joints (closer than tol x duration count as one) and coefficients (m, order + 1, n), each
    joint's state integrated exactly from rest at q0 through its phases (times (n, P + 1),
    top derivatives (n, P)) and expanded about every merged break."""
    n, P = values.shape
    start, end = times[0, 0], times[0, P]
    eps = tol * (end - start)
    # The joints' inner phase times, sorted by insertion (a few dozen: cheaper to compile than
    # np.sort, whose quicksort is eight more functions for numba to build on a first call).
    inner = np.empty(n * (P - 1))
    count = 0
    for j in range(n):
        for k in range(1, P):
            t = times[j, k]
            i = count
            while i > 0 and inner[i - 1] > t:
                inner[i] = inner[i - 1]
                i -= 1
            inner[i] = t
            count += 1
    breaks = np.empty(inner.shape[0] + 2)
    breaks[0] = start
    m = 1
    for t in inner:
        if start + eps < t < end - eps and t - breaks[m - 1] > eps:
            breaks[m] = t
            m += 1
    breaks[m] = end
    # State (q, v, a) at the start of every phase of every joint.
    state = np.zeros((n, P + 1, 3))
    for j in range(n):
        q, v, a = q0[j], 0.0, 0.0
        for k in range(P):
            state[j, k, 0], state[j, k, 1], state[j, k, 2] = q, v, a
            h, top = times[j, k + 1] - times[j, k], values[j, k]
            if order == 2:
                q, v, a = q + v * h + top * h * h / 2.0, v + top * h, 0.0
            else:
                q, v, a = (q + v * h + a * h * h / 2.0 + top * h * h * h / 6.0,
                           v + a * h + top * h * h / 2.0, a + top * h)
        state[j, P, 0], state[j, P, 1], state[j, P, 2] = q, v, a
    c = np.zeros((m, order + 1, n))
    for j in range(n):
        k = 0
        for i in range(m):
            b = breaks[i]
            while k < P - 1 and times[j, k + 1] <= b + eps:
                k += 1
            tau, top = b - times[j, k], values[j, k]
            q, v, a = state[j, k, 0], state[j, k, 1], state[j, k, 2]
            if order == 2:
                c[i, 0, j] = q + v * tau + top * tau * tau / 2.0
                c[i, 1, j] = v + top * tau
                c[i, 2, j] = top / 2.0
            else:
                c[i, 0, j] = q + v * tau + a * tau * tau / 2.0 + top * tau * tau * tau / 6.0
                c[i, 1, j] = v + a * tau + top * tau * tau / 2.0
                c[i, 2, j] = (a + top * tau) / 2.0
                c[i, 3, j] = top / 6.0
    return breaks[:m + 1].copy(), c


# --- TOPP-RA (retime.py) -----------------------------------------------------------------------
# Path q(s) on a grid s_0 < ... < s_N; unknowns x_i = sdot^2 at s_i and u_i = sddot on
# [s_i, s_{i+1}], with x_{i+1} = x_i + 2 ds_i u_i. A constraint channel k is a quantity
# a_k(s) u + b_k(s) x + c_k(s) held within +-U_k(s): a joint's acceleration (a = q', b = q'',
# c = 0) or its torque (a = M q', b = M q'' + C(q, q') q', c = g(q)). Stage i holds every
# channel at both ends of its interval, at s_{i+1} with x_{i+1} put in (toppra's
# "interpolation" discretisation), as rows alpha u + beta x <= gamma, and keeps x_{i+1} inside
# the next controllable set [lo, hi]: the rows (2 ds, 1, hi) and (-2 ds, -1, -lo).
# The x a stage allows is found by Fourier-Motzkin: u is bounded below by the rows with
# alpha < 0 and above by those with alpha > 0; a pair (k below, l above) is compatible iff
# g x <= h, g = beta_k alpha_l - beta_l alpha_k, h = gamma_k alpha_l - gamma_l alpha_k; a row
# with alpha = 0 bounds x alone. Only the pairs with a row of the next set depend on the pass:
# the pairs of channel rows are taken for every stage first (`_channel_rows_numpy`), and the
# pass is then linear in the rows.

@_inline
def _narrow(least, largest, g, h):
    """[least, largest] narrowed to the x with g x <= h; below 1 and above 0 (empty) when no x
    meets it (g = 0, h < 0)."""
    if g > 0.0:
        return least, min(largest, h / g)
    if g < 0.0:
        return max(least, h / g), largest
    if h < 0.0:
        return max(least, 1.0), min(largest, 0.0)
    return least, largest


def narrow_all(lo, hi, g, h, axis):
    """`_narrow` of [lo, hi] by every row (g, h) along `axis` at once (NumPy)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = h / g
    hi = np.minimum(hi, np.where(g > 0.0, bound, np.inf).min(axis=axis))
    lo = np.maximum(lo, np.where(g < 0.0, bound, -np.inf).max(axis=axis))
    none = ((g == 0.0) & (h < 0.0)).any(axis=axis)
    return np.where(none, np.maximum(lo, 1.0), lo), np.where(none, np.minimum(hi, 0.0), hi)


def _channel_rows_numpy(a, b, c, bound, ds, xv):
    """Each stage's channel rows, and the x their pairs alone allow (NumPy).

    Parameters
    ----------
    a, b, c, bound : (N + 1, m) arrays
        Each channel's a(s), b(s), c(s) and bound U(s) > 0 at the grid points.
    ds : (N,) array
        Grid steps.
    xv : (N + 1,) array
        Bound on x at each grid point from the velocity limits (inf where there is none).

    Returns
    -------
    rows : (N, 2, 2 m, 3) array
        Per stage, the rows (alpha, beta, gamma) that bound u from below (``[:, 0]``,
        alpha < 0) and from above (``[:, 1]``, alpha > 0), at s_i then s_{i+1}; alpha = 0
        where a = 0 (such a channel bounds x alone, in `allowed`).
    allowed : (N, 2) array
        Per stage, the least and largest x in [0, xv] the channel rows allow; least > largest
        where they allow none.
    """
    alpha = np.concatenate([a[:-1], a[1:] + 2.0 * ds[:, None] * b[1:]], axis=1)
    beta = np.concatenate([b[:-1], b[1:]], axis=1)
    offset = np.concatenate([c[:-1], c[1:]], axis=1)
    gamma = np.concatenate([bound[:-1], bound[1:]], axis=1)
    sign = np.sign(alpha)
    up = np.stack([np.abs(alpha), sign * beta, gamma - sign * offset], axis=-1)
    down = np.stack([-np.abs(alpha), -sign * beta, gamma + sign * offset], axis=-1)
    rows = np.stack([down, up], axis=1)
    # Rows with alpha = 0 bound x directly: beta x + offset within +-gamma.
    flat = alpha == 0.0
    lo, hi = narrow_all(np.zeros(alpha.shape[0]), xv[:-1],
                           np.where(flat, beta, 0.0), np.where(flat, gamma - offset, 0.0), 1)
    lo, hi = narrow_all(lo, hi, np.where(flat, -beta, 0.0),
                           np.where(flat, gamma + offset, 0.0), 1)
    below, above = rows[:, 0, :, None, :], rows[:, 1, None, :, :]
    g = below[..., 1] * above[..., 0] - above[..., 1] * below[..., 0]
    h = below[..., 2] * above[..., 0] - above[..., 2] * below[..., 0]
    pair = (below[..., 0] < 0.0) & (above[..., 0] > 0.0)
    lo, hi = narrow_all(lo, hi, np.where(pair, g, 0.0), np.where(pair, h, 0.0), (1, 2))
    return rows, np.column_stack([lo, hi])


@_jit
def _channel_rows(a, b, c, bound, ds, xv, rows, allowed):
    """`_channel_rows_numpy` as loops, filling `rows` and `allowed` (the compiled tier)."""
    N, m = ds.shape[0], a.shape[1]
    for i in range(N):
        least, largest = 0.0, xv[i]
        for k in range(2 * m):
            j = k % m
            if k < m:
                al, be, of, ga = a[i, j], b[i, j], c[i, j], bound[i, j]
            else:
                al = a[i + 1, j] + 2.0 * ds[i] * b[i + 1, j]
                be, of, ga = b[i + 1, j], c[i + 1, j], bound[i + 1, j]
            sign = 1.0 if al > 0.0 else -1.0 if al < 0.0 else 0.0
            rows[i, 1, k, 0], rows[i, 1, k, 1], rows[i, 1, k, 2] = abs(al), sign * be, ga - sign * of
            rows[i, 0, k, 0], rows[i, 0, k, 1], rows[i, 0, k, 2] = (-abs(al), -(sign * be),
                                                                    ga + sign * of)
            if al == 0.0:
                least, largest = _narrow(least, largest, be, ga - of)
                least, largest = _narrow(least, largest, -be, ga + of)
        for k in range(2 * m):
            alpha_k, beta_k, gamma_k = rows[i, 0, k, 0], rows[i, 0, k, 1], rows[i, 0, k, 2]
            for l in range(2 * m):
                alpha_l, beta_l, gamma_l = rows[i, 1, l, 0], rows[i, 1, l, 1], rows[i, 1, l, 2]
                if alpha_k < 0.0 and alpha_l > 0.0:
                    least, largest = _narrow(least, largest, beta_k * alpha_l - beta_l * alpha_k,
                                             gamma_k * alpha_l - gamma_l * alpha_k)
        allowed[i, 0], allowed[i, 1] = least, largest


@_jit
def _pass(rows, allowed, ds, end_top, free_start, x):
    """Backward pass (controllable sets), then the greedy forward pass; x is filled (see
    `topp`; `rows` and `allowed` are `_channel_rows_numpy`'s)."""
    N, m = ds.shape[0], rows.shape[2]
    lo, hi = np.empty(N + 1), np.empty(N + 1)
    lo[N], hi[N] = 0.0, end_top
    for i in range(N - 1, -1, -1):
        step = 2.0 * ds[i]
        least, largest = allowed[i, 0], allowed[i, 1]
        for k in range(m):
            alpha, beta, gamma = rows[i, 0, k, 0], rows[i, 0, k, 1], rows[i, 0, k, 2]
            if alpha < 0.0:                     # with the next set's row (2 ds, 1, hi)
                least, largest = _narrow(least, largest, beta * step - alpha,
                                         gamma * step - hi[i + 1] * alpha)
            alpha, beta, gamma = rows[i, 1, k, 0], rows[i, 1, k, 1], rows[i, 1, k, 2]
            if alpha > 0.0:                     # with the next set's row (-2 ds, -1, -lo)
                least, largest = _narrow(least, largest, -alpha + beta * step,
                                         -lo[i + 1] * alpha + gamma * step)
        if least > largest * (1.0 + 1e-9) + 1e-12:
            return i
        lo[i], hi[i] = least, max(largest, least)
    x[0] = hi[0] if free_start else 0.0
    if lo[0] > x[0] + 1e-12:
        return 0
    for i in range(N):
        step = 2.0 * ds[i]
        u = (hi[i + 1] - x[i]) / step           # the largest u every row allows
        for k in range(m):
            alpha = rows[i, 1, k, 0]
            if alpha > 0.0:
                u = min(u, (rows[i, 1, k, 2] - rows[i, 1, k, 1] * x[i]) / alpha)
        x[i + 1] = min(max(x[i] + step * u, lo[i + 1]), hi[i + 1])
    return -1


def _topp_numpy(a, b, c, bound, xv, ds, end_top, free_start, x):
    """`topp` for a light call: the channel rows in NumPy, then the pass as Python."""
    rows, allowed = _channel_rows_numpy(a, b, c, bound, ds, xv)
    return _pass(rows, allowed, ds, end_top, free_start, x)


@kernel(cache=True, nogil=True, python=_topp_numpy)
def topp(a, b, c, bound, xv, ds, end_top, free_start, x):
    """Backward pass (controllable sets), then the greedy forward pass; x (N + 1,) is filled.

    a, b, c, bound (N + 1, m) are the constraint channels at the grid points (each holds
    ``|a u + b x + c| <= bound``), xv (N + 1,) the velocity bound on x, ds (N,) the grid
    steps. The end set is [0, end_top]; the start is x = 0, or with free_start the largest
    controllable x. Returns -1 on success, else the first grid index where the path cannot
    be followed.
    """
    N, m = ds.shape[0], a.shape[1]
    rows, allowed = np.empty((N, 2, 2 * m, 3)), np.empty((N, 2))
    _channel_rows(a, b, c, bound, ds, xv, rows, allowed)
    return _pass(rows, allowed, ds, end_top, free_start, x)
