"""Planning for an arm with a mimic joint (a parallelogram-like wrist that turns back as the
elbow turns): the checker moves the mimic joint with its leader, against the independent
reference, and a planned path passes the dense check."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.planning import CollisionChecker, Scene, Sphere, default_geometry, plan
from tests.planning import reference

URDF = """<robot name="parallel">
  <link name="base"/><link name="upper"/><link name="fore"/><link name="hand"/><link name="tool"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" velocity="1"/></joint>
  <joint name="wrist" type="revolute"><parent link="fore"/><child link="hand"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" velocity="1"/>
    <mimic joint="elbow" multiplier="-1" offset="0.2"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="hand"/><child link="tool"/>
    <origin xyz="0.2 0 0"/></joint>
</robot>"""


@pytest.fixture(scope="module")
def checker(tmp_path_factory):
    path = tmp_path_factory.mktemp("mimic") / "parallel.urdf"
    path.write_text(URDF)
    robot = armkit.load_robot(path)
    scene = Scene([Sphere([0.45, 0.45, 0.0], 0.1)])
    return CollisionChecker(robot, scene, default_geometry(robot, 0.03), 0.005)


def test_the_displacement_bound_counts_the_mimic_joint(checker):
    # The shoulder carries every capsule: 0.4 + 0.3 + 0.2 m. The elbow moves the forearm
    # (0.3 + 0.2 m from its axis) and, through the mimic wrist, the hand (0.2 m) again.
    assert checker.robot.n == 2 and checker.robot.chain.n_joints == 3
    np.testing.assert_allclose(checker.weights, [0.9, 0.5 + 0.2], rtol=1e-12)


def test_clearance_matches_the_reference(checker):
    robot = checker.robot
    Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (100, robot.n))
    expected = [reference.free_distance(robot, checker.geometry, checker.scene, q) for q in Q]
    np.testing.assert_allclose(np.minimum(checker.clearance(Q), 1.0),
                               np.minimum(expected, 1.0), rtol=0, atol=1e-9)


@pytest.mark.parametrize("planner", ["rrtconnect", "rrt"])
def test_a_planned_path_passes_the_dense_check(checker, planner):
    start, goal = np.array([0.0, 0.3]), np.array([1.6, 0.3])
    assert checker.valid(start) and checker.valid(goal)
    assert not checker.edge_valid(start, goal)[0]          # the straight line hits the ball
    result = plan(checker, start, goal, planner=planner, seed=2, time_limit=np.inf)
    assert result.success, result.reason
    assert reference.dense_ok(checker, result.path)
