"""Torque-limited time-optimal retiming: the torque limits held on the continuous result (dense
time sampling, between grid points too), the duration against toppra under the same
constraints, friction and payload counted, and a path no torque can follow refused."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest
import toppra
import toppra.algorithm
import toppra.constraint
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.dynamics import TorqueLimits, inverse_dynamics, torque_profile, with_payload
from armkit.errors import InputError
from armkit.trajectory import retime, waypoint_path

logging.getLogger("toppra").setLevel(logging.ERROR)
EXCESS = 1e-6           # the largest relative excess allowed on dense sampling


def dense_ratio(robot, trajectory, limits, count=10_000):
    """Largest |torque| / limit over `count` uniform times (the issue's check)."""
    t = np.linspace(trajectory.start, trajectory.end, count)
    s = trajectory.sample(t)
    tau = inverse_dynamics(robot, s.q, s.qd, s.qdd)
    held = np.isfinite(limits)
    return np.max(np.abs(tau[:, held]) / limits[held])


def ur5_case(seed=0, count=6):
    robot = armkit.robot("ur5")
    waypoints = np.random.default_rng(seed).uniform(-2, 2, (count, 6))
    return robot, waypoints, np.array([60.0, 60.0, 25.0, 10.0, 10.0, 10.0])


def toppra_result(robot, path, waypoints, vmax, amax, tau_max, grid):
    """toppra (interpolation discretisation) under the same velocity, acceleration and torque
    limits, on its own spline through the same waypoints at the same path parameters."""
    spline = toppra.SplineInterpolator(path.knots, waypoints, bc_type="natural")

    def inv_dyn(q, qd, qdd):
        return inverse_dynamics(robot, q, qd, qdd)

    interpolation = toppra.constraint.DiscretizationType.Interpolation
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
        toppra.constraint.JointAccelerationConstraint(np.c_[-amax, amax], interpolation),
        toppra.constraint.JointTorqueConstraint(inv_dyn, np.c_[-tau_max, tau_max],
                                                np.zeros(robot.n), interpolation)]
    algorithm = toppra.algorithm.TOPPRA(constraints, spline, gridpoints=np.linspace(
        0, path.end, grid + 1), parametrizer="ParametrizeConstAccel")
    return algorithm.compute_trajectory()


def test_torque_limits_hold_between_grid_points():
    robot, waypoints, tau_max = ur5_case()
    result = retime(waypoints, robot.velocity_limits, 20.0,
                    torque=TorqueLimits(robot, tau_max))
    assert result.success, result.reason
    assert dense_ratio(robot, result.trajectory, tau_max) <= 1 + EXCESS
    assert dense_ratio(robot, result.trajectory, tau_max, 200_001) <= 1 + EXCESS
    # The limits bind: without them the same path needs more torque.
    free = retime(waypoints, robot.velocity_limits, 20.0)
    assert dense_ratio(robot, free.trajectory, tau_max) > 1.1
    assert result.duration > free.duration


def test_duration_against_toppra():
    """Within 1 % of toppra with the same constraints on a fine grid, where toppra meets the
    torque limit only at its grid points (between them it overshoots)."""
    robot, waypoints, tau_max = ur5_case(count=6)
    vmax, amax = robot.velocity_limits, np.full(6, 20.0)
    path = waypoint_path(waypoints)
    ours = retime(path, vmax, amax, torque=TorqueLimits(robot, tau_max))
    theirs = toppra_result(robot, path, waypoints, vmax, amax, tau_max, 2000)
    assert ours.duration == pytest.approx(theirs.duration, rel=1e-2)
    assert ours.duration >= theirs.duration * (1 - 1e-3)
    assert dense_ratio(robot, ours.trajectory, tau_max) <= 1 + EXCESS


@pytest.mark.parametrize("name", ["water_supply", "inspection_6dof", "tool_changer_6dof",
                                  "modular_4dof", "puma560"])
def test_builtin_robots_hold_their_torque_limits(name):
    """Each built-in robot with inertias along a path through random waypoints, its own
    velocity limits, generous accelerations and torque limits at 60 % of what the fastest
    motion without them needs."""
    robot = armkit.robot(name)
    rng = np.random.default_rng(len(name))
    waypoints = rng.uniform(robot.lower * 0.8 + robot.upper * 0.2,
                            robot.lower * 0.2 + robot.upper * 0.8, (5, robot.n))
    vmax = np.where(np.isfinite(robot.velocity_limits), robot.velocity_limits, 3.0)
    amax = np.where(np.isfinite(robot.acceleration_limits), robot.acceleration_limits * 4, 20.0)
    tau_max = limits_that_bind(robot, waypoints, vmax, amax, 0.6)
    result = retime(waypoints, vmax, amax, torque=TorqueLimits(robot, tau_max))
    assert result.success, result.reason
    assert dense_ratio(robot, result.trajectory, tau_max) <= 1 + EXCESS
    assert result.duration > retime(waypoints, vmax, amax).duration


