"""Trajectory case files: read into trajectories, limits checked, mistakes named."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.errors import InputError, ModelFileError
from armkit.io.trajectory_cases import limit_excesses, read_case


def test_a_point_to_point_case_within_limits_has_no_excess():
    case = read_case("inspection_6dof", {"start": [0] * 6, "goal": [30, -45, 60, 0, 90, 0],
                                         "profiles": ["trapezoidal"]})
    assert case.moving == [0, 1, 2, 4] and not case.via and case.source == ""
    assert limit_excesses(case) == []


def test_a_quintic_too_short_exceeds_by_the_law_s_factors():
    case = read_case("inspection_6dof", {"start": [0] * 6, "goal": [30, 0, 0, 0, 0, 0],
                                         "duration": 0.5})
    velocity, acceleration = limit_excesses(case)
    # 10-15-6 law: peak velocity 1.875 d / T at T / 2, peak acceleration 10 / sqrt(3) d / T^2.
    d = np.deg2rad(30)
    assert velocity.quantity == "velocity" and velocity.joint == 0
    assert velocity.peak == pytest.approx(1.875 * d / 0.5, rel=1e-12)
    assert velocity.limit == pytest.approx(np.deg2rad(90))
    assert velocity.time == pytest.approx(0.25, abs=0.5 / 256)
    assert acceleration.peak == pytest.approx(10 / np.sqrt(3) * d / 0.25, rel=1e-12)
    assert acceleration.ratio == pytest.approx(acceleration.peak / np.deg2rad(180))


def test_a_case_file_and_its_mistakes(tmp_path):
    path = tmp_path / "case.yaml"
    path.write_text("robot: modular_4dof\njoints: [1]\ntimes: [0, 1, 2]\n"
                    "points: [[0], [80], [0]]\npatterns: [5-5]\n")
    case = read_case(str(path))
    assert case.via and case.source == str(path) and list(case.trajectories) == ["5-5"]
    path.write_text("robot: modular_4dof\njoints: [1]\ntimes: [0, 1, 2]\n"
                    "points: [[0], [800], [0]]\n")
    with pytest.raises(InputError, match=r"points\[1\]: expected joint 1 \(yaw\) within its "
                                         r"limits -90 \.\. 90 deg, found 800"):
        read_case(str(path))
    path.write_text("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [.nan, 0, 0, 0, 0, 0]\n")
    with pytest.raises(ModelFileError, match="goal"):
        read_case(str(path))
    path.write_text("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [0, 0, 0, 0, 0, 0]\n")
    with pytest.raises(InputError, match="goal: expected a configuration other than the start"):
        read_case(str(path))
