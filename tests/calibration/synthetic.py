"""Simulated hand-eye data with a known X, for the calibration tests."""

from __future__ import annotations

import cv2
import numpy as np

from armkit.spatial import exp_so3, invert, rotation_angle


def pose(rotvec, p) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = exp_so3(rotvec), p
    return T


def handeye_data(n: int, seed: int, *, noise_rotation: float = 0.0,
                 noise_translation: float = 0.0, mode: str = "eye_in_hand",
                 axis=None, spread: float = 0.5):
    """Robot poses G (T_base_gripper), camera poses C (T_camera_target), the true X and W.

    Eye-in-hand: G X C = W; eye-to-hand: G^-1 X C = W. ``axis``: every robot rotation about
    that one axis (of the base frame). Noise: rad and m on each camera pose (right-multiplied).
    """
    rng = np.random.default_rng(seed)
    X = pose(rng.normal(size=3), rng.normal(size=3) * 0.1)
    W = pose(rng.normal(size=3), [0.8, 0.1, 0.0])
    G, C = [], []
    for _ in range(n):
        rv = rng.normal(size=3) * spread if axis is None else np.asarray(axis) * rng.normal() * 0.8
        Gi = pose(rv, rng.normal(size=3) * 0.2 + [0.5, 0.0, 0.5])
        Ci = invert(Gi @ X) @ W if mode == "eye_in_hand" else invert(X) @ Gi @ W
        noise = pose(rng.normal(size=3) * noise_rotation, rng.normal(size=3) * noise_translation)
        G.append(Gi)
        C.append(Ci @ noise)
    return np.array(G), np.array(C), X, W


def errors(X_est: np.ndarray, X: np.ndarray) -> tuple[float, float]:
    """Rotation (rad) and translation (m) error of an estimate of X."""
    return (float(rotation_angle(X_est[:3, :3].T @ X[:3, :3])),
            float(np.linalg.norm(X_est[:3, 3] - X[:3, 3])))


OPENCV_METHODS = {"tsai": cv2.CALIB_HAND_EYE_TSAI, "park": cv2.CALIB_HAND_EYE_PARK,
                  "horaud": cv2.CALIB_HAND_EYE_HORAUD, "andreff": cv2.CALIB_HAND_EYE_ANDREFF,
                  "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS}


def opencv(G: np.ndarray, C: np.ndarray, method: str, mode: str = "eye_in_hand") -> np.ndarray:
    """OpenCV's calibrateHandEye on the same data (eye-to-hand: the base-to-gripper poses, as
    OpenCV's documentation says)."""
    if mode == "eye_to_hand":
        G = invert(G)
    R, t = cv2.calibrateHandEye(G[:, :3, :3], G[:, :3, 3], C[:, :3, :3], C[:, :3, 3],
                                method=OPENCV_METHODS[method])
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, np.ravel(t)
    return X
