"""Straight-line tool motion: on the line to 1e-9 m where the arm can follow it, and an honest
stop (out of reach, outside joint limits, singular) where it cannot."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.kinematics.ik.reasons import OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, SINGULAR
from armkit.spatial import rotation_angle, rotz, transform
from armkit.trajectory.cartesian import cartesian_line, line_poses

UR5 = armkit.robot("ur5")
Q0 = np.deg2rad([30, -60, 80, -100, -70, 20])


def distance_from_line(points, a, b):
    u = (b - a) / np.linalg.norm(b - a)
    rel = points - a
    return np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)


@given(dx=st.floats(-0.15, 0.15), dy=st.floats(-0.15, 0.15), dz=st.floats(-0.15, 0.15),
       turn=st.floats(-0.5, 0.5))
def test_the_tool_stays_on_the_line_as_far_as_it_follows_it(dx, dy, dz, turn):
    T0 = armkit.fk(UR5, Q0)
    T1 = transform(T0[:3, :3] @ rotz(turn), T0[:3, 3] + [dx, dy, dz])
    path = cartesian_line(UR5, T0, T1, Q0)
    assert path.success or path.reason in (OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, SINGULAR)
    assert path.success == (path.stop == 1.0) == (len(path.q) == len(path.s))
    reached = armkit.fk(UR5, path.q)
    np.testing.assert_allclose(reached, path.poses[:len(path.q)], atol=1e-9)
    if np.linalg.norm([dx, dy, dz]) > 1e-6:
        assert distance_from_line(reached[:, :3, 3], T0[:3, 3], T1[:3, 3]).max() < 1e-9
    # No jumps: every joint step stays under the singularity threshold.
    assert np.abs(np.diff(path.q, axis=0)).max(initial=0.0) <= 0.35


def test_a_short_line_is_followed_whole():
    T0 = armkit.fk(UR5, Q0)
    T1 = transform(T0[:3, :3] @ rotz(0.2), T0[:3, 3] + [0.1, -0.05, 0.08])
    path = cartesian_line(UR5, T0, T1, Q0)
    assert path.success and path.reason == "ok"
    assert distance_from_line(armkit.fk(UR5, path.q)[:, :3, 3], T0[:3, 3], T1[:3, 3]).max() < 1e-9
    assert np.abs(np.diff(path.q, axis=0)).max() < 0.05      # smooth, well away from singular


def test_steps_bound_the_sample_spacing():
    T0 = armkit.fk(UR5, Q0)
    T1 = transform(T0[:3, :3] @ rotz(0.3), T0[:3, 3] + [0.2, 0.0, 0.0])
    path = cartesian_line(UR5, T0, T1, Q0, step=0.01, angle_step=np.deg2rad(2))
    spacing = np.linalg.norm(np.diff(path.poses[:, :3, 3], axis=0), axis=1)
    turns = rotation_angle(np.swapaxes(path.poses[:-1, :3, :3], 1, 2) @ path.poses[1:, :3, :3])
    assert spacing.max() <= 0.01 + 1e-12 and turns.max() <= np.deg2rad(2) + 1e-12
    np.testing.assert_allclose(spacing, spacing[0], atol=1e-12)      # constant speed along s
    np.testing.assert_allclose(turns, turns[0], atol=1e-9)           # and constant turn rate


def test_line_poses_ends_and_midpoint():
    T0 = transform(np.eye(3), [0, 0, 0])
    T1 = transform(rotz(np.pi / 2), [1.0, 2.0, 0.0])
    P = line_poses(T0, T1, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(P[0], T0, atol=1e-15)
    np.testing.assert_allclose(P[2], T1, atol=1e-15)
    np.testing.assert_allclose(P[1], transform(rotz(np.pi / 4), [0.5, 1.0, 0.0]), atol=1e-15)


def test_leaving_the_workspace_stops_with_out_of_reach():
    T0 = armkit.fk(UR5, Q0)
    T1 = T0.copy()
    T1[:3, 3] += [1.5, 0.0, 0.0]
    path = cartesian_line(UR5, T0, T1, Q0)
    assert not path.success and path.reason == OUT_OF_REACH and 0 < path.stop < 1
    assert len(path.q) < len(path.s)
    np.testing.assert_allclose(armkit.fk(UR5, path.q), path.poses[:len(path.q)], atol=1e-9)


def test_a_joint_limit_stops_the_lift():
    robot = armkit.robot("water_supply")
    q0 = np.array([0.1, 0.3, 0.6, 0.0])
    T0 = armkit.fk(robot, q0)
    T1 = T0.copy()
    T1[2, 3] += 1.0                                          # the lift's stroke ends at 0.6 m
    path = cartesian_line(robot, T0, T1, q0)
    assert not path.success and path.reason == OUTSIDE_JOINT_LIMITS
    assert path.stop == pytest.approx(0.5, abs=0.01)


def test_through_the_wrist_singularity_is_reported_not_jumped():
    qa, qb = np.deg2rad([0, -90, 90, -90, 20, 0]), np.deg2rad([0, -90, 90, -90, -20, 0])
    path = cartesian_line(UR5, armkit.fk(UR5, qa), armkit.fk(UR5, qb), qa)
    assert not path.success and path.reason == SINGULAR
    assert armkit.min_singular_value(UR5, path.q[-1]) < 0.05
    assert np.abs(np.diff(path.q, axis=0)).max() < 0.35


def test_bad_arguments():
    T0 = armkit.fk(UR5, Q0)
    with pytest.raises(InputError, match="step: expected a positive step, found 0"):
        cartesian_line(UR5, T0, T0, Q0, step=0)
    with pytest.raises(InputError, match=r"q0: expected one configuration \(6,\)"):
        cartesian_line(UR5, T0, T0, np.zeros((2, 6)))
    with pytest.raises(InputError, match="T_goal: expected shape"):
        cartesian_line(UR5, T0, np.eye(3), Q0)
