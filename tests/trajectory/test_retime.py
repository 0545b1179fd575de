"""Retiming (TOPP-RA): duration against toppra for the same path and limits, limits kept on a
dense sample, the path followed through its waypoints, from rest to rest."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import toppra
import toppra.algorithm
import toppra.constraint
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.trajectory import Trajectory, retime, spline, waypoint_path

logging.getLogger("toppra").setLevel(logging.ERROR)
DENSE_RTOL = 1e-6       # limits on a dense sample; the retimer checks 8 samples per interval


def toppra_duration(spline_path, s, vmax, amax) -> float:
    constraints = [toppra.constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
                   toppra.constraint.JointAccelerationConstraint(np.c_[-amax, amax])]
    algorithm = toppra.algorithm.TOPPRA(constraints, spline_path, gridpoints=s,
                                        parametrizer="ParametrizeConstAccel")
    return algorithm.compute_trajectory().duration


def check_limits_and_path(tr, path, vmax, amax):
    s = tr.sample(np.linspace(0, tr.end, 200_001))
    assert (np.abs(s.qd) <= vmax * (1 + DENSE_RTOL)).all()
    assert (np.abs(s.qdd) <= amax * (1 + DENSE_RTOL)).all()
    ends = tr.sample([0.0, tr.end])
    np.testing.assert_allclose(ends.q, path.evaluate([path.start, path.end]), atol=1e-12)
    np.testing.assert_allclose(ends.qd, 0.0, atol=1e-12)
    np.testing.assert_allclose(tr.evaluate(tr.knots), path.evaluate(path.knots), atol=1e-9)


def test_waypoint_path_duration_against_toppra():
    rng = np.random.default_rng(0)
    waypoints = rng.uniform(-1.5, 1.5, (10, 6))
    vmax, amax = rng.uniform(0.5, 2.0, 6), rng.uniform(1.0, 4.0, 6)
    path = waypoint_path(waypoints)
    tr = retime(path, vmax, amax).trajectory
    # toppra's own spline through the same waypoints at the same path parameters.
    reference = toppra.SplineInterpolator(path.knots, waypoints, bc_type="natural")
    theirs = toppra_duration(reference, np.linspace(0, path.end, 3001), vmax, amax)
    assert tr.duration == pytest.approx(theirs, rel=1e-3)          # target: 1 %
    check_limits_and_path(tr, path, vmax, amax)
    np.testing.assert_allclose(tr.evaluate(tr.knots), waypoints, atol=1e-9)


def test_table1_spline_as_a_path_within_the_robots_limits():
    """The spline's ends stand still (q'(s) = 0), so the arm is at rest there whatever ds/dt
    is; retime leaves with ds/dt > 0, toppra (sd_start = 0) does not and is slower."""
    robot = armkit.robot("tool_changer_6dof")
    q = np.zeros((4, 6))
    q[:, [1, 2, 4]] = [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    q = robot.q_to_si(q)
    vmax, amax = robot.velocity_limits, robot.acceleration_limits
    path = spline([0, 2, 4, 5], q, "3-3-3")       # its ends are stationary: q'(s) = 0 there
    tr = retime(path, vmax, amax).trajectory
    reference = toppra.SplineInterpolator([0, 2, 4, 5], q, bc_type="clamped")
    theirs = toppra_duration(reference, np.linspace(0, 5, 1001), vmax, amax)
    assert theirs * 0.99 < tr.duration < theirs                       # target: within 1 %
    finer = retime(path, vmax, amax, grid=4000).trajectory
    assert tr.duration == pytest.approx(finer.duration, rel=1e-3)     # converged already
    check_limits_and_path(tr, path, vmax, amax)
    assert tr.label == "retimed" and tr.knots.shape == (4,)


def test_a_path_still_to_rounding_is_still():
    """An end velocity solved to 1e-17 instead of 0 is a path at rest there: the same
    timing, not a slower one from a velocity bound of 1e34."""
    robot = armkit.robot("tool_changer_6dof")
    q = np.zeros((4, 6))
    q[:, [1, 2, 4]] = [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    path = spline([0, 2, 4, 5], robot.q_to_si(q), "3-3-3")
    c = path.coefficients.copy()
    c[0, 1] = 0.0                                       # q'(0) = 0 exactly
    exact = Trajectory(path.breaks, c)
    noisy = c.copy()
    noisy[0, 1, 2] = 5.5e-17
    vmax, amax = robot.velocity_limits, robot.acceleration_limits
    assert retime(Trajectory(path.breaks, noisy), vmax, amax).duration == \
        retime(exact, vmax, amax).duration


def test_a_velocity_limit_alone_with_a_slow_acceleration_limit():
    path = waypoint_path([[0.0, 0.0], [1.0, 0.5], [2.0, 0.0]])
    fast = retime(path, vmax=[np.inf, np.inf], amax=10.0).trajectory
    slow = retime(path, vmax=0.2, amax=10.0).trajectory
    assert slow.duration > fast.duration
    check_limits_and_path(slow, path, np.full(2, 0.2), np.full(2, 10.0))


@pytest.mark.parametrize("kwargs, words", [
    ({"vmax": 1.0, "amax": np.inf}, "amax: expected finite"),
    ({"vmax": -1.0, "amax": 1.0}, "vmax: expected positive"),
    ({"vmax": 1.0, "amax": 1.0, "grid": 0}, "grid: expected a positive number"),
])
def test_bad_input(kwargs, words):
    with pytest.raises(InputError, match=words):
        retime([[0.0, 0.0], [1.0, 1.0]], **kwargs)


def test_repeated_waypoints_are_refused():
    with pytest.raises(InputError, match="distinct consecutive waypoints"):
        waypoint_path([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]])


@settings(max_examples=15)
@given(st.integers(0, 2**32 - 1), st.integers(2, 6))
def test_limits_hold_for_random_paths(seed, count):
    rng = np.random.default_rng(seed)
    path = waypoint_path(rng.uniform(-2, 2, (count, 3)))
    vmax, amax = rng.uniform(0.1, 3.0, 3), rng.uniform(0.1, 10.0, 3)
    check_limits_and_path(retime(path, vmax, amax, grid=300).trajectory, path, vmax, amax)


def test_a_followed_path_reports_success():
    result = retime([[0.0, 0.0], [1.0, 1.0]], vmax=1.0, amax=1.0)
    assert result.success and result.reason == "ok" and np.isnan(result.stop)
    assert result.duration == result.trajectory.duration > 0
