"""Calibration and frames: hand-eye calibration, camera-to-base mapping, kinematic calibration
with identifiability, accuracy reports."""

from armkit.calibration.accuracy import AccuracyReport, accuracy_report
from armkit.calibration.frames import (
                                       CameraMount,
                                       camera_mount,
                                       camera_to_base,
                                       point_covariance_in_base,
                                       points_to_base,
                                       poses_to_base,
)
from armkit.calibration.handeye import HandEyeResult, handeye
from armkit.calibration.identify import (
                                       CalibrationResult,
                                       Identifiability,
                                       calibrate,
                                       identifiability,
                                       parametric_model,
                                       select_poses,
)

__all__ = ["AccuracyReport", "accuracy_report", "CameraMount", "camera_mount", "camera_to_base",
           "point_covariance_in_base", "points_to_base", "poses_to_base", "HandEyeResult",
           "handeye", "CalibrationResult", "Identifiability", "calibrate", "identifiability",
           "parametric_model", "select_poses"]
