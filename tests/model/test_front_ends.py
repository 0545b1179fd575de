"""One arm written as standard DH, modified DH, screws and URDF gives one FK (to 1e-12).

The conversions are done by hand here, from the DH table's definition, not through armkit.
"""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.io.urdf import read_urdf
from armkit.model import (DHRow, DHTable, Limits, Robot, ScrewRow, ScrewTable, chain_from_dh,
                          chain_from_poe, chain_from_urdf)
from armkit.spatial import rotx, rotz, transform

from tests.helpers import random_q

# Puma 560 (SI): alpha, a, d per row; all revolute, theta offsets zero; then a 0.1 m tool.
ALPHA = np.deg2rad([90, 0, -90, 90, -90, 0])
A = [0, 0.4318, 0.0203, 0, 0, 0]
D = [0.67183, 0, 0.15005, 0.4318, 0, 0]
LIMITS = Limits(-np.pi, np.pi)
TOOL = transform(rotx(0.3), [0.0, 0.02, 0.1])


def dh_robot() -> Robot:
    rows = tuple(DHRow("revolute", al, a, d, 0.0, limits=LIMITS) for al, a, d in zip(ALPHA, A, D))
    return Robot("dh", chain_from_dh(DHTable(rows, T_tool=TOOL)))


def mdh_robot() -> Robot:
    # Row i of modified DH carries alpha_{i-1}, a_{i-1}; the last alpha and a go to the tool.
    alphas, lengths = np.r_[0, ALPHA[:-1]], np.r_[0, A[:-1]]
    rows = tuple(DHRow("revolute", al, a, d, 0.0, limits=LIMITS)
                 for al, a, d in zip(alphas, lengths, D))
    last = transform(p=[A[-1], 0, 0]) @ transform(rotx(ALPHA[-1]))
    return Robot("mdh", chain_from_dh(DHTable(rows, modified=True, T_tool=last @ TOOL)))


def screw_robot() -> Robot:
    # At q = 0 joint i turns about z of DH frame i-1; walk the DH frames by hand.
    frame, rows = np.eye(4), []
    for al, a, d in zip(ALPHA, A, D):
        rows.append(ScrewRow("revolute", frame[:3, 2].copy(), LIMITS, frame[:3, 3].copy()))
        frame = frame @ transform(p=[0, 0, d]) @ transform(p=[a, 0, 0]) @ transform(rotx(al))
    return Robot("poe", chain_from_poe(ScrewTable(tuple(rows), T_home=frame @ TOOL)))


def urdf_robot(tmp_path) -> Robot:
    # Joint i turns about z of its parent; its child frame is DH frame i-1 turned by q_i, so
    # the origin of joint i+1 is DH row i's fixed part Tz(d) Tx(a) Rx(alpha).
    joints, origin = [], "0 0 0"
    rpy = "0 0 0"
    for i, (al, a, d) in enumerate(zip(ALPHA, A, D)):
        joints.append(f"""
  <joint name="j{i + 1}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>
    <origin xyz="{origin}" rpy="{rpy}"/><axis xyz="0 0 1"/>
    <limit lower="-3.14159" upper="3.14159" effort="1" velocity="2"/></joint>""")
        origin, rpy = f"{float(a)!r} 0 {float(d)!r}", f"{float(al)!r} 0 0"
    joints.append(f"""
  <joint name="flange" type="fixed"><parent link="l6"/><child link="flange"/>
    <origin xyz="{origin}" rpy="{rpy}"/></joint>
  <joint name="tool" type="fixed"><parent link="flange"/><child link="tool"/>
    <origin xyz="0 0.02 0.1" rpy="0.3 0 0"/></joint>""")
    links = "".join(f'<link name="l{i}"/>' for i in range(7)) + '<link name="flange"/><link name="tool"/>'
    path = tmp_path / "puma.urdf"
    path.write_text(f'<robot name="puma">{links}{"".join(joints)}\n</robot>')
    return Robot("urdf", chain_from_urdf(read_urdf(path)))


