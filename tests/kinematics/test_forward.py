"""Forward kinematics: batch shapes, input checks, frames, large batches."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.kinematics import core
from tests.helpers import random_q


@pytest.mark.parametrize("lead", [(), (7,), (2, 3)])
def test_leading_shapes_match_single_calls(any_robot, lead):
    Q = random_q(any_robot, lead if lead else 1)[0] if not lead else random_q(any_robot, lead)
    T, F = armkit.fk(any_robot, Q), armkit.fk_frames(any_robot, Q)
    assert T.shape == lead + (4, 4) and F.shape == lead + (any_robot.n + 1, 4, 4)
    flat_q, flat_T = Q.reshape(-1, any_robot.n), T.reshape(-1, 4, 4)
    for q, Tk in zip(flat_q, flat_T):
        np.testing.assert_array_equal(armkit.fk(any_robot, q), Tk)
    np.testing.assert_array_equal(F[..., -1, :, :], T)                  # the tool is last
    np.testing.assert_array_equal(F[..., 0, :, :], np.broadcast_to(any_robot.chain.T_base, T.shape))


def test_serial_and_parallel_kernels_agree():
    robot = armkit.robot("panda")
    Q = random_q(robot, 2 * core.GRAIN + 5)
    k = robot.chain.kernel
    a, b = np.empty((len(Q), 4, 4)), np.empty((len(Q), 4, 4))
    core.poses(Q, k.F, k.I, a)
    core.poses_parallel(Q, k.F, k.I, b)
    np.testing.assert_array_equal(a, b)


def test_thread_count_changes_nothing_but_speed():
    robot = armkit.robot("ur5")
    Q = random_q(robot, 3 * core.GRAIN)
    try:
        armkit.set_num_threads(1)
        one = armkit.fk(robot, Q), armkit.jacobian(robot, Q)
        armkit.set_num_threads(2)
        two = armkit.fk(robot, Q), armkit.jacobian(robot, Q)
    finally:
        armkit.set_num_threads(None)
    np.testing.assert_array_equal(one[0], two[0])
    np.testing.assert_array_equal(one[1], two[1])


@pytest.mark.parametrize("n", [0, -1, 1.5, True, "2", 10_000])
def test_bad_thread_counts_are_refused(n):
    with pytest.raises(InputError, match=r"n: expected a whole number of threads 1 \.\. \d+"):
        armkit.set_num_threads(n)


def test_rotation_stays_orthonormal_over_a_large_batch():
    robot = armkit.robot("ur5")
    T = armkit.fk(robot, random_q(robot, 100_000))
    R = T[:, :3, :3]
    assert np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() < 1e-14
    assert np.all(T[:, 3] == [0, 0, 0, 1])


def test_accepts_lists_and_integer_arrays():
    robot = armkit.robot("ur5")
    np.testing.assert_array_equal(armkit.fk(robot, [0, 1, 0, 0, 0, 0]),
                                  armkit.fk(robot, np.array([0, 1, 0, 0, 0, 0])))


@pytest.mark.parametrize("q, words", [
    (np.zeros(4), "q: expected last axis 6 (the joints of ur5), found 4"),
    (np.zeros((3, 5)), "found 5"),
    (1.0, "found a scalar"),
    ([0, 0, np.nan, 0, 0, 0], "q: expected finite joint values, found NaN or inf"),
    (np.full((100, 6), np.inf), "NaN or inf"),
    ("abc", "q: expected real joint values, found text"),
    (np.zeros(6, complex), "q: expected real joint values, found complex numbers"),
    (np.ones(6, bool), "q: expected real joint values, found booleans"),
    ([True, False, True, True, True, True], "found booleans"),
])
def test_bad_q_is_refused_with_its_reason(q, words):
    with pytest.raises(InputError) as err:
        armkit.fk(armkit.robot("ur5"), q)
    assert words in str(err.value)


MIMIC_URDF = """<robot name="parallel">
  <link name="base"/><link name="upper"/><link name="fore"/><link name="hand"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.4 0 0.1" rpy="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" velocity="1"/></joint>
  <joint name="wrist" type="revolute"><parent link="fore"/><child link="hand"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" velocity="1"/>
    <mimic joint="elbow" multiplier="-1" offset="0.2"/></joint>
</robot>"""


def packed_robots(tmp_path) -> list[armkit.Robot]:
    path = tmp_path / "parallel.urdf"
    path.write_text(MIMIC_URDF)
    names = ("ur5", "puma560", "stanford", "panda", "tool_changer_6dof", "water_supply")
    return [armkit.robot(name) for name in names] + [armkit.load_robot(path)]


def test_the_packed_chain_holds_the_kernel_arrays(tmp_path):
    for robot in packed_robots(tmp_path):
        k, nj = robot.chain.kernel, robot.chain.n_joints
        np.testing.assert_array_equal(k.ints, np.r_[k.kinds, k.source])
        np.testing.assert_array_equal(k.floats[:nj], k.offsets)
        np.testing.assert_array_equal(k.floats[nj:2 * nj], k.scale)
        np.testing.assert_array_equal(k.floats[2 * nj:2 * nj + 12].reshape(3, 4), k.pre[:3])
        np.testing.assert_array_equal(k.floats[2 * nj + 12:].reshape(nj, 3, 4), k.links[:, :3])
        assert not (k.floats.flags.writeable or k.ints.flags.writeable)


def test_one_configuration_equals_its_row_of_the_batch(tmp_path):
    # One configuration goes straight to the `_one` kernels with the packed chain; a batch
    # goes through the batch loops: the same values, bit for bit, mimic joints included.
    for robot in packed_robots(tmp_path):
        Q = random_q(robot, 50, seed=3)
        T, J = armkit.fk(robot, Q), armkit.jacobian(robot, Q)
        for q, Tk, Jk in zip(Q, T, J):
            np.testing.assert_array_equal(armkit.fk(robot, q), Tk)
            np.testing.assert_array_equal(armkit.jacobian(robot, q), Jk)
        # And with the chain's own definition, walked joint by joint in NumPy.
        for q, Tk in zip(Q[:5], T[:5]):
            np.testing.assert_allclose(chain_pose(robot.chain, q), Tk, atol=1e-12)


def chain_pose(chain, q) -> np.ndarray:
    """T_base @ prod(T_before @ M(value) @ T_after) @ T_tool, M about or along the joint's
    axis by ``scale * q[source] + offsets`` (mimic joints by their leader's value)."""
    k, T = chain.kernel, chain.T_base.copy()
    for j, source, scale, offset in zip(chain.joints, k.source, k.scale, k.offsets):
        value, M, (x, y, z) = scale * q[source] + offset, np.eye(4), j.axis
        if j.kind == "revolute":
            K = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
            M[:3, :3] += np.sin(value) * K + (1 - np.cos(value)) * K @ K
        else:
            M[:3, 3] = value * j.axis
        T = T @ j.T_before @ M @ j.T_after
    return T @ chain.T_tool
