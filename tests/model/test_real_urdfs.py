"""Real URDF files from public robot packages (the example-robot-data wheel) load with the chain
asked for and match Pinocchio's forward kinematics (an independent reference) to 1e-12."""

from __future__ import annotations

import importlib.metadata
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.urdf import read_urdf
from armkit.model import chain_from_urdf


def robot_file(suffix: str) -> str:
    """The installed example-robot-data file whose path ends with `suffix`."""
    dist = importlib.metadata.distribution("example-robot-data")
    found = [f for f in dist.files or () if str(f).replace("\\", "/").endswith(suffix)]
    assert len(found) == 1, f"example-robot-data holds {len(found)} files ending {suffix}"
    path = dist.locate_file(found[0])
    assert path.is_file(), path
    return str(path)


# (file, tip, moving joints on the chain): the arms the issue names, then other public arms.
ARMS = [
    ("panda_description/urdf/panda.urdf", "panda_hand", 7),          # the hand, fingers off
    ("panda_description/urdf/panda.urdf", "panda_leftfinger", 8),    # the independent finger
    ("baxter_description/urdf/baxter.urdf", "left_gripper", 7),      # one arm of two
    ("baxter_description/urdf/baxter.urdf", "right_gripper", 7),
    ("talos_data/robots/talos_reduced.urdf", "arm_left_7_link", 9),  # torso 2 + arm 7
    ("talos_data/robots/talos_full_v2.urdf", "gripper_right_motor_double_link", 10),
    ("ur_description/urdf/ur5_robot.urdf", "tool0", 6),
    ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector", 6),
    ("xarm_description/urdf/xarm7.urdf", "link_eef", 7),
    ("so_arm_description/urdf/so101.urdf", "gripper_frame_link", 5),
    ("z1_description/urdf/z1.urdf", "gripperMover", 7),
    ("tiago_description/robots/tiago.urdf", "arm_tool_link", 8),     # torso lift + arm 7
]


def pinocchio_frames(path: str, robot: armkit.Robot, Q: np.ndarray, links: list[str]):
    """Pinocchio's pose of each named link (k, len(links), 4, 4) at armkit's joint vectors Q."""
    model = pin.buildModelFromUrdf(path)
    data = model.createData()
    out = np.empty((len(Q), len(links), 4, 4))
    for k, q in enumerate(Q):
        qp = pin.neutral(model)
        for joint, value in zip(robot.chain.joints, q):
            jid = model.getJointId(joint.name)
            assert jid < model.njoints, joint.name
            i, nq = model.joints[jid].idx_q, model.joints[jid].nq
            qp[i:i + nq] = [np.cos(value), np.sin(value)] if nq == 2 else [value]  # continuous
        pin.framesForwardKinematics(model, data, qp)
        for m, link in enumerate(links):
            out[k, m] = data.oMf[model.getFrameId(link)].homogeneous
    return out


@pytest.mark.parametrize("suffix, tip, n", ARMS, ids=[f"{a[0].split('/')[-1]}-{a[1]}"
                                                      for a in ARMS])
