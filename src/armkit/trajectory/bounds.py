"""Exact bounds of a piecewise-polynomial trajectory: the largest velocity, acceleration or
jerk of every joint over every instant, not only at samples."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from armkit.trajectory.piecewise import Trajectory, falling_factorial


def peaks(tr: Trajectory, derivative: int) -> NDArray:
    """The largest |d^r q / dt^r| of every joint over the whole trajectory, exact, (n,).

    On each piece the derivative is a polynomial; its extrema lie at the piece's ends or at the
    real roots of the next derivative inside the piece, found as the eigenvalues of its
    companion matrix, in the piece's time scaled to [0, 1] for conditioning. Nine evenly
    spaced points of each piece are looked at too, so that a root the eigenvalues give as a
    complex pair (a double root, a flat extremum) costs no more than rounding.
    """
    c = tr.coefficients                                    # (m, K, n)
    m, K, n = c.shape
    h = np.diff(tr.breaks)
    k = np.arange(K)
    # Coefficients of the r-th derivative in the scaled time x = tau / h: c_k k!/(k-r)! h^(k-r).
    deriv = np.zeros((m, K, n))
    for j in range(derivative, K):
        deriv[:, j - derivative] = c[:, j] * falling_factorial(j, derivative) \
            * h[:, None] ** (j - derivative)
    flat = deriv.transpose(0, 2, 1).reshape(m * n, K)          # per piece and joint
    even = np.abs(_horner(flat, np.broadcast_to(np.linspace(0.0, 1.0, 9), (m * n, 9))))
    best = even.max(axis=1).reshape(m, n).max(axis=0)
    # Slope in x, highest power first, per piece and joint.
    slope = deriv[:, 1:] * k[1:, None]                       # (m, K - 1, n)
    polys = slope.transpose(0, 2, 1).reshape(m * n, K - 1)   # lowest power first
    degree = K - 2
    while degree > 0 and not np.any(polys[:, degree]):
        degree -= 1
    if degree >= 1:
        roots = _real_roots(polys[:, :degree + 1])           # (m * n, degree) NaN where none
        x = np.where((roots > 0) & (roots < 1), roots, np.nan)
        values = np.abs(_horner(flat, x))
        inside = np.nanmax(np.where(np.isnan(values), -np.inf, values), axis=1)
        best = np.maximum(best, inside.reshape(m, n).max(axis=0))
    return best


def _real_roots(polys: NDArray) -> NDArray:
    """Real roots (rows, d) of polynomials (rows, d + 1), lowest power first, NaN for the
    complex ones and for the missing ones of a row whose leading coefficient vanishes (its
    roots are those of the polynomial of one degree less)."""
    rows, d1 = polys.shape
    d = d1 - 1
    lead = polys[:, d]
    ok = np.abs(lead) > 1e-14 * np.max(np.abs(polys), axis=1)
    out = np.full((rows, d), np.nan)
    if ok.any():
        p = polys[ok] / lead[ok, None]
        companion = np.zeros((p.shape[0], d, d))
        companion[:, 1:, :-1] = np.eye(d - 1)
        companion[:, :, -1] = -p[:, :d]
        ev = np.linalg.eigvals(companion)
        real = np.abs(ev.imag) <= 1e-7 * np.maximum(1.0, np.abs(ev.real))
        out[ok] = np.where(real, ev.real, np.nan)
    if (~ok).any():
        out[~ok, :d - 1] = _real_roots(polys[~ok, :d])[:, :d - 1] if d > 1 else np.nan
    return out


def _horner(c: NDArray, x: NDArray) -> NDArray:
    """Polynomials c (rows, K), lowest power first, at x (rows, S)."""
    out = np.zeros(x.shape)
    for k in range(c.shape[1] - 1, -1, -1):
        out = out * x + c[:, k:k + 1]
    return out
