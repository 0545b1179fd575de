"""The piecewise-polynomial Trajectory: evaluation against NumPy, shapes, errors, helpers."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from armkit.errors import InputError
from armkit.trajectory import Trajectory, _kernels
from armkit.trajectory.piecewise import merge, shift


def random_trajectory(seed: int = 0, m: int = 5, K: int = 6, n: int = 3) -> Trajectory:
    rng = np.random.default_rng(seed)
    breaks = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.5, m))]
    return Trajectory(breaks, rng.normal(size=(m, K, n)))


def numpy_reference(tr: Trajectory, t: np.ndarray, r: int) -> np.ndarray:
    """d^r q / dt^r with np.polynomial, piece by piece."""
    i = np.clip(np.searchsorted(tr.breaks, t, side="right") - 1, 0, len(tr.breaks) - 2)
    out = np.empty(t.shape + (tr.n,))
    for j in range(tr.n):
        for piece in np.unique(i):
            p = np.polynomial.Polynomial(tr.coefficients[piece, :, j]).deriv(r)
            sel = i == piece
            out[sel, j] = p(t[sel] - tr.breaks[piece])
    return out


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("count, order", [
    (7, "random"), (3 * _kernels.PARALLEL_FROM + 5, "random"),       # serial, parallel
    (3 * _kernels.PARALLEL_FROM + 5, "sorted"),                       # runs within a piece
    (50, "breaks"),                                                   # exactly on the breaks
])
def test_sample_matches_numpy_polynomials(count, order, threads, monkeypatch):
    import armkit.threads

    monkeypatch.setattr(armkit.threads, "_chosen", threads)    # as armkit.set_num_threads
    tr = random_trajectory()
    t = np.random.default_rng(1).uniform(tr.start, tr.end, count)
    if order == "sorted":
        t = np.sort(t)
    elif order == "breaks":
        t = np.sort(np.r_[t, np.repeat(tr.breaks, 10)])
    s = tr.sample(t)
    for r, values in enumerate((s.q, s.qd, s.qdd, s.qddd)):
        np.testing.assert_allclose(values, numpy_reference(tr, t, r), rtol=1e-12, atol=1e-10)
        np.testing.assert_array_equal(tr.evaluate(t, r), values)


@pytest.mark.parametrize("shape", [(), (4,), (2, 3)])
def test_leading_shapes_match_single_calls(shape):
    tr = random_trajectory(n=2)
    t = np.random.default_rng(2).uniform(tr.start, tr.end, shape)
    s = tr.sample(t)
    assert s.q.shape == shape + (2,) and s.t.shape == shape
    for index in np.ndindex(shape):
        np.testing.assert_array_equal(s.qdd[index], tr.sample(t[index]).qdd)


def test_ends_and_breaks_evaluate_from_the_right_piece():
    tr = random_trajectory()
    h = np.diff(tr.breaks)
    np.testing.assert_allclose(tr.evaluate(tr.breaks[:-1]), tr.coefficients[:, 0], atol=1e-15)
    last = tr.piece_values(h[-1:, None] * np.ones((len(h), 1)), 0)[-1, 0]
    np.testing.assert_allclose(tr.evaluate(tr.end), last, rtol=1e-14)


@pytest.mark.parametrize("t", [-0.1, 100.0, np.nan])
def test_times_outside_raise(t):
    with pytest.raises(InputError, match="t: expected times within"):
        random_trajectory().sample([0.5, t])


@pytest.mark.parametrize("breaks, coefficients, words", [
    ([0, 1, 1], np.zeros((2, 2, 1)), "strictly increasing"),
    ([0, 1], np.zeros((2, 2, 1)), "coefficients: expected shape (1, K, n)"),
    ([0], np.zeros((0, 2, 1)), "breaks: expected shape"),
    ([0, 1], np.full((1, 2, 1), np.nan), "finite"),
])
def test_bad_trajectories_are_refused(breaks, coefficients, words):
    with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)")):
        Trajectory(breaks, coefficients)


def test_scaled_runs_slower_along_the_same_path():
    tr = random_trajectory()
    slow = tr.scaled(2.0)
    assert slow.duration == pytest.approx(2 * tr.duration)
    t = np.linspace(tr.start, tr.end, 50)
    np.testing.assert_allclose(slow.evaluate(2 * t), tr.evaluate(t), atol=1e-12)
    np.testing.assert_allclose(slow.evaluate(2 * t, 2), tr.evaluate(t, 2) / 4, atol=1e-12)


@given(st.floats(-3, 3), st.integers(0, 10_000))
def test_shift_re_expands_the_same_polynomial(delta, seed):
    c = np.random.default_rng(seed).normal(size=(6, 2))
    x = np.linspace(-1, 1, 7)
    before = np.polynomial.polynomial.polyval(x + delta, c).T
    after = np.polynomial.polynomial.polyval(x, shift(c, delta)).T
    np.testing.assert_allclose(after, before, rtol=1e-9, atol=1e-9 * np.abs(before).max())


def test_merge_keeps_each_joints_values():
    rng = np.random.default_rng(3)
    times = np.c_[np.zeros(3), np.sort(rng.uniform(0, 2, (3, 3)), axis=1), np.full(3, 2.0)]
    times[1, 2] = times[1, 1]                                   # a zero-length piece
    coefficients = rng.normal(size=(3, 4, 3))
    breaks, c = merge(times, coefficients)
    merged = Trajectory(breaks, c)
    t = np.linspace(0, 2, 301)
    for j in range(3):
        own = Trajectory(times[j][np.r_[True, np.diff(times[j]) > 0]],
                         coefficients[j][np.diff(times[j]) > 0][..., None])
        np.testing.assert_allclose(merged.evaluate(t)[:, j], own.evaluate(t)[:, 0], atol=1e-12)
