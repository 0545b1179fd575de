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
    units = [t.get_text() for t in fig.axes[4].texts]        # joint 4, the telescope
    assert units == ["mm"]


def test_bad_joint_selection():
    robot, trs = table1()
    with pytest.raises(InputError, match="joints: expected 0-based joint indices"):
        patterns_figure(robot, trs, [6])


@pytest.mark.parametrize("name", ["tool_changer_table1_joints.png",
                                  "tool_changer_table1_tool.png"])
def test_the_shipped_table1_pictures_are_small(name):
    path = ROOT / "docs" / "figures" / name
    assert path.exists() and path.stat().st_size < 400_000
