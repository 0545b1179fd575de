"""Jacobians against central finite differences of FK (hypothesis, q within limits), Jdot
against differences of J, tool acceleration against second differences, singularity measures by
hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.model import DHRow, DHTable, Limits, Robot, chain_from_dh
from armkit.spatial import log_so3, matrix_to_rpy
from tests.helpers import random_q

ROBOTS = {name: armkit.robot(name) for name in armkit.robots()}
seeds = st.integers(0, 2**32 - 1)


def numeric_jacobian(robot, q, h=1e-6):
    """Central differences: linear rows from the tool position, angular from log(dR R^T)."""
    J = np.zeros((6, robot.n))
    for i in range(robot.n):
        dq = np.zeros(robot.n)
        dq[i] = h
        Tp, Tm = armkit.fk(robot, q + dq), armkit.fk(robot, q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, i] = log_so3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J


@given(name=st.sampled_from(sorted(ROBOTS)), seed=seeds)
def test_jacobian_matches_finite_differences(name, seed):
    robot = ROBOTS[name]
    q = random_q(robot, 1, seed)[0]
    J = armkit.jacobian(robot, q)
    np.testing.assert_allclose(J, numeric_jacobian(robot, q), atol=1e-8)
    R = armkit.fk(robot, q)[:3, :3]
    Jt = armkit.jacobian(robot, q, frame="tool")
    np.testing.assert_allclose(Jt[:3], R.T @ J[:3], atol=1e-14)
    np.testing.assert_allclose(Jt[3:], R.T @ J[3:], atol=1e-14)


@given(name=st.sampled_from(sorted(ROBOTS)), seed=seeds)
def test_jacobian_dot_matches_differences_of_jacobian(name, seed):
    robot = ROBOTS[name]
    q = random_q(robot, 1, seed)[0]
    qd = np.random.default_rng(seed).normal(size=robot.n)
    h = 1e-6
    expected = (armkit.jacobian(robot, q + h * qd) - armkit.jacobian(robot, q - h * qd)) / (2 * h)
    np.testing.assert_allclose(armkit.jacobian_dot(robot, q, qd), expected, atol=1e-7)


@given(name=st.sampled_from(sorted(ROBOTS)), seed=seeds)
def test_analytic_jacobian_matches_differences_of_rpy(name, seed):
    robot = ROBOTS[name]
    q = random_q(robot, 1, seed)[0]
    rpy = matrix_to_rpy(armkit.fk(robot, q)[:3, :3])
    if abs(np.cos(rpy[1])) < 1e-2:
        return                                   # near gimbal lock the rates blow up
    h = 1e-7
    Ja = armkit.jacobian_analytic(robot, q)
    for i in range(robot.n):
        dq = np.zeros(robot.n)
        dq[i] = h
        Tp, Tm = armkit.fk(robot, q + dq), armkit.fk(robot, q - dq)
        drpy = (matrix_to_rpy(Tp[:3, :3]) - matrix_to_rpy(Tm[:3, :3]) + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(Ja[3:, i], drpy / (2 * h), atol=2e-5)
    np.testing.assert_array_equal(Ja[:3], armkit.jacobian(robot, q)[:3])


def test_analytic_jacobian_is_nan_at_gimbal_lock():
    # The tool changer's pitch joints add up: pitch3 = 90 deg points the tool straight down.
    robot = ROBOTS["tool_changer_6dof"]
    Ja = armkit.jacobian_analytic(robot, [0, 0, 0, 0, np.pi / 2, 0])
    assert np.isnan(Ja[3:]).all() and np.isfinite(Ja[:3]).all()


@given(name=st.sampled_from(sorted(ROBOTS)), seed=seeds)
def test_tool_acceleration_matches_second_differences(name, seed):
    robot = ROBOTS[name]
    rng = np.random.default_rng(seed)
    q0 = random_q(robot, 1, seed)[0]
    qd, qdd = rng.normal(size=robot.n), rng.normal(size=robot.n)
    path = lambda t: q0 + qd * t + 0.5 * qdd * t**2          # noqa: E731
    h = 1e-4
    p = [armkit.fk(robot, path(t))[:3, 3] for t in (-h, 0, h)]
    a = armkit.tool_acceleration(robot, q0, qd, qdd)
    np.testing.assert_allclose(a[:3], (p[2] - 2 * p[1] + p[0]) / h**2, atol=1e-5)
    w = [armkit.tool_velocity(robot, path(t), qd + qdd * t)[3:] for t in (-h, h)]
    np.testing.assert_allclose(a[3:], (w[1] - w[0]) / (2 * h), atol=1e-6)


@pytest.mark.parametrize("lead", [(), (5,), (2, 3)])
def test_leading_shapes(lead):
    robot = ROBOTS["stanford"]
    Q = random_q(robot, lead or 1)
    Q = Q[0] if not lead else Q
    qd = np.ones(robot.n)
    for f in (lambda q: armkit.jacobian(robot, q), lambda q: armkit.jacobian_dot(robot, q, qd),
              lambda q: armkit.jacobian_analytic(robot, q)):
        assert f(Q).shape == lead + (6, robot.n)
        np.testing.assert_allclose(f(Q).reshape(-1, 6, robot.n)[-1],
                                   f(Q.reshape(-1, robot.n)[-1]), atol=1e-15)
    assert armkit.manipulability(robot, Q).shape == lead
    assert armkit.tool_acceleration(robot, Q, qd, qd).shape == lead + (6,)


def planar_2r(l1=1.0, l2=0.5) -> Robot:
    rows = tuple(DHRow("revolute", 0.0, a, 0.0, 0.0, limits=Limits(-np.pi, np.pi))
                 for a in (l1, l2))
    return Robot("2r", chain_from_dh(DHTable(rows)))


def test_manipulability_of_a_planar_2r_by_hand():
    robot, q2 = planar_2r(), np.linspace(-3, 3, 13)
    Q = np.c_[np.full_like(q2, 0.4), q2]
    xy = [True, True, False, False, False, False]
    np.testing.assert_allclose(armkit.manipulability(robot, Q, xy), 1.0 * 0.5 * np.abs(np.sin(q2)),
                               atol=1e-15)
    assert armkit.min_singular_value(robot, [0.4, 0.0], xy) < 1e-15
    assert armkit.condition_number(robot, [0.4, 0.0], xy) > 1e15
    # Over the rows x, y, rz the planar arm has full rank except when stretched.
    assert armkit.manipulability(robot, [0.4, 1.0], [1, 1, 0, 0, 0, 1]) > 0.1


def test_stretched_water_supply_arm_is_singular():
    robot = ROBOTS["water_supply"]
    task = [True, True, True, False, False, True]
    assert armkit.manipulability(robot, [0.1, 0.2, 0.0, 0.3], task) < 1e-12
    assert armkit.manipulability(robot, [0.1, 0.2, 0.8, 0.3], task) > 0.1


def test_bad_arguments():
    robot = ROBOTS["ur5"]
    with pytest.raises(InputError, match="frame: expected 'base' or 'tool', found 'world'"):
        armkit.jacobian(robot, np.zeros(6), frame="world")
    with pytest.raises(InputError, match="axes: expected 'all', 'trans', 'rot'"):
        armkit.manipulability(robot, np.zeros(6), axes="xyz")
    with pytest.raises(InputError, match="axes: expected 6 booleans"):
        armkit.manipulability(robot, np.zeros(6), axes=[True, False])
    with pytest.raises(InputError, match="qd: expected last axis 6"):
        armkit.jacobian_dot(robot, np.zeros(6), np.zeros(5))


def test_large_batches_stream_block_by_block_to_the_same_values(monkeypatch):
    """Results computed block by block (bounded memory) equal those of one pass."""
    from armkit.kinematics import jacobian as module

    robot = armkit.robot("ur5")
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.lower, robot.upper, (5, 7, 6))
    qd, qdd = rng.normal(size=(2, 5, 7, 6))
    calls = {name: getattr(armkit, name) for name in (
        "manipulability", "singular_values", "min_singular_value", "condition_number",
        "jacobian_analytic")}
    whole = {name: f(robot, q) for name, f in calls.items()}
    whole["tool"] = armkit.jacobian(robot, q, frame="tool")
    whole["Jdot"] = armkit.jacobian_dot(robot, q, qd)
    whole["velocity"] = armkit.tool_velocity(robot, q, qd)
    whole["acceleration"] = armkit.tool_acceleration(robot, q, qd, qdd)
    monkeypatch.setattr(module, "STREAM", 4)            # 35 configurations: 9 blocks
    blocks = {name: f(robot, q) for name, f in calls.items()}
    blocks["tool"] = armkit.jacobian(robot, q, frame="tool")
    blocks["Jdot"] = armkit.jacobian_dot(robot, q, qd)
    blocks["velocity"] = armkit.tool_velocity(robot, q, qd)
    blocks["acceleration"] = armkit.tool_acceleration(robot, q, qd, qdd)
    for name, value in whole.items():
        assert blocks[name].shape == value.shape, name
        np.testing.assert_allclose(blocks[name], value, rtol=0, atol=1e-12, err_msg=name)


def test_rate_arrays_broadcast_against_q():
    robot = armkit.robot("ur5")
    q = np.random.default_rng(4).uniform(robot.lower, robot.upper, (3, 6))
    v = armkit.tool_velocity(robot, q, np.ones(6))
    assert v.shape == (3, 6)
    np.testing.assert_allclose(v[1], armkit.jacobian(robot, q[1]) @ np.ones(6), atol=1e-15)
