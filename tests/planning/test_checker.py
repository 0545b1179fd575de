"""The compiled checker against the plain-NumPy reference, the arm's geometry, and the
displacement bound that certification rests on."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.planning import (
    ArmGeometry,
    CollisionChecker,
    Scene,
    arm_geometry,
    default_geometry,
    displacement_weights,
)
from tests.helpers import random_q
from tests.planning import reference
from tests.planning.scenes import SHELF_GOAL, SHELF_START, random_scene, shelf


@pytest.mark.parametrize("name", ["inspection_6dof", "ur5", "water_supply", "tool_changer_6dof",
                                  "panda"])
def test_checker_matches_reference_on_random_states(name):
    robot = armkit.robot(name)
    geometry = default_geometry(robot, 0.05)
    scene = random_scene(3, count=8)
    checker = CollisionChecker(robot, scene, geometry, resolution=0.005)
    Q = random_q(robot, 12, seed=7)
    found = checker.clearance(Q)
    expected = np.array([reference.free_distance(robot, geometry, scene, q) for q in Q])
    np.testing.assert_allclose(found, expected, atol=1e-7)
    np.testing.assert_array_equal(checker.valid(Q), expected > 0)
    padded = CollisionChecker(robot, scene, geometry, padding=0.01)
    np.testing.assert_array_equal(padded.valid(Q), expected > 0.01)
    assert checker.clearance(Q[0]).shape == () and checker.valid(Q.reshape(3, 4, -1)).shape == (3, 4)


def test_shelf_straight_line_collides_over_28_percent():
    robot = armkit.robot("inspection_6dof")
    checker = CollisionChecker(robot, shelf(), default_geometry(robot, 0.04))
    s = np.linspace(0, 1, 2001)[:, None]
    f = checker.clearance(SHELF_START + s * (SHELF_GOAL - SHELF_START))
    assert np.mean(f <= 0) == pytest.approx(0.28, abs=0.01)
    assert checker.valid(SHELF_START) and checker.valid(SHELF_GOAL)
    assert checker.edge_valid(SHELF_START, SHELF_GOAL)[0] is False


def test_default_capsules_join_the_joint_origins():
    robot = armkit.robot("inspection_6dof")
    geometry = default_geometry(robot, 0.04)
    q = random_q(robot, (), seed=2)
    a, b = reference.capsules(robot, geometry, q)
    origins = armkit.fk_frames(robot, q)[:, :3, 3]       # DH frame origins 0 .. 6
    np.testing.assert_allclose(a, origins[:-1], atol=1e-12)
    np.testing.assert_allclose(b, origins[1:], atol=1e-12)
    assert np.all(geometry.radius == 0.04)
    # Adjacent links are never paired; the wrist's always-touching pairs are skipped.
    pairs = geometry.self_pairs()
    assert all(abs(geometry.link[i] - geometry.link[j]) > 1 for i, j in pairs)
    assert (3, 5) in geometry.skip


@pytest.mark.parametrize("name", ["inspection_6dof", "water_supply", "tool_changer_6dof", "ur5"])
def test_displacement_bound_holds(name):
    """No point of a capsule moves further than sum w_i |dq_i| between two configurations."""
    robot = armkit.robot(name)
    geometry = default_geometry(robot, 0.05)
    w = displacement_weights(robot, geometry)
    rng = np.random.default_rng(0)
    Q0 = random_q(robot, 200, seed=1)
    dQ = rng.normal(0, 0.2, Q0.shape) * (robot.upper - robot.lower) / 6
    Q1 = np.clip(Q0 + dQ, robot.lower, robot.upper)
    t = np.linspace(0, 1, 11)[:, None]
    for q0, q1 in zip(Q0, Q1):
        a0, b0 = reference.capsules(robot, geometry, q0)
        a1, b1 = reference.capsules(robot, geometry, q1)
        moved = np.linalg.norm((a0 + t[:, None] * (b0 - a0)) - (a1 + t[:, None] * (b1 - a1)),
                               axis=-1).max()
        assert moved <= w @ np.abs(q1 - q0) + 1e-12


@pytest.mark.parametrize("padding", [0.0, 0.01])
def test_certified_edges_keep_the_padding_between_checks(padding):
    """Every configuration of a certified edge, between its checked states too, keeps more
    than the padding from the obstacles (twice it between the arm's parts): the independent
    dense check."""
    robot = armkit.robot("inspection_6dof")
    geometry = default_geometry(robot, 0.04)
    scene = shelf()
    checker = CollisionChecker(robot, scene, geometry, resolution=0.002, padding=padding)
    Q = random_q(robot, 300, seed=5)
    Q = Q[checker.valid(Q)]
    accepted = 0
    for qa, qb in zip(Q[:-1:2], Q[1::2]):
        qb = qa + 0.2 * (qb - qa)
        free, _ = checker.edge_valid(qa, qb)
        if free:
            accepted += 1
            obstacle_gap, self_gap, _ = reference.dense_gaps(robot, geometry, scene, [qa, qb],
                                                             points=60)
            assert obstacle_gap > padding and self_gap > 2 * padding
        if accepted == 8:
            break
    assert accepted == 8


def test_a_tiny_clearance_is_valid_and_its_edges_check_finely():
    """Validity is apart from certification: a state 0.5 mm from a plate is valid; an edge
    from it certifies with more states than one far from everything, and one too close for
    the resolution fails."""
    robot = armkit.robot("inspection_6dof")
    checker = CollisionChecker(robot, shelf(), default_geometry(robot, 0.04), resolution=1e-4)
    line = SHELF_START + np.linspace(0, 1, 4001)[:, None] * (SHELF_GOAL - SHELF_START)
    f = checker.clearance(line)
    k = int(np.argmax(f <= 0)) - 1                   # the last free state before the plate
    near = line[k]
    assert 0 < f[k] < 0.003 and checker.valid(near)
    back = line[k - 200]
    free, near_states = checker.edge_valid(back, near)
    assert free
    far = back - 0.05 * (SHELF_GOAL - SHELF_START)
    assert checker.edge_valid(far, back)[0]
    assert near_states > checker.edge_valid(far, back)[1]
    coarse = CollisionChecker(robot, shelf(), default_geometry(robot, 0.04), resolution=0.05)
    assert coarse.valid(near) and not coarse.edge_valid(back, near)[0]


def test_robot_file_collision_section(tmp_path):
    text = """name: two_link
units: {length: mm, angle: deg}
convention: dh
collision:
  shapes:
    - {link: 1, a: [-300, 0, 0], b: [0, 0, 0], radius: 30}
    - {link: 2, a: [0, 0, 0], radius: 50}
  skip: [[0, 2]]
joints:
  - {type: revolute, alpha: 0, a: 300, d: 0, theta: 0, limits: [-90, 90]}
  - {type: revolute, alpha: 0, a: 200, d: 0, theta: 0, limits: [-90, 90]}
"""
    path = tmp_path / "two.yaml"
    path.write_text(text)
    robot = armkit.robot(str(path))
    geometry = arm_geometry(robot)
    assert geometry.source == "robot file" and len(geometry) == 2
    np.testing.assert_allclose(geometry.a[0], [-0.3, 0, 0])
    np.testing.assert_allclose(geometry.b[1], geometry.a[1])          # a sphere
    np.testing.assert_allclose(geometry.radius, [0.03, 0.05])
    assert geometry.skip == ((0, 2),)
    saved = tmp_path / "saved.yaml"
    armkit.save_robot(robot, saved)
    again = arm_geometry(armkit.robot(str(saved)))
    np.testing.assert_allclose(again.a, geometry.a) and np.testing.assert_allclose(
        again.radius, geometry.radius)
    radius_only = text.replace("""  shapes:
    - {link: 1, a: [-300, 0, 0], b: [0, 0, 0], radius: 30}
    - {link: 2, a: [0, 0, 0], radius: 50}
""", "  radius: 25\n")
    path.write_text(radius_only)
    g = arm_geometry(armkit.robot(str(path)))
    assert g.source.startswith("default") and np.all(g.radius == 0.025)


@pytest.mark.parametrize("section, field, found", [
    ("  shapes:\n    - {link: 7, a: [0, 0, 0], radius: 5}\n", "collision.shapes[0].link", "7"),
    ("  radius: -3\n", "collision.radius", "-3"),
    ("  radius: 3\n  shapes:\n    - {link: 1, a: [0, 0, 0], radius: 5}\n", "collision",
     "found both"),
    ("  skip: [[0, 9]]\n", "collision.skip[0]", "[0, 9]"),
    ("  shapes:\n    - {link: 1, a: [0, 0], radius: 5}\n", "collision.shapes[0].a", ""),
    ("  radiuss: 3\n", "collision", "radiuss"),
])
def test_robot_file_collision_section_bad_input(tmp_path, section, field, found):
    path = tmp_path / "bad.yaml"
    path.write_text("name: one\nunits: {length: mm, angle: deg}\nconvention: dh\ncollision:\n"
                    + section + "joints:\n  - {type: revolute, alpha: 0, a: 300, d: 0, "
                    "theta: 0, limits: [-90, 90]}\n")
    with pytest.raises(armkit.ModelFileError) as err:
        armkit.robot(str(path))
    assert err.value.field == field and found in str(err.value)


def test_checker_bad_input():
    robot = armkit.robot("ur5")
    with pytest.raises(InputError, match="resolution"):
        CollisionChecker(robot, Scene(), resolution=0)
    for bad in (-0.01, float("nan"), "1"):
        with pytest.raises(InputError, match="padding: expected a non-negative length"):
            CollisionChecker(robot, Scene(), padding=bad)
    with pytest.raises(InputError, match="scene"):
        CollisionChecker(robot, [1, 2])
    with pytest.raises(InputError, match="links 0 .. 6"):
        CollisionChecker(robot, Scene(), ArmGeometry([9], [[0, 0, 0]], [[0, 0, 0]], [0.1]))
    with pytest.raises(InputError, match="expected last axis 6"):
        CollisionChecker(robot).valid([0, 0, 0])