def test_real_arm_matches_pinocchio(suffix, tip, n):
    path = robot_file(suffix)
    table = read_urdf(path, tip=tip)
    robot = armkit.Robot(tip, chain_from_urdf(table))
    assert robot.n == n
    Q = np.random.default_rng(7).uniform(*robot.chain.sampling_limits, (40, n))
    links = [j.child for j in table.joints if j.kind != "fixed"][:-1] + [tip]
    expected = pinocchio_frames(path, robot, Q, links)
    frames = armkit.fk_frames(robot, Q)[:, 1:]        # link frames of joints 1..n-1, then tip
    np.testing.assert_allclose(frames, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(armkit.fk(robot, Q), expected[:, -1], rtol=0, atol=1e-12)


def test_limits_come_from_the_file():
    table = read_urdf(robot_file("panda_description/urdf/panda.urdf"), tip="panda_hand")
    robot = armkit.Robot("panda", chain_from_urdf(table))
    np.testing.assert_allclose(robot.lower[[0, 3]], [-2.8973, -3.0718])
    np.testing.assert_allclose(robot.chain.velocity_limits[[0, 6]], [2.175, 2.61])


# Chains through mimic joints: (file, tip, joint values, moving joints on the chain).
MIMIC_CHAINS = [
    ("panda_description/urdf/panda.urdf", "panda_rightfinger", 8, 8),   # leader off the chain
    ("talos_data/robots/talos_full_v2.urdf", "gripper_left_fingertip_1_link", 10, 11),
    ("talos_data/robots/talos_full_v2.urdf", "gripper_left_fingertip_3_link", 10, 11),
    ("pr2_description/urdf/pr2.urdf", "r_gripper_l_finger_tip_link", 9, 10),
]


def file_mimics(path: str) -> dict[str, tuple[str, float, float]]:
    """Each mimic joint's (leader, multiplier, offset), read from the file with ElementTree."""
    out = {}
    for joint in ET.parse(path).getroot().iter("joint"):
        m = joint.find("mimic")
        if m is not None:
            out[joint.get("name")] = (m.get("joint"), float(m.get("multiplier", "1")),
                                      float(m.get("offset", "0")))
    return out


@pytest.mark.parametrize("suffix, tip, n, moving", MIMIC_CHAINS,
                         ids=[c[1] for c in MIMIC_CHAINS])
def test_a_chain_through_mimic_joints_matches_pinocchio(suffix, tip, n, moving):
    path = robot_file(suffix)
    robot = armkit.load_robot(path, tip=tip)
    assert (robot.n, robot.chain.n_joints) == (n, moving)
    mimics = file_mimics(path)
    assert not set(robot.joint_names) & set(mimics)         # a mimic joint has no value
    model = pin.buildModelFromUrdf(path)                   # every joint independent
    data = model.createData()
    frame = model.getFrameId(tip)
    Q = np.random.default_rng(3).uniform(*robot.chain.sampling_limits, (20, n))
    for q in Q:
        values = dict(zip(robot.joint_names, q))
        coupling = np.zeros((model.nv, n))                 # d(pinocchio's v)/d(armkit's q)
        for k, name in enumerate(robot.joint_names):
            coupling[model.joints[model.getJointId(name)].idx_v, k] = 1.0
        for name, (leader, m, b) in mimics.items():
            if leader in values:
                values[name] = m * values[leader] + b
                k = robot.joint_names.index(leader)
                coupling[model.joints[model.getJointId(name)].idx_v, k] = m
        qp = pin.neutral(model)
        for name, v in values.items():
            joint = model.joints[model.getJointId(name)]
            qp[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(v), np.sin(v)] if joint.nq == 2 else v
        pin.computeJointJacobians(model, data, qp)
        pin.updateFramePlacements(model, data)
        J = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED) @ coupling
        np.testing.assert_allclose(armkit.fk(robot, q), data.oMf[frame].homogeneous,
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(armkit.jacobian(robot, q), J, rtol=0, atol=1e-12)
    # The leaders' limits keep every mimic joint within its own.
    lower = {j.name: j.limits.lower for j in robot.chain.joints}
    upper = {j.name: j.limits.upper for j in robot.chain.joints}
    for name, (leader, m, b) in mimics.items():
        if name in lower:
            k = robot.joint_names.index(leader)
            ends = m * np.array([robot.lower[k], robot.upper[k]]) + b
            assert lower[name] - 1e-12 <= ends.min() and ends.max() <= upper[name] + 1e-12


def test_ik_through_a_mimic_finger():
    robot = armkit.load_robot(robot_file("panda_description/urdf/panda.urdf"),
                              tip="panda_rightfinger")
    q = np.random.default_rng(5).uniform(*robot.chain.sampling_limits, (50, robot.n))
    found = armkit.ik(robot, armkit.fk(robot, q), mask="position", seed=1)
    assert found.success.all()
    np.testing.assert_allclose(armkit.fk(robot, found.q)[:, :3, 3], armkit.fk(robot, q)[:, :3, 3],
                               rtol=0, atol=1e-9)
    assert ((found.q >= robot.lower) & (found.q <= robot.upper)).all()


def test_a_tree_without_a_named_tip_lists_its_leaves():
    path = robot_file("baxter_description/urdf/baxter.urdf")
    with pytest.raises(ModelFileError, match=r"tip: expected the name of the tip link \(the tree "
                                             r"has several: left_torso_itb, .* \(29 in all\)\)"):
        armkit.load_robot(path)
    arm = armkit.load_robot(path, tip="left_gripper")
    assert arm.name == "baxter" and arm.n == 7 and arm.joint_names[0] == "left_s0"


def test_robot_file_wrapping_a_real_urdf(tmp_path):
    path = robot_file("talos_data/robots/talos_reduced.urdf")
    wrapper = tmp_path / "talos_left.yaml"
    wrapper.write_text(f"name: talos_left\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                       f"urdf: {path}\ntip: arm_left_7_link\n")
    robot = armkit.robot(str(wrapper))
    assert robot.n == 9 and robot.joint_names[2] == "arm_left_1_joint"
    direct = armkit.Robot("t", chain_from_urdf(read_urdf(path, tip="arm_left_7_link")))
    q = np.random.default_rng(1).uniform(robot.lower, robot.upper)
    np.testing.assert_array_equal(armkit.fk(robot, q), armkit.fk(direct, q))
