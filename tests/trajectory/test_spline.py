"""Mixed-degree splines: knots, continuity and end conditions to 1e-9, the least-jerk rule,
the paper's Table 1 case, and scipy's interpolating splines as references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline, make_interp_spline

import armkit
from armkit.errors import InputError
from armkit.trajectory import knot_jumps, patterns, spline, splines

# Paper 4, Table 1 (SPEC.md): knots (s) and joints 2, 3, 5 of tool_changer_6dof (deg).
TABLE1_T = np.array([0.0, 2.0, 4.0, 5.0])
TABLE1_DEG = np.array([[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]])
TOL = 1e-9


def table1() -> tuple[armkit.Robot, np.ndarray]:
    robot = armkit.robot("tool_changer_6dof")
    q = np.zeros((4, robot.n))
    q[:, [1, 2, 4]] = TABLE1_DEG
    return robot, robot.q_to_si(q)


def sides(tr, r):
    """Derivative r at each break from the left (end of the piece before) and the right."""
    h = np.diff(tr.breaks)
    left = tr.piece_values(h[:, None], r)[:, 0]
    right = tr.piece_values(np.zeros((len(h), 1)), r)[:, 0]
    return left, right


def check_spline(tr, t, q, continuity, start, end):
    """Through the knots, continuous at interior knots, end values as given (dict r -> value);
    each to 1e-9 of the size of that derivative at the knots (1 + its largest magnitude)."""
    for r in range(continuity + 1):
        left, right = sides(tr, r)
        tol = TOL * (1.0 + max(np.abs(left).max(), np.abs(right).max()))
        if r == 0:
            np.testing.assert_allclose(right, q[:-1], atol=tol)
            np.testing.assert_allclose(left, q[1:], atol=tol)
        else:
            np.testing.assert_allclose(left[:-1], right[1:], atol=tol)
        if r in start:
            np.testing.assert_allclose(right[0], start[r], atol=tol)
        if r in end:
            np.testing.assert_allclose(left[-1], end[r], atol=tol)


@pytest.mark.parametrize("pattern", ["3-3-3", "4-5-5", "5-5-5"])
def test_table1_patterns_meet_their_conditions_exactly(pattern):
    robot, q = table1()
    tr = spline(TABLE1_T, q, pattern)
    np.testing.assert_allclose(tr.evaluate(TABLE1_T), q, atol=1e-12)   # through every knot
    assert tr.label == pattern and list(tr.knots) == list(TABLE1_T)
    ends = {1: 0.0} if pattern == "3-3-3" else {1: 0.0, 2: 0.0}
    check_spline(tr, TABLE1_T, q, 2, ends, ends)


def test_3_3_3_end_accelerations_step_and_are_not_zero():
    robot, q = table1()
    tr = spline(TABLE1_T, q, "3-3-3")
    jumps = knot_jumps(tr).jump                          # (4 knots, 4 derivatives, n)
    moving = [1, 2, 4]
    assert (np.abs(jumps[0, 2, moving]) > 0.05).all() and (np.abs(jumps[-1, 2, moving]) > 0.2).all()
    np.testing.assert_allclose(jumps[1:-1, 1:3], 0.0, atol=TOL)      # v, a continuous inside
    np.testing.assert_allclose(jumps[:, 1], 0.0, atol=TOL)           # starts and stops at rest
    # Held joints stay exactly where they are.
    np.testing.assert_allclose(tr.sample_uniform(50).q[:, [0, 3, 5]], 0.0, atol=1e-15)


def test_5_5_5_least_jerk_is_the_c4_quintic_spline():
    robot, q = table1()
    jumps = knot_jumps(spline(TABLE1_T, q, "5-5-5")).jump
    np.testing.assert_allclose(jumps[1:-1, 1:], 0.0, atol=1e-9)       # velocity ... jerk
    tr = spline(TABLE1_T, q, "5-5-5")
    h = np.diff(tr.breaks)
    snap_left = tr.piece_values(h[:, None], 4)[:-1, 0]
    snap_right = tr.piece_values(np.zeros((3, 1)), 4)[1:, 0]
    np.testing.assert_allclose(snap_left, snap_right, atol=1e-9)      # and snap


def test_4_5_5_least_jerk_conditions_at_the_via_points():
    """The quartic leaves one condition at the first via point: 6 [jerk] = h_1 [snap]."""
    robot, q = table1()
    tr = spline(TABLE1_T, q, "4-5-5")
    h = np.diff(tr.breaks)
    jerk_jump = sides(tr, 3)[1][1:] - sides(tr, 3)[0][:-1]
    snap_jump = sides(tr, 4)[1][1:] - sides(tr, 4)[0][:-1]
    np.testing.assert_allclose(jerk_jump[1], 0.0, atol=1e-9)
    np.testing.assert_allclose(snap_jump[1], 0.0, atol=1e-9)
    np.testing.assert_allclose(6 * jerk_jump[0], h[0] * snap_jump[0], atol=1e-9)
    assert np.abs(jerk_jump[0]).max() > 1e-3                       # really a jerk step


def test_least_jerk_quintics_equal_scipys_interpolating_quintic_spline():
    rng = np.random.default_rng(0)
    t = np.r_[0.0, np.cumsum(rng.uniform(0.3, 2.0, 7))]
    q = rng.normal(size=(8, 3))
    zero = np.zeros(3)
    reference = make_interp_spline(t, q, k=5, bc_type=([(1, zero), (2, zero)],
                                                       [(1, zero), (2, zero)]))
    ours = spline(t, q, 5)
    s = np.linspace(0, t[-1], 999)
    for r in range(4):
        np.testing.assert_allclose(ours.evaluate(s, r), reference(s, r), atol=1e-10 * 10**r)


def test_cubics_equal_scipys_clamped_cubic_spline():
    rng = np.random.default_rng(1)
    t = np.r_[0.0, np.cumsum(rng.uniform(0.1, 1.0, 100))]          # 100 via points
    q = rng.normal(size=(101, 6))
    ours, reference = spline(t, q, 3), CubicSpline(t, q, bc_type="clamped")
    s = np.linspace(0, t[-1], 5000)
    for r in range(3):
        np.testing.assert_allclose(ours.evaluate(s, r), reference(s, r), atol=1e-11 * 10**r)


@pytest.mark.parametrize("degrees, count", [(3, 6), ("4-5-5", 4), ([5, 7, 4, 6], 5)])
def test_dense_and_banded_solves_agree(degrees, count, monkeypatch):
    """Small systems are solved dense and large ones banded (`DENSE_UP_TO`): the same
    spline to rounding, whether its conditions fix it or leave it to the least jerk."""
    rng = np.random.default_rng(count)
    t = np.r_[0.0, np.cumsum(rng.uniform(0.3, 2.0, count - 1))]
    q = rng.normal(size=(count, 3))
    dense = spline(t, q, degrees)
    monkeypatch.setattr(splines, "DENSE_UP_TO", 0)
    banded = spline(t, q, degrees)
    np.testing.assert_allclose(dense.coefficients, banded.coefficients, rtol=0,
                               atol=1e-12 * np.abs(dense.coefficients).max())


def test_given_end_values_and_free_ends():
    rng = np.random.default_rng(2)
    t, q = np.array([0.0, 1.0, 2.5, 3.0]), rng.normal(size=(4, 2))
    tr = spline(t, q, [5, 5, 5], start_velocity=[0.5, -1.0], end_velocity=0.2,
                start_acceleration=1.0, end_acceleration=[0.0, 3.0])
    check_spline(tr, t, q, 2, {1: [0.5, -1.0], 2: 1.0}, {1: 0.2, 2: [0.0, 3.0]})
    natural = spline(t, q, 3, start_velocity=None, end_velocity=None, start_acceleration=0.0,
                     end_acceleration=0.0)
    np.testing.assert_allclose(natural.evaluate(t, 2)[[0, -1]], 0.0, atol=1e-9)
    reference = CubicSpline(t, q, bc_type="natural")
    np.testing.assert_allclose(natural.evaluate(np.linspace(0, 3, 50)),
                               reference(np.linspace(0, 3, 50)), atol=1e-12)


def test_patterns_by_label_in_order():
    robot, q = table1()
    trs = patterns(TABLE1_T, q, ["5-5-5", (3, 3, 3), 4])
    assert list(trs) == ["5-5-5", "3-3-3", "4-4-4"]


@pytest.mark.parametrize("kwargs, words", [
    ({"degrees": "3-3-3", "start_acceleration": 0.0},
     "pattern 3-3-3 has 12 coefficients per joint but 13 conditions"),
    ({"degrees": "3-3"}, "degrees: expected 3 segment degrees"),
    ({"degrees": "4-x-5"}, "expected a pattern such as 4-5-5"),
    ({"degrees": [3, 3, 0]}, "degrees: expected integers from 1 to 15"),
    ({"degrees": 1}, "pattern 1-1-1 has 6 coefficients"),
    ({"degrees": 3, "start_velocity": "fast"}, "start_velocity: expected a number"),
    ({"degrees": 3, "continuity": -1}, "continuity: expected an integer"),
])
def test_impossible_patterns_and_bad_input_say_why(kwargs, words):
    robot, q = table1()
    with pytest.raises(InputError, match=words):
        spline(TABLE1_T, q, **kwargs)


@pytest.mark.parametrize("times, points, words", [
    ([0, 1, 1, 2], np.zeros((4, 2)), "times: expected strictly increasing"),
    ([0, 1, 2], np.zeros((4, 2)), r"points: expected shape \(3, n\)"),
    ([0], np.zeros((1, 2)), "times: expected shape"),
    ([0, 1], [[0, np.nan], [1, 1]], "finite"),
])
def test_bad_knots(times, points, words):
    with pytest.raises(InputError, match=words):
        spline(times, points, 3)


@st.composite
def spline_cases(draw):
    m = draw(st.integers(1, 6))
    gaps = draw(st.lists(st.floats(0.05, 5.0), min_size=m, max_size=m))
    t = np.r_[draw(st.floats(-10, 10)), gaps].cumsum()
    seed = draw(st.integers(0, 2**32 - 1))
    q = np.random.default_rng(seed).uniform(-3, 3, (m + 1, 2))
    degrees = draw(st.lists(st.integers(3, 7), min_size=m, max_size=m))
    return t, q, degrees


@given(spline_cases())
def test_continuity_and_ends_hold_for_random_knots_values_and_degrees(case):
    t, q, degrees = case
    ends_free = sum(d + 1 for d in degrees) - 2 * len(degrees) - 2 * (len(degrees) - 1) - 2 < 2
    tr = spline(t, q, degrees)
    ends = {1: 0.0} if ends_free else {1: 0.0, 2: 0.0}
    check_spline(tr, t, q, 2, ends, ends)
