"""Motions played one after another: the same values as each motion at its own time, knots
carried over, jumps refused."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armkit.errors import InputError
from armkit.trajectory import jerk_limited, quintic, trapezoidal
from armkit.trajectory.concatenate import concatenate
from armkit.trajectory.piecewise import at_rest


@settings(max_examples=25, deadline=None)
@given(st.lists(st.lists(st.floats(-3, 3), min_size=2, max_size=2), min_size=2, max_size=5),
       st.sampled_from(["quintic", "trapezoidal", "jerk_limited"]))
def test_each_motion_plays_at_its_own_time(points, law):
    points = np.array(points)
    build = {"quintic": lambda a, b: quintic(a, b, 1.5),
             "trapezoidal": lambda a, b: trapezoidal(a, b, 2.0, 4.0),
             "jerk_limited": lambda a, b: jerk_limited(a, b, 2.0, 4.0, 30.0)}[law]
    pieces = [build(a, b) for a, b in zip(points, points[1:])]
    whole = concatenate(pieces)
    starts = np.r_[0.0, np.cumsum([p.duration for p in pieces])]
    assert whole.duration == pytest.approx(starts[-1], abs=1e-12)
    for p, t0 in zip(pieces, starts):
        if p.duration == 0:
            continue
        tau = np.linspace(0.0, p.duration, 7)
        got = whole.sample(t0 + tau)
        want = p.sample(p.start + tau)
        for r in range(4):
            if r < 2 or law == "quintic":     # the profiles' steps sit on their breaks
                np.testing.assert_allclose(got.derivative(r)[1:-1], want.derivative(r)[1:-1],
                                           atol=1e-9)
        np.testing.assert_allclose(got.q, want.q, atol=1e-9)
    assert set(np.round(starts, 9)) <= set(np.round(whole.knots, 9))


def test_a_jump_between_motions_is_refused():
    with pytest.raises(InputError, match=r"motions\[1\]: expected to start where"):
        concatenate([quintic([0.0], [1.0], 1.0), quintic([1.5], [0.0], 1.0)])


def test_motions_of_different_joints_and_none_are_refused():
    with pytest.raises(InputError, match="at least one"):
        concatenate([])
    with pytest.raises(InputError, match="of 1 joints each"):
        concatenate([quintic([0.0], [1.0], 1.0), quintic([1.0, 0.0], [0.0, 0.0], 1.0)])


def test_a_motion_at_rest_takes_no_time():
    a, b = quintic([0.0], [1.0], 1.0), quintic([1.0], [0.0], 2.0)
    whole = concatenate([a, at_rest([1.0]), b])
    assert whole.duration == pytest.approx(3.0)
    assert concatenate([at_rest([2.0])]).evaluate(0.0)[0] == 2.0
