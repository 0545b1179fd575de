"""Figures of joint trajectories and of the tool's motion, in the robot file's units.

- `patterns_figure`: displacement, velocity and acceleration (and jerk) of chosen joints (rows)
  for each spline pattern or profile (columns), as the tool-changer paper's figures 5 to 7;
- `motion_figure`: position, velocity, acceleration and jerk of each joint of one trajectory;
- `tool_figure`: the tool's position, velocity and acceleration per pattern (paper figure 9).

Each returns a `matplotlib.figure.Figure`; ``fig.savefig("name.png")`` writes it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from armkit.errors import InputError
from armkit.model.robot import Robot
from armkit.trajectory.piecewise import Trajectory
from armkit.trajectory.tool import ToolMotion

QUANTITIES = ("displacement", "velocity", "acceleration", "jerk")
SUFFIX = ("", "/s", "/s²", "/s³")
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:gray")


def joint_label(robot: Robot, j: int) -> str:
    """``joint 2 (pitch1)``: 1-based number and name."""
    return f"joint {j + 1} ({robot.joint_names[j]})"


def joint_unit(robot: Robot, j: int) -> str:
    """The file unit of joint j's value: the angle unit or the length unit."""
    return robot.joint_units[j]


def _units(robot: Robot, joints: Sequence[int], order: int) -> str:
    units = dict.fromkeys(joint_unit(robot, j) for j in joints)
    return ", ".join(u + SUFFIX[order] for u in units)


def _joints(robot: Robot, joints: Sequence[int] | None, tr: Trajectory) -> list[int]:
    if tr.n != robot.n:
        raise InputError(f"trajectory: expected {robot.n} joints (the joints of {robot.name}), "
                         f"found {tr.n}")
    joints = list(range(robot.n)) if joints is None else [int(j) for j in joints]
    if not joints or not all(0 <= j < robot.n for j in joints):
        raise InputError(f"joints: expected 0-based joint indices below {robot.n}, "
                         f"found {joints}")
    return joints


def _in_file_units(robot: Robot, tr: Trajectory, count: int):
    s = tr.sample_uniform(count)
    return s.t, [robot.q_from_si(s.derivative(r)) for r in range(len(QUANTITIES))]


def patterns_figure(robot: Robot, trajectories: Mapping[str, Trajectory],
                    joints: Sequence[int] | None = None, *, rows: int = 3, count: int = 600,
                    title: str | None = None) -> Figure:
    """Displacement, velocity, acceleration (rows) of chosen joints, one column per trajectory.

    Parameters
    ----------
    robot : Robot
        Gives the joints' names and the file units the axes use.
    trajectories : mapping of str to Trajectory
        E.g. `armkit.trajectory.patterns(...)`: ``{"3-3-3": ..., "4-5-5": ..., "5-5-5": ...}``,
        each over all of the robot's joints.
    joints : sequence of int, optional
        0-based indices of the joints to draw (the paper's joints 2, 3, 5 are ``[1, 2, 4]``);
        default all.
    rows : {3, 4}
        4 adds jerk.
    count : int
        Samples per curve.

    Returns
    -------
    matplotlib.figure.Figure
        Rows share their y axis, so the patterns compare at a glance; dotted lines mark knots.
    """
    if not trajectories:
        raise InputError("trajectories: expected at least one, found none")
    if rows not in (3, 4):
        raise InputError(f"rows: expected 3 or 4, found {rows!r}")
    first = next(iter(trajectories.values()))
    joints = _joints(robot, joints, first)
    fig = Figure(figsize=(4.2 * len(trajectories) + 1, 2.8 * rows + 0.1), layout="constrained")
    axes = fig.subplots(rows, len(trajectories), sharex=True, sharey="row", squeeze=False)
    for col, (name, tr) in enumerate(trajectories.items()):
        _joints(robot, joints, tr)
        t, values = _in_file_units(robot, tr, count)
        for row in range(rows):
            ax = axes[row, col]
            for colour, j in zip(COLOURS, joints):
                ax.plot(t, values[row][:, j], color=colour, lw=1.6, label=joint_label(robot, j))
            for knot in tr.knots:
                ax.axvline(knot, color="0.6", lw=0.8, ls=":")
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(name)
            if col == 0:
                ax.set_ylabel(f"{QUANTITIES[row]} ({_units(robot, joints, row)})")
            if row == rows - 1:
                ax.set_xlabel("t (s)")
    axes[0, 0].legend(loc="best", fontsize=8)
    fig.suptitle(title or f"{robot.name}: " + ", ".join(trajectories), fontsize=12)
    return fig


def motion_figure(robot: Robot, tr: Trajectory, joints: Sequence[int] | None = None, *,
                  count: int = 600, title: str | None = None) -> Figure:
    """Position, velocity, acceleration and jerk (columns) of each chosen joint (rows)."""
    joints = _joints(robot, joints, tr)
    t, values = _in_file_units(robot, tr, count)
    fig = Figure(figsize=(14, 1.9 * len(joints) + 1.2), layout="constrained")
    axes = fig.subplots(len(joints), len(QUANTITIES), sharex=True, squeeze=False)
    for row, j in enumerate(joints):
        for col in range(len(QUANTITIES)):
            ax = axes[row, col]
            ax.plot(t, values[col][:, j], color=COLOURS[row % len(COLOURS)], lw=1.4)
            for knot in tr.knots:
                ax.axvline(knot, color="0.6", lw=0.8, ls=":")
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(QUANTITIES[col])
            if col == 0:
                ax.set_ylabel(joint_label(robot, j), fontsize=9)
            ax.annotate(joint_unit(robot, j) + SUFFIX[col], (0.99, 0.96),
                        xycoords="axes fraction", ha="right", va="top", fontsize=8,
                        color="0.35")
            if row == len(joints) - 1:
                ax.set_xlabel("t (s)")
    fig.suptitle(title or f"{robot.name}: {tr.label}, {tr.duration:.4g} s", fontsize=12)
    return fig


def tool_figure(robot: Robot, motions: Mapping[str, ToolMotion], *,
                title: str | None = None) -> Figure:
    """The tool's position, linear velocity and linear acceleration (rows) per motion (columns).

    Components x, y, z in the base frame and, for velocity and acceleration, the magnitude; in
    the robot file's length unit.
    """
    if not motions:
        raise InputError("motions: expected at least one, found none")
    unit = robot.units.length
    fig = Figure(figsize=(4.2 * len(motions) + 1, 8.5), layout="constrained")
    axes = fig.subplots(3, len(motions), sharex=True, sharey="row", squeeze=False)
    labels = ("position", "velocity", "acceleration")
    for col, (name, m) in enumerate(motions.items()):
        rows = (m.position, m.velocity[:, :3], m.acceleration[:, :3])
        for row, data in enumerate(rows):
            ax = axes[row, col]
            data = robot.units.length_from_si(data)
            for i, axis in enumerate("xyz"):
                ax.plot(m.t, data[:, i], color=COLOURS[i], lw=1.5, label=axis)
            if row:
                ax.plot(m.t, np.linalg.norm(data, axis=1), color="k", lw=1.2, ls="--",
                        label="magnitude")
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(name)
            if col == 0:
                ax.set_ylabel(f"tool {labels[row]} ({unit}{SUFFIX[row]})")
            if row == 2:
                ax.set_xlabel("t (s)")
    axes[1, 0].legend(loc="best", fontsize=8)
    fig.suptitle(title or f"{robot.name}: tool motion, base frame", fontsize=12)
    return fig
