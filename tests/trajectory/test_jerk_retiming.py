"""Jerk-limited retiming: limits kept at 10 kHz (not only where the retimer looked), the path
followed through its waypoints, rest to rest without an acceleration step; the duration against
ruckig's time-optimal jerk-limited motion on straight lines, and against the
acceleration-limited optimum (armkit.retime) on the demo's planned path."""

from __future__ import annotations

import numpy as np
import pytest
import ruckig
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.trajectory import Trajectory, retime, retime_jerk, waypoint_path
from armkit.trajectory.bounds import peaks

RATE = 10_000                # Hz: the samples the limits are checked on
RTOL = 1e-7                  # on the 10 kHz samples: the retimer bounds every instant

# The path the demo's planner finds around the post (water_supply: lift mm, swings deg).
DEMO_PATH = [[50.0, 0.0, 30.0, -30.0], [88.603, -1.549, 37.011, -31.115],
             [127.205, -3.098, 44.023, -32.23], [165.808, -4.647, 51.034, -33.346],
             [203.755, -6.142, 58.025, -34.543], [217.904, -5.689, 64.293, -38.732],
             [232.053, -5.236, 70.561, -42.921], [246.202, -4.784, 76.829, -47.109],
             [260.351, -4.331, 83.097, -51.298], [274.5, -3.878, 89.365, -55.486]]


def check(tr: Trajectory, path: Trajectory, V, A, J) -> None:
    """Limits at 10 kHz; no acceleration step between samples; waypoints passed; rest (zero
    velocity and acceleration) at both ends."""
    t = np.arange(0.0, tr.end, 1.0 / RATE)
    s = tr.sample(np.r_[t, tr.end])
    assert (np.abs(s.qd) <= V * (1 + RTOL)).all()
    assert (np.abs(s.qdd) <= A * (1 + RTOL)).all()
    assert (np.abs(s.qddd) <= J * (1 + RTOL)).all()
    step = np.abs(np.diff(s.qdd, axis=0))                      # at most J per sample interval
    assert (step <= J / RATE * (1 + 1e-6) + 1e-12).all()
    np.testing.assert_allclose(tr.evaluate(tr.knots), path.evaluate(path.knots), atol=1e-9)
    ends = tr.sample([0.0, tr.end])
    np.testing.assert_allclose(ends.qd, 0.0, atol=1e-9)
    np.testing.assert_allclose(ends.qdd, 0.0, atol=1e-6 * A.max())


def ruckig_duration(q0, q1, V, A, J) -> float:
    """ruckig's time-optimal jerk-limited motion from rest to rest on the straight line."""
    n = len(q0)
    inp = ruckig.InputParameter(n)
    inp.current_position, inp.target_position = list(q0), list(q1)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(V), list(A), list(J)
    inp.synchronization = ruckig.Synchronization.Phase          # a straight line in q
    out = ruckig.Trajectory(n)
    assert ruckig.Ruckig(n).calculate(inp, out) == ruckig.Result.Working
    return out.duration


def test_the_demo_path_within_every_limit_and_near_the_acceleration_optimum():
    robot = armkit.robot("water_supply")
    path = waypoint_path(robot.q_to_si(DEMO_PATH))
    V, A, J = robot.velocity_limits, robot.acceleration_limits, robot.jerk_limits
    smooth = retime_jerk(path, V, A, J)
    assert smooth.success, smooth.reason
    check(smooth.trajectory, path, V, A, J)
    optimum = retime(path, V, A)
    assert optimum.duration <= smooth.duration <= 1.2 * optimum.duration


@pytest.mark.parametrize("seed", range(3))
def test_a_straight_line_as_fast_as_ruckig_within_two_percent(seed):
    robot = armkit.robot("inspection_6dof")
    V, A, J = robot.velocity_limits, robot.acceleration_limits, robot.jerk_limits
    rng = np.random.default_rng(seed)
    q0, q1 = rng.uniform(robot.lower, robot.upper, (2, robot.n)) * 0.5
    path = waypoint_path([q0, q1])
    smooth = retime_jerk(path, V, A, J)
    assert smooth.success, smooth.reason
    check(smooth.trajectory, path, V, A, J)
    best = ruckig_duration(q0, q1, V, A, J)
    assert best * (1 - 1e-6) <= smooth.duration <= 1.02 * best


def test_the_exact_peaks_bound_every_sample_and_are_reached():
    rng = np.random.default_rng(4)
    tr = Trajectory(np.cumsum(np.r_[0.0, rng.uniform(0.1, 1.0, 6)]), rng.normal(size=(6, 8, 3)))
    # Every piece sampled densely up to and including its end (the left limit at a break).
    tau = np.diff(tr.breaks)[:, None] * np.linspace(0.0, 1.0, 100_001)
    for r in (1, 2, 3):
        dense = np.abs(tr.piece_values(tau, r)).max(axis=(0, 1))
        exact = peaks(tr, r)
        assert (dense <= exact * (1 + 1e-12)).all()
        np.testing.assert_allclose(exact, dense, rtol=1e-8)


def _random_path_case(data) -> tuple:
    robot = armkit.robot(data.draw(st.sampled_from(["inspection_6dof", "water_supply",
                                                    "tool_changer_6dof"])))
    k = data.draw(st.integers(2, 6))
    seed = data.draw(st.integers(0, 2**32 - 1))
    q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (k, robot.n)) * 0.6
    return robot, waypoint_path(q)


def _holds(robot, path) -> None:
    V, A, J = robot.velocity_limits, robot.acceleration_limits, robot.jerk_limits
    smooth = retime_jerk(path, V, A, J, grid=150)
    assert smooth.success, smooth.reason
    check(smooth.trajectory, path, V, A, J)


@settings(max_examples=4, deadline=None)
@given(st.data())
def test_limits_hold_on_random_paths(data):
    _holds(*_random_path_case(data))


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.data())
def test_limits_hold_on_many_random_paths(data):
    _holds(*_random_path_case(data))


@pytest.mark.parametrize("kwargs, words", [
    ({"jmax": 0.0}, "jmax: expected positive limits"),
    ({"jmax": np.inf}, "expected finite limits"),
    ({"grid": 1}, "grid: expected 2 to 100000"),
])
def test_bad_limits_are_input_errors(kwargs, words):
    robot = armkit.robot("water_supply")
    args = {"vmax": robot.velocity_limits, "amax": robot.acceleration_limits,
            "jmax": robot.jerk_limits, **kwargs}
    with pytest.raises(InputError, match=words):
        retime_jerk(robot.q_to_si(DEMO_PATH), **args)
