"""The built-in robots: FK against roboticstoolbox-python and against geometry derived by hand."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import roboticstoolbox as rtb

import armkit
from armkit.model import DHTable
from armkit.spatial import rotz, transform

from tests.helpers import random_q


def rtb_from_table(robot: armkit.Robot) -> rtb.DHRobot:
    """An rtb DHRobot built independently from the robot's DH table (SI)."""
    table: DHTable = robot.table
    links = []
    for row in table.rows:
        assert row.kind != "fixed", "fixed rows go into base/tool for rtb"
        if table.modified:
            cls = rtb.RevoluteMDH if row.kind == "revolute" else rtb.PrismaticMDH
        else:
            cls = rtb.RevoluteDH if row.kind == "revolute" else rtb.PrismaticDH
        if row.kind == "revolute":
            links.append(cls(a=row.a, alpha=row.alpha, d=row.d, offset=row.theta))
        else:
            links.append(cls(a=row.a, alpha=row.alpha, theta=row.theta, offset=row.d))
    return rtb.DHRobot(links, base=table.T_base, tool=table.T_tool)


def references() -> dict[str, rtb.DHRobot]:
    ur5 = rtb.models.DH.UR5()
    # rtb's UR5 has d1 = 0.089459; Universal Robots publish 0.089159 (our file). All else agrees.
    assert ur5.links[0].d == pytest.approx(0.089459)
    ur5.links[0].d = 0.089159
    panda = rtb.models.DH.Panda()
    # rtb puts the Franka Hand's TCP 0.103 m past the flange; Franka documents 0.1034 m.
    panda.tool = transform(rotz(-np.pi / 4), [0.0, 0.0, 0.1034])
    return {"ur5": ur5, "puma560": rtb.models.DH.Puma560(), "stanford": rtb.models.DH.Stanford(),
            "panda": panda}


@pytest.mark.parametrize("name", ["ur5", "puma560", "stanford", "panda"])
def test_fk_matches_roboticstoolbox_models(name):
    robot, ref = armkit.robot(name), references()[name]
    Q = random_q(robot, 200, seed=1)
    expected = np.array([ref.fkine(q).A for q in Q])
    np.testing.assert_allclose(armkit.fk(robot, Q), expected, rtol=0, atol=1e-12)
    frames = np.array([[T.A for T in ref.fkine_all(q)] for q in Q[:20]])
    np.testing.assert_allclose(armkit.fk_frames(robot, Q[:20])[:, :-1], frames[:, :-1], atol=1e-12)


@pytest.mark.parametrize("name", ["modular_4dof", "inspection_6dof"])
def test_fk_of_paper_dh_robots_matches_roboticstoolbox(name):
    robot = armkit.robot(name)
    ref = rtb_from_table(robot)
    Q = random_q(robot, 200, seed=2)
    np.testing.assert_allclose(armkit.fk(robot, Q), np.array([ref.fkine(q).A for q in Q]),
                               atol=1e-12)


def test_builtin_tables_match_the_spec():
    deg = np.pi / 180
    rows = armkit.robot("inspection_6dof").table.rows
    assert [r.alpha / deg for r in rows] == pytest.approx([-90, 0, 0, 90, -90, 0])
    assert [r.a for r in rows] == pytest.approx([0, 0.5, 0.5, 0, 0, 0])
    assert [r.d for r in rows] == pytest.approx([0.05] * 5 + [0.5])
    rows = armkit.robot("modular_4dof").table.rows
    np.testing.assert_allclose([(r.alpha / deg, r.a, r.d) for r in rows],
                               [(-90, 0, 0.266), (0, 0.368, 0), (0, 0.291, 0), (90, 0.354, 0)])
    robot = armkit.robot("modular_4dof")
    assert robot.upper / deg == pytest.approx([90, 105, 120, 120])


def test_water_supply_by_hand():
    """Lift z = 525.5 + q1; planar arm 214 + 760 + 352.5 mm; yaw = q2 + q3 + q4."""
    robot = armkit.robot("water_supply")
    Q = random_q(robot, 100, seed=3)
    T = armkit.fk(robot, Q)
    q1, q2, q3, q4 = Q.T
    x = 0.214 + 0.760 * np.cos(q2) + 0.3525 * np.cos(q2 + q3)
    y = 0.760 * np.sin(q2) + 0.3525 * np.sin(q2 + q3)
    np.testing.assert_allclose(T[:, :3, 3], np.c_[x, y, 0.5255 + q1], atol=1e-12)
    np.testing.assert_allclose(T[:, :3, :3], rotz(q2 + q3 + q4), atol=1e-12)
    assert robot.lower == pytest.approx([0, *np.deg2rad([-120, -150, -180])])
    assert robot.upper == pytest.approx([0.6, *np.deg2rad([120, 150, 180])])


