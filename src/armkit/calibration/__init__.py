"""Calibration and frames: hand-eye calibration, camera-to-base mapping, kinematic calibration
with identifiability, accuracy reports.

The kinematic calibration's names are loaded on first use (PEP 562): a hand-eye solve does not
import the SciPy that it needs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.calibration.accuracy import AccuracyReport, accuracy_report
from armkit.calibration.frames import (CameraMount, camera_mount, camera_to_base,
                                       point_covariance_in_base, points_to_base, poses_to_base)
from armkit.calibration.handeye import HandEyeResult, handeye
from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.calibration.identify import (CalibrationResult, Identifiability, calibrate,
                                             identifiability, parametric_model, select_poses)

__getattr__, __dir__, __all__ = lazy_names(__name__)

