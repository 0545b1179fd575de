"""Points and poses from a camera to the robot's base: fixed mounts and hand-eye results."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.calibration.frames import (
    CameraMount,
    camera_mount,
    camera_to_base,
    point_covariance_in_base,
    points_to_base,
    poses_to_base,
)
from armkit.calibration.handeye import handeye
from armkit.errors import InputError
from armkit.spatial import exp_so3, invert, pose_from_xyz_rpy
from tests.calibration.synthetic import handeye_data, pose


def test_fixed_transform_maps_points_and_poses():
    T = pose_from_xyz_rpy([1.2, 0.0, 0.8], [np.pi, 0, np.pi / 2])
    p = np.array([[0.1, 0.2, 0.5], [0.0, 0.0, 1.0]])
    expected = (T @ np.c_[p, np.ones(2)].T).T[:, :3]
    assert np.allclose(points_to_base(T, p), expected, atol=1e-15)
    assert np.allclose(points_to_base(T, p[0]), expected[0], atol=1e-15)
    obj = pose([0.1, 0.2, 0.3], [0.1, 0.2, 0.5])
    assert np.allclose(poses_to_base(T, obj), T @ obj)
    assert np.allclose(points_to_base(T, np.zeros((2, 4, 3))).shape, (2, 4, 3))


def test_eye_in_hand_result_needs_the_gripper_pose():
    G, C, X, W = handeye_data(8, seed=2)
    result = handeye(G, C)
    target_in_camera = C[3][:3, 3]
    # The target's origin seen from pose 3 is the target's origin in the base frame: W.
    assert np.allclose(points_to_base(result, target_in_camera, G[3]), W[:3, 3], atol=1e-9)
    assert np.allclose(poses_to_base(result, C[5], G[5]), W, atol=1e-9)
    assert np.allclose(camera_to_base(result, G[0]), G[0] @ X, atol=1e-9)
    with pytest.raises(InputError, match="T_base_gripper: expected the robot's pose when the "
                                         "camera measured"):
        points_to_base(result, target_in_camera)


def test_eye_to_hand_result_is_a_fixed_camera():
    G, C, X, W = handeye_data(8, seed=2, mode="eye_to_hand")
    result = handeye(G, C, "eye_to_hand")
    # The target on the gripper at pose 4: G_4 W in the base frame.
    assert np.allclose(points_to_base(result, C[4][:3, 3]), (G[4] @ W)[:3, 3], atol=1e-9)
    with pytest.raises(InputError, match="T_base_gripper: expected none for a eye_to_hand"):
        points_to_base(result, C[4][:3, 3], G[4])


def test_refused_result_cannot_map():
    G, C, _, _ = handeye_data(8, seed=2, axis=[0, 0, 1])
    refused = handeye(G, C)
    with pytest.raises(InputError, match="expected a solved one, found a refusal"):
        camera_mount(refused)


def test_bad_mounts():
    with pytest.raises(InputError, match="T: expected a rotation part that is orthonormal"):
        CameraMount("fixed", np.diag([1.0, 2.0, 1.0, 1.0]))
    with pytest.raises(InputError, match="mount kind: expected fixed"):
        CameraMount("on_the_ceiling", np.eye(4))
    with pytest.raises(InputError, match=r"covariance: expected shape \(\.\.\., 6, 6\)"):
        CameraMount("fixed", np.eye(4), np.eye(5))
    with pytest.raises(InputError, match=r"points: expected shape \(\.\.\., 3\)"):
        points_to_base(np.eye(4), [1.0, 2.0])


def test_uncertainty_is_carried_to_the_base_frame():
    """Propagated covariance of a mapped point matches sampling X from its covariance."""
    rng = np.random.default_rng(7)
    cov = np.diag([1e-4, 2e-4, 5e-5, 1e-6, 4e-6, 2e-6])
    X = pose([0.2, -0.1, 0.4], [0.05, 0.02, 0.1])
    mount = CameraMount("eye_in_hand", X, cov)
    G = pose([0.3, 0.1, -0.2], [0.5, 0.1, 0.6])
    p = np.array([0.1, -0.05, 0.7])
    predicted = point_covariance_in_base(mount, p, G)
    d = rng.multivariate_normal(np.zeros(6), cov, 20000)
    Xs = np.repeat(X[None], len(d), axis=0)
    Xs[:, :3, :3] = X[:3, :3] @ exp_so3(d[:, :3])
    Xs[:, :3, 3] += d[:, 3:]
    sampled = (G @ Xs @ np.r_[p, 1.0])[:, :3]
    assert np.abs(np.cov(sampled.T) - predicted).max() < 0.05 * predicted.max()
    assert np.all(point_covariance_in_base(np.eye(4), p) == 0)


def test_handeye_result_std_carries_into_points():
    G, C, X, W = handeye_data(10, seed=21, noise_rotation=np.deg2rad(0.2),
                              noise_translation=0.001)
    result = handeye(G, C)
    cov = point_covariance_in_base(result, C[0][:3, 3], G[0])
    std = np.sqrt(np.diag(cov))
    assert np.all(std > 1e-5) and np.all(std < 5e-3)
    assert np.allclose(invert(invert(G[0])), G[0])
