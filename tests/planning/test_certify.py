"""A timed motion certified against a scene (armkit.planning.certify), checked against an
independent dense sampling of the arm's clearance."""

from __future__ import annotations

import numpy as np

import armkit
from armkit.planning import Box, CollisionChecker, Scene
from armkit.planning.certify import certify
from armkit.trajectory import quintic


def _checker(scene):
    return CollisionChecker(armkit.robot("water_supply"), scene, resolution=0.005)


def test_a_motion_through_an_obstacle_is_not_certified_and_says_when():
    robot = armkit.robot("water_supply")
    q0, q1 = robot.q_to_si([100, -60, 30, 0]), robot.q_to_si([100, 60, -30, 0])
    motion = quintic(q0, q1, 3.0)
    T = np.eye(4)
    T[:3, 3] = armkit.fk(robot, motion.evaluate(1.5))[:3, 3]
    checker = _checker(Scene([Box([0.2, 0.2, 0.2], T, "in the way")]))
    found = certify(checker, motion)
    assert not found.success and found.reason.startswith("in collision at t = ")
    # Independently: the first colliding sample of a far denser sampling is no later.
    t = np.linspace(0.0, 3.0, 30001)
    first = t[np.argmax(checker.clearance(motion.evaluate(t)) <= 0)]
    assert first - 0.2 <= found.first_collision <= first


def test_a_clear_motion_is_certified_with_samples_dense_enough():
    robot = armkit.robot("water_supply")
    motion = quintic(robot.q_to_si([100, -60, 30, 0]), robot.q_to_si([300, 20, 60, 10]), 2.0)
    far = np.eye(4)
    far[:3, 3] = [3.0, 3.0, 0.0]
    checker = _checker(Scene([Box([0.2, 0.2, 0.2], far, "far")]))
    found = certify(checker, motion)
    assert found.success and found.reason == "ok"
    # No point of the arm moves more than half the resolution between two samples.
    q = motion.evaluate(np.linspace(0, 2.0, found.samples))
    step = np.abs(np.diff(q, axis=0)) @ checker.weights
    assert step.max() <= 0.5 * checker.resolution


def test_a_motion_at_rest_is_one_state():
    robot = armkit.robot("water_supply")
    q = robot.q_to_si([100, 0, 0, 0])
    found = certify(_checker(Scene()), quintic(q, q))
    assert found.success and found.samples == 1
