"""Inverse and forward dynamics, mass and Coriolis matrices, gravity torques: armkit against
Pinocchio (an independent reference) on real URDFs and on the built-in DH and screw robots,
to 1e-10 relative, at random configurations, rates and accelerations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import armkit
from armkit.dynamics import (coriolis, coriolis_matrix, forward_dynamics, gravity_torques,
                             inverse_dynamics, mass_matrix, with_payload)
from tests.dynamics.reference import from_table, from_urdf, robot_file

# (file, tip): the arms the issue names, then other public arms; mimic chains last.
URDFS = [
    ("ur_description/urdf/ur3_robot.urdf", "tool0"),
    ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    ("ur_description/urdf/ur10_robot.urdf", "tool0"),
    ("panda_description/urdf/panda.urdf", "panda_hand"),
    ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    ("talos_data/robots/talos_left_arm.urdf", "arm_left_7_link"),
    ("talos_data/robots/talos_reduced.urdf", "arm_left_7_link"),      # torso 2 + arm 7
    ("xarm_description/urdf/xarm7.urdf", "link_eef"),
    ("z1_description/urdf/z1.urdf", "gripperMover"),
    ("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
    ("baxter_description/urdf/baxter.urdf", "left_gripper"),
    ("tiago_description/robots/tiago.urdf", "arm_tool_link"),         # torso lift + arm 7
    ("panda_description/urdf/panda.urdf", "panda_rightfinger"),       # mimics finger 1
]
URDF_IDS = [f"{f.split('/')[-1]}-{tip}" for f, tip in URDFS]

DYNAMIC_BUILTINS = [name for name in armkit.robots() if armkit.robot(name).inertia is not None]


def frictionless(robot: armkit.Robot) -> armkit.Robot:
    """The robot without joint friction (Pinocchio's algorithms have none)."""
    return dataclasses.replace(robot, inertia=dataclasses.replace(
        robot.inertia, viscous=None, coulomb=None))


def samples(robot: armkit.Robot, count: int, seed: int):
    rng = np.random.default_rng(seed)
    lower, upper = robot.chain.sampling_limits
    q = rng.uniform(lower, upper, (count, robot.n))
    return q, rng.uniform(-2, 2, (count, robot.n)), rng.uniform(-5, 5, (count, robot.n))


def relative(a, b):
    """|a - b| over the size of b, per sample (the last one or two axes)."""
    axes = tuple(range(1, np.ndim(b)))
    return np.abs(a - b).max(axis=axes) / np.maximum(np.abs(b).max(axis=axes), 1e-300)


def compare(robot: armkit.Robot, reference, seed: int) -> None:
    q, qd, qdd = samples(robot, 25, seed)
    tau = inverse_dynamics(robot, q, qd, qdd)
    expected = np.array([reference.rnea(*x) for x in zip(q, qd, qdd)])
    assert relative(tau, expected).max() < 1e-10
    M = mass_matrix(robot, q)
    assert relative(M, np.array([reference.mass(x) for x in q])).max() < 1e-10
    C = coriolis_matrix(robot, q, qd)
    assert relative(C, np.array([reference.coriolis(*x) for x in zip(q, qd)])).max() < 1e-10
    g = gravity_torques(robot, q)
    assert relative(g, np.array([reference.gravity(x) for x in q])).max() < 1e-10
    cqd = coriolis(robot, q, qd)
    assert relative(cqd, expected - np.array([reference.rnea(a, np.zeros_like(a), c) for a, c
                                              in zip(q, qdd)])).max() < 1e-10
    qdd_found = forward_dynamics(robot, q, qd, expected)
    assert relative(qdd_found, qdd).max() < 1e-10
    aba = np.array([reference.aba(*x) for x in zip(q, qd, tau)])
    assert relative(forward_dynamics(robot, q, qd, tau), aba).max() < 1e-10


@pytest.mark.parametrize("suffix, tip", URDFS, ids=URDF_IDS)
def test_real_urdf_matches_pinocchio(suffix, tip):
    robot = frictionless(armkit.load_robot(robot_file(suffix), tip=tip))
    assert robot.inertia is not None
    compare(robot, from_urdf(robot), seed=len(suffix))


@pytest.mark.parametrize("name", DYNAMIC_BUILTINS)
def test_builtin_robot_matches_pinocchio(name):
    robot = armkit.robot(name)
    compare(frictionless(robot), from_table(frictionless(robot)), seed=len(name))


@pytest.mark.parametrize("name", ["water_supply", "tool_changer_6dof", "ur5"])
def test_payload_matches_pinocchio(name):
    robot = with_payload(armkit.robot(name), 3.5, [0.02, -0.01, 0.08],
                         np.diag([0.01, 0.02, 0.015]))
    compare(robot, from_table(robot), seed=5)


def test_armature_matches_pinocchio():
    """The Puma's motor inertias (armature) against Pinocchio's armature (added to M's
    diagonal and to RNEA's torques)."""
    robot = armkit.robot("puma560")
    assert np.any(robot.inertia.armature > 0)
    reference = from_table(robot)
    assert np.array_equal(reference.model.armature, robot.inertia.armature)
    q, qd, qdd = samples(robot, 10, 2)
    M = mass_matrix(robot, q)
    assert relative(M, np.array([reference.mass(x) for x in q])).max() < 1e-10
    tau = inverse_dynamics(robot, q, qd, qdd)
    expected = np.array([reference.rnea(*x) for x in zip(q, qd, qdd)])
    assert relative(tau, expected).max() < 1e-10


def test_puma_matches_roboticstoolbox():
    """A second reference: roboticstoolbox-python's recursive Newton-Euler (in C) on its own
    Puma 560 model (armature Jm G^2 included, friction removed)."""
    import roboticstoolbox as rtb

    robot = armkit.robot("puma560")
    puma = rtb.models.DH.Puma560().nofriction(coulomb=True, viscous=True)
    q, qd, qdd = samples(robot, 10, 4)
    for x in zip(q, qd, qdd):
        expected = puma.rne(*x, gravity=[0, 0, -9.80665])
        # The armature in the robot file is Jm G^2 to 6 significant digits.
        np.testing.assert_allclose(inverse_dynamics(robot, *x), expected, rtol=1e-5,
                                   atol=1e-5 * np.abs(expected).max())
