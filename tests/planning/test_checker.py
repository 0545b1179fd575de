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
    np.testing.assert_array_equal(checker.valid(Q), expected > 0.005)
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


def test_certified_edges_keep_half_the_resolution_between_checks():
    robot = armkit.robot("inspection_6dof")
    geometry = default_geometry(robot, 0.04)
    scene = shelf()
    checker = CollisionChecker(robot, scene, geometry, resolution=0.01)
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
            assert obstacle_gap >= 0.005 - 1e-12 and self_gap >= 0.01 - 1e-12
        if accepted == 8:
            break
    assert accepted == 8


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
    with pytest.raises(InputError, match="scene"):
        CollisionChecker(robot, [1, 2])
    with pytest.raises(InputError, match="links 0 .. 6"):
        CollisionChecker(robot, Scene(), ArmGeometry([9], [[0, 0, 0]], [[0, 0, 0]], [0.1]))
    with pytest.raises(InputError, match="expected last axis 6"):
        CollisionChecker(robot).valid([0, 0, 0])


def test_kernel_sine_cosine_within_one_ulp_of_libm():
    """The checker's inlined sine and cosine (range reduction and polynomials) against the C
    library's, at angles near the reduction's quadrant edges, small, large and huge."""
    import math

    from armkit.planning.collision import sin_cos

    rng = np.random.default_rng(4)
    edges = np.arange(-40, 41) * (np.pi / 4)
    x = np.concatenate([rng.uniform(-7, 7, 3000), rng.uniform(-1e5, 1e5, 500),
                        edges, np.nextafter(edges, 0), np.nextafter(edges, 9),
                        [0.0, -0.0, 1e-300, 5e-9, 1e6, -3e7, 1e300]])
    for v in x:
        s, c = sin_cos(v)
        ls, lc = math.sin(v), math.cos(v)
        assert abs(s - ls) <= np.spacing(abs(ls)) and abs(c - lc) <= np.spacing(abs(lc))
    s, c = sin_cos(np.inf)
    assert math.isnan(s) and math.isnan(c)


def test_joint_angles_beyond_the_reduction_range_match_the_reduced_ones():
    """Angles whose sines the kernel leaves to libm (|v| >= 1e5 rad) give the clearance of the
    same angles taken modulo 2 pi, in a batch and one state at a time."""
    robot = armkit.robot("inspection_6dof")
    checker = CollisionChecker(robot, shelf(), default_geometry(robot, 0.04))
    Q = random_q(robot, 50, seed=9)
    turns = np.zeros_like(Q)
    turns[:, ::2] = 2 * np.pi * 20_000                      # 1.26e5 rad on three joints
    far = Q + turns
    np.testing.assert_allclose(checker.clearance(far), checker.clearance(Q), atol=1e-9)
    np.testing.assert_allclose([checker.clearance(q) for q in far], checker.clearance(Q),
                               atol=1e-9)


def test_kernel_sine_reduction_constants_split_half_pi():
    """The three parts of pi/2 the reduction subtracts: the first two of 33 significant bits
    (their products with any k below 2**20 are exact), the three summing to pi/2 within 1e-36,
    pi from Machin's formula in integers."""
    from fractions import Fraction

    from armkit.planning.collision import _PI_2_HIGH, _PI_2_LOW, _PI_2_MID

    def arctan_of_inverse(n: int, scale: int) -> int:
        total, term, k = 0, scale // n, 1
        while term:
            total += term // k if k % 4 == 1 else -(term // k)
            term //= n * n
            k += 2
        return total

    scale = 10 ** 60
    half_pi = Fraction(16 * arctan_of_inverse(5, scale) - 4 * arctan_of_inverse(239, scale),
                       2 * scale)
    for part in (_PI_2_HIGH, _PI_2_MID):
        mantissa = Fraction(part)
        while mantissa.denominator != 1:
            mantissa *= 2
        assert int(mantissa).bit_length() - (int(mantissa) & -int(mantissa)).bit_length() < 33
    assert abs(Fraction(_PI_2_HIGH) + Fraction(_PI_2_MID) + Fraction(_PI_2_LOW) - half_pi) < 1e-36