def test_four_descriptions_one_fk(tmp_path):
    reference = dh_robot()
    Q = random_q(reference, 300, seed=4)
    T = armkit.fk(reference, Q)
    for other in (mdh_robot(), screw_robot(), urdf_robot(tmp_path)):
        np.testing.assert_allclose(armkit.fk(other, Q), T, atol=1e-12, err_msg=other.name)
        np.testing.assert_allclose(armkit.jacobian(other, Q), armkit.jacobian(reference, Q),
                                   atol=1e-12, err_msg=other.name)


def test_link_frames_follow_each_convention(tmp_path):
    q = random_q(dh_robot(), 1, seed=5)[0]
    dh = armkit.fk_frames(dh_robot(), q)
    # DH frame i = A_1 ... A_i.
    A_rows = [transform(rotz(qi)) @ transform(p=[0, 0, d]) @ transform(p=[a, 0, 0])
              @ transform(rotx(al)) for qi, al, a, d in zip(q, ALPHA, A, D)]
    expected = np.eye(4)
    for i, Ai in enumerate(A_rows[:-1]):
        expected = expected @ Ai
        np.testing.assert_allclose(dh[i + 1], expected, atol=1e-12)
    # URDF link frames: the child of joint i (DH frame i-1 turned by q_i).
    urdf = armkit.fk_frames(urdf_robot(tmp_path), q)
    np.testing.assert_allclose(urdf[1], transform(rotz(q[0])), atol=1e-12)
    np.testing.assert_allclose(urdf[2], dh[1] @ transform(rotz(q[1])), atol=1e-12)


def test_prismatic_rows_slide_along_z():
    rows = (DHRow("prismatic", 0.0, 0.1, 0.2, 0.3, limits=Limits(0, 1)),)
    for modified in (False, True):
        robot = Robot("p", chain_from_dh(DHTable(rows, modified=modified)))
        dz = armkit.fk(robot, [0.5])[:3, 3] - armkit.fk(robot, [0.0])[:3, 3]
        np.testing.assert_allclose(dz, [0, 0, 0.5], atol=1e-15)


def test_fixed_rows_fold_into_neighbours():
    lift = DHRow("prismatic", 0, 0, 0, 0, limits=Limits(0, 1))
    base = DHRow("fixed", 0, 0, 0.5, 0)
    tip = DHRow("fixed", 0, 0.25, 0, 0)
    robot = Robot("f", chain_from_dh(DHTable((base, lift, tip), modified=True)))
    assert robot.n == 1
    np.testing.assert_allclose(armkit.fk(robot, [0.1])[:3, 3], [0.25, 0, 0.6], atol=1e-15)


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, -1, 0], [0, 0, -1], [1, 2, 3]])
def test_any_screw_axis(axis):
    axis = np.array(axis, float) / np.linalg.norm(axis)
    point = np.array([0.3, -0.2, 0.1])
    robot = Robot("s", chain_from_poe(ScrewTable(
        (ScrewRow("revolute", axis, LIMITS, point),), T_home=transform(p=[1.0, 0.5, 0.2]))))
    t = 0.8
    # Rodrigues about the line through `point`.
    K = armkit.spatial.skew(axis)
    R = np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K
    expected = R @ (np.array([1.0, 0.5, 0.2]) - point) + point
    np.testing.assert_allclose(armkit.fk(robot, [t])[:3, 3], expected, atol=1e-15)


def test_home_screws_reproduce_fk(any_robot):
    """T(q) = exp([S_1] q_1) ... exp([S_n] q_n) T_home, for every built-in robot."""
    from armkit.spatial import exp_se3
    chain = any_robot.chain
    for q in random_q(any_robot, 20, seed=6):
        T = np.eye(4)
        for S, qi in zip(chain.screws, q):
            T = T @ exp_se3(S * qi)
        np.testing.assert_allclose(T @ chain.T_home, armkit.fk(any_robot, q), atol=1e-12)