def test_tool_changer_by_hand():
    robot = armkit.robot("tool_changer_6dof")
    np.testing.assert_allclose(armkit.fk(robot, np.zeros(6)),
                               transform(p=[2.0, 0.0, 0.5]), atol=1e-15)       # home pose M
    d = 0.63                                                                   # telescope out
    np.testing.assert_allclose(armkit.fk(robot, [0, 0, 0, d, 0, 0])[:3, 3], [2.0 + d, 0, 0.5],
                               atol=1e-15)
    # Swing 90 deg: the arm points along +y.
    np.testing.assert_allclose(armkit.fk(robot, [np.pi / 2, 0, 0, 0, 0, 0])[:3, 3], [0, 2.0, 0.5],
                               atol=1e-15)
    # Pitch 1 by t about y through (0, 0, 0.5): the 2 m arm dips to (2 cos t, 0, 0.5 - 2 sin t).
    t = 0.4
    np.testing.assert_allclose(armkit.fk(robot, [0, t, 0, 0, 0, 0])[:3, 3],
                               [2 * np.cos(t), 0, 0.5 - 2 * np.sin(t)], atol=1e-15)
    # Pitch 2 folds the arm back about (1, 0, 0.5); telescope and pitch 3 ride along.
    T = armkit.fk(robot, [0, 0, -np.pi / 2, 0.2, 0, 0])
    np.testing.assert_allclose(T[:3, 3], [1.0, 0.0, 0.5 + 1.2], atol=1e-15)
    # The roll joint turns the tool about the arm without moving its origin.
    T = armkit.fk(robot, [0, 0, 0, 0, 0, 0.7])
    np.testing.assert_allclose(T[:3, 3], [2.0, 0.0, 0.5], atol=1e-15)
    np.testing.assert_allclose(T[:3, :3], armkit.spatial.rotx(0.7), atol=1e-15)


def test_every_builtin_loads_and_is_consistent(any_robot):
    r = any_robot
    assert r.n == len(r.joint_names) == r.lower.size == r.upper.size
    assert np.all(r.lower < r.upper)
    assert armkit.fk(r, random_q(r, 3)).shape == (3, 4, 4)


def test_a_changed_robot_is_a_new_robot():
    ur5 = armkit.robot("ur5")
    moved = dataclasses.replace(ur5, chain=dataclasses.replace(
        ur5.chain, T_base=transform(p=[0, 0, 1.0])))
    q = random_q(ur5, 1)[0]
    assert armkit.fk(moved, q)[2, 3] == pytest.approx(armkit.fk(ur5, q)[2, 3] + 1.0)
    with pytest.raises(ValueError):
        ur5.chain.lower[0] = 0.0                                 # arrays are read-only


def test_robot_exposes_its_limits():
    robot = armkit.robot("water_supply")
    for name in ("velocity_limits", "acceleration_limits"):
        np.testing.assert_array_equal(getattr(robot, name), getattr(robot.chain, name))
        assert getattr(robot, name).shape == (robot.n,)
    lower, upper = robot.sampling_limits
    np.testing.assert_array_equal(lower, robot.lower)
    np.testing.assert_array_equal(upper, robot.upper)


def test_no_module_is_hidden_by_a_function_of_its_name():
    import importlib
    import types

    for name in ("armkit.model.robot", "armkit.kinematics.jacobian", "armkit.kinematics.forward",
                 "armkit.sampled_workspace", "armkit.trajectory.splines",
                 "armkit.trajectory.retiming", "armkit.trajectory.profiles"):
        module = importlib.import_module(name)
        parent, _, leaf = name.rpartition(".")
        assert isinstance(getattr(importlib.import_module(parent), leaf), types.ModuleType), name
        assert getattr(importlib.import_module(parent), leaf) is module
    assert callable(armkit.robot) and callable(armkit.workspace) and callable(armkit.jacobian)