def limits_that_bind(robot, waypoints, vmax, amax, share):
    """Torque limits at `share` of what the fastest motion without them needs, and above
    what holding the arm still along the path needs."""
    free = retime(waypoints, vmax, amax).trajectory
    need = torque_profile(robot, free, limits=np.inf).peak
    hold = torque_profile(robot, free.scaled(50.0), limits=np.inf).peak
    return np.maximum(share * need, 1.3 * hold + 0.5)


def test_friction_and_payload_count():
    robot, waypoints, _ = ur5_case(seed=3)
    rough = dataclasses.replace(robot, inertia=dataclasses.replace(
        robot.inertia, viscous=[3.0, 3.0, 2.0, 0.5, 0.5, 0.5], coulomb=[2.0, 2.0, 1.0, 0.3,
                                                                        0.3, 0.3]))
    loaded = with_payload(rough, 3.0, [0, 0, 0.1])
    vmax, amax = robot.velocity_limits, np.full(6, 20.0)
    tau_max = limits_that_bind(loaded, waypoints, vmax, amax, 0.6)
    result = retime(waypoints, vmax, amax, torque=TorqueLimits(loaded, tau_max))
    assert result.success, result.reason
    assert dense_ratio(loaded, result.trajectory, tau_max) <= 1 + EXCESS
    plain = retime(waypoints, vmax, amax, torque=TorqueLimits(robot, tau_max))
    assert result.duration > plain.duration


def test_loose_torque_limits_change_nothing():
    robot, waypoints, _ = ur5_case(seed=1)
    free = retime(waypoints, robot.velocity_limits, 5.0)
    loose = retime(waypoints, robot.velocity_limits, 5.0, torque=TorqueLimits(robot, 1e6))
    assert loose.duration == pytest.approx(free.duration, rel=1e-12)


def test_a_path_the_motors_cannot_hold_is_a_result():
    """A torque limit below what holds the arm against gravity: no timing follows the path,
    and the result says so (no exception)."""
    robot, waypoints, _ = ur5_case(seed=2)
    result = retime(waypoints, robot.velocity_limits, 20.0,
                    torque=TorqueLimits(robot, [150, 5, 150, 28, 28, 28]))
    assert not result.success
    assert result.reason == "exceeds the limits"
    assert 0 <= result.stop <= waypoint_path(waypoints).end


def test_bad_torque_limits_are_named():
    robot = armkit.robot("ur5")
    with pytest.raises(InputError, match="limits: expected 6 positive torque limits"):
        TorqueLimits(robot, [1, 2, 3])
    with pytest.raises(InputError, match="limits: expected 6 positive torque limits"):
        TorqueLimits(robot, [10, 10, -1, 10, 10, 10])
    with pytest.raises(InputError, match="expected inertial parameters"):
        TorqueLimits(armkit.robot("stanford"))


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31), st.integers(3, 10), st.floats(0.3, 0.9))
def test_torque_limits_hold_for_random_paths(seed, count, share):
    """Random paths and torque limits at a random share of the unconstrained need."""
    robot = armkit.robot("ur5")
    waypoints = np.random.default_rng(seed).uniform(-2.5, 2.5, (count, 6))
    vmax, amax = robot.velocity_limits, np.full(6, 15.0)
    tau_max = limits_that_bind(robot, waypoints, vmax, amax, share)
    result = retime(waypoints, vmax, amax, torque=TorqueLimits(robot, tau_max))
    assert result.success, result.reason
    assert dense_ratio(robot, result.trajectory, tau_max) <= 1 + EXCESS


def test_torque_profile_finds_the_peaks():
    robot = armkit.robot("ur5")
    move = armkit.quintic(np.zeros(6), np.deg2rad([90, -90, 90, 0, 0, 0]), 1.5)
    profile = torque_profile(robot, move, samples=2001)
    s = move.sample(profile.t)
    np.testing.assert_allclose(profile.torque, inverse_dynamics(robot, s.q, s.qd, s.qdd))
    assert np.array_equal(profile.peak, np.abs(profile.torque).max(axis=0))
    assert profile.within and (profile.ratio <= 1).all()
    tight = torque_profile(robot, move, limits=profile.peak * 0.9, samples=2001)
    assert not tight.within
    np.testing.assert_allclose(tight.ratio[profile.peak > 0], 1 / 0.9)
    assert tight.to_dict()["within"] is False
    with pytest.raises(InputError, match="trajectory: expected 6 joints"):
        torque_profile(robot, armkit.quintic(np.zeros(3), np.ones(3), 1.0))
