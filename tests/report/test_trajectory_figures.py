"""Trajectory figures: drawn without pyplot, axes in the robot file's units, PNGs written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

import armkit
from armkit.errors import InputError
from armkit.report.trajectory import motion_figure, patterns_figure, tool_figure
from armkit.trajectory import patterns, quintic, tool_motion

ROOT = Path(__file__).resolve().parents[2]


def table1():
    robot = armkit.robot("tool_changer_6dof")
    q = np.zeros((4, 6))
    q[:, [1, 2, 4]] = [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    return robot, patterns([0, 2, 4, 5], robot.q_to_si(q))


def test_patterns_figure_is_three_quantities_by_three_patterns(tmp_path):
    robot, trs = table1()
    fig = patterns_figure(robot, trs, [1, 2, 4])
    assert isinstance(fig, Figure) and len(fig.axes) == 9
    axes = np.array(fig.axes).reshape(3, 3)
    assert [ax.get_title() for ax in axes[0]] == ["3-3-3", "4-5-5", "5-5-5"]
    assert axes[0, 0].get_ylabel() == "displacement (deg)"
    assert axes[2, 0].get_ylabel() == "acceleration (deg/s²)"
    x, y = axes[0, 0].lines[0].get_data()                 # joint 2 in degrees, from 50.4
    assert y[0] == pytest.approx(50.4) and y[-1] == pytest.approx(27.0)
    fig.savefig(tmp_path / "p.png")
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_motion_and_tool_figures(tmp_path):
    robot, trs = table1()
    fig = tool_figure(robot, {k: tool_motion(robot, v) for k, v in trs.items()})
    assert len(fig.axes) == 9 and fig.axes[0].get_ylabel() == "tool position (mm)"
    fig.savefig(tmp_path / "t.png")
    tr = quintic(np.zeros(6), robot.q_to_si([0, 30, -20, 400, 10, 0]), 4.0)
    fig = motion_figure(robot, tr, [1, 3])
    assert len(fig.axes) == 8
    # Units are axis labels, not text over the curves.
    assert fig.axes[4].get_ylabel() == "joint 4 (telescope)\n(mm)"      # the telescope
    assert [ax.get_ylabel() for ax in fig.axes[5:]] == ["mm/s", "mm/s²", "mm/s³"]
    assert all(not ax.texts for ax in fig.axes)


def _dashed_levels(ax) -> list[float]:
    return sorted(float(line.get_ydata()[0]) for line in ax.get_lines()
                  if line.get_linestyle() == "--")


def _to_the_inlet():
    """The water-supply arm's quintic from rest to the inlet at (1000, 300, 800) mm, yaw 30 deg
    (the nearest solution), as short as its limits allow."""
    from armkit.spatial import pose_from_xyz_rpy

    robot = armkit.robot("water_supply")
    q0 = np.array([0.05, 0.0, 0.5, -0.5])
    sols = armkit.ik_solutions(robot, pose_from_xyz_rpy([1.0, 0.3, 0.8], [0, 0, np.pi / 6]))
    qf = sols.q[np.argmin(np.linalg.norm(sols.q - q0, axis=1))]
    return robot, armkit.quintic(q0, qf, vmax=robot.velocity_limits,
                                 amax=robot.acceleration_limits)


def test_the_inlet_joint_figure_draws_the_velocity_limit_the_lift_reaches():
    robot, trajectory = _to_the_inlet()
    fig = motion_figure(robot, trajectory)
    axes = np.array(fig.axes).reshape(robot.n, 4)
    # The quintic is as short as the lift's 200 mm/s allows: its peak touches the limit.
    assert _dashed_levels(axes[0, 1]) == [pytest.approx(200.0)]
    assert "limit" in [t.get_text() for t in axes[0, 1].get_legend().get_texts()]
    # The swing that moves 4 deg is far from its limits: no line squashes its curve.
    assert _dashed_levels(axes[1, 1]) == []


def test_the_tool_figure_has_a_legend_and_draws_the_yaw_of_a_yaw_task():
    robot, trajectory = _to_the_inlet()
    motion = tool_motion(robot, trajectory.sample_uniform(200))
    fig = tool_figure(robot, {"quintic": motion}, yaw=True)
    assert len(fig.axes) == 4
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["x", "y", "z"]
    assert fig.axes[3].get_ylabel() == "tool yaw (deg)"
    yaw = fig.axes[3].lines[0].get_ydata()
    assert yaw[-1] == pytest.approx(30.0, abs=1e-6)        # the inlet's heading, deg
    assert "quintic" in fig._suptitle.get_text()


def test_patterns_figure_draws_limits_it_comes_near_and_says_so_in_the_legend():
    robot, trs = table1()
    fig = patterns_figure(robot, trs, [1, 2, 4], amax=robot.q_to_si(np.full(6, 60.0)))
    axes = np.array(fig.axes).reshape(3, 3)
    assert _dashed_levels(axes[2, 0]) == [pytest.approx(-60.0)]     # 3-3-3 steps to -55
    labels = [t.get_text() for t in axes[0, -1].get_legend().get_texts()]
    assert labels[-1].startswith("limit") and "joint 2 (pitch1)" in labels


def test_bad_joint_selection():
    robot, trs = table1()
    with pytest.raises(InputError, match="joints: expected 0-based joint indices"):
        patterns_figure(robot, trs, [6])


@pytest.mark.parametrize("name", ["tool_changer_table1_joints.png",
                                  "tool_changer_table1_tool.png"])
def test_the_shipped_table1_pictures_are_small(name):
    path = ROOT / "docs" / "figures" / name
    assert path.exists() and path.stat().st_size < 400_000


def test_a_limit_the_curve_goes_far_beyond_is_drawn():
    robot = armkit.robot("ur5")
    tr = quintic(np.zeros(6), robot.q_to_si([90, 0, 0, 0, 0, 0]), 0.1)     # 1688 deg/s
    fig = motion_figure(robot, tr, [0])
    velocity = fig.axes[1]
    assert _dashed_levels(velocity) == [pytest.approx(180.0)]
    assert max(velocity.lines[0].get_ydata()) > 9 * 180
