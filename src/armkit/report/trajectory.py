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
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.model.robot import Robot
from armkit.report.text import figure_text
from armkit.trajectory.piecewise import Trajectory
from armkit.trajectory.tool import ToolMotion

QUANTITIES = ("displacement", "velocity", "acceleration", "jerk")
SUFFIX = ("", "/s", "/s²", "/s³")
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:gray")


def joint_label(robot: Robot, j: int) -> str:
    """``joint 2 (pitch1)``: 1-based number and name, as a figure draws it literally."""
    return f"joint {j + 1} ({figure_text(robot.joint_names[j])})"


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
                    title: str | None = None, vmax: NDArray | None = None,
                    amax: NDArray | None = None) -> Figure:
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
    vmax, amax : ndarray, shape (n,), optional
        Velocity and acceleration limits (SI) drawn as dashed lines in each joint's colour;
        default the robot's. Position limits are drawn when a curve comes within a tenth of
        its range of them.

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
    limits = _limits(robot, vmax, amax)
    fig = Figure(figsize=(4.2 * len(trajectories) + 2.6, 2.8 * rows + 0.1),
                 layout="constrained")
    axes = fig.subplots(rows, len(trajectories), sharex=True, sharey="row", squeeze=False)
    for col, (name, tr) in enumerate(trajectories.items()):
        _joints(robot, joints, tr)
        t, values = _in_file_units(robot, tr, count)
        for row in range(rows):
            ax = axes[row, col]
            for colour, j in zip(COLOURS, joints):
                ax.plot(t, values[row][:, j], color=colour, lw=1.6, label=joint_label(robot, j))
                _draw_limit(ax, limits[row][j], values[row][:, j], colour)
            _knot_lines(ax, tr.knots)
            ax.grid(alpha=0.3)
            if row == 0 and len(trajectories) > 1:
                ax.set_title(figure_text(name))
            if col == 0:
                ax.set_ylabel(f"{QUANTITIES[row]} ({_units(robot, joints, row)})")
            if row == rows - 1:
                ax.set_xlabel("t (s)")
    _legend(fig, axes[0, -1], limits_drawn=_any_drawn(axes))
    if title is None:
        title = f"{robot.name}: " + ", ".join(trajectories)
    elif len(trajectories) == 1:        # one column, untitled: its name in the one title
        title += f" ({next(iter(trajectories))})"
    fig.suptitle(figure_text(title), fontsize=12)
    return fig


def _limits(robot: Robot, vmax: NDArray | None, amax: NDArray | None,
            jmax: NDArray | None = None) -> list[NDArray]:
    """Per quantity (position, velocity, acceleration, jerk) the limits in file units, as
    (n, 2) lower/upper rows; NaN where there is none. Jerk limits are drawn only when given."""
    v = robot.chain.velocity_limits if vmax is None else np.asarray(vmax, dtype=float)
    a = robot.chain.acceleration_limits if amax is None else np.asarray(amax, dtype=float)
    j = np.full(robot.n, np.nan) if jmax is None else np.asarray(jmax, dtype=float)
    scale = robot.q_from_si(np.ones(robot.n))
    position = np.column_stack([robot.q_from_si(robot.lower), robot.q_from_si(robot.upper)])
    out = [position]
    for limit in (v, a, j):
        limit = np.where(np.isfinite(limit), limit * scale, np.nan)
        out.append(np.column_stack([-limit, limit]))
    return [np.where(np.isfinite(x), x, np.nan) for x in out]


_LIMIT_STYLE = {"ls": "--", "lw": 1.0, "alpha": 0.8}


def _knot_lines(ax, knots: NDArray) -> None:
    """Dotted vertical lines at the knot times (s), as one collection: one artist per knot
    would be drawn, and measured for the layout, one by one in every panel."""
    ax.vlines(knots, 0.0, 1.0, transform=ax.get_xaxis_transform(), colors="0.6", lw=0.8,
              linestyles=":")


def _draw_limit(ax, bounds: NDArray, values: NDArray, colour: str,
                label: str | None = None) -> bool:
    """Dashed lines at a joint's limits (file units) where the curve comes within a tenth of
    its span of them, or goes beyond; the other limit lines would only squash the curves."""
    drawn = False
    near = 0.1 * max(float(np.ptp(values)), 1e-12)
    lower, upper = bounds
    for bound, reached in ((lower, values.min() <= lower + near),
                           (upper, values.max() >= upper - near)):
        if np.isfinite(bound) and reached:
            ax.axhline(bound, color=colour, label=label, **_LIMIT_STYLE)
            drawn, label = True, None
    return drawn


def _any_drawn(axes) -> bool:
    return any(line.get_linestyle() == "--" and len(set(line.get_ydata())) == 1
               for ax in np.ravel(axes) for line in ax.get_lines())


def _legend(fig: Figure, ax, limits_drawn: bool) -> None:
    """One legend outside the panels: the lines of `ax`, and the limit style if drawn."""
    from matplotlib.lines import Line2D

    handles, labels = [], []
    for line in ax.get_lines():
        label = line.get_label()
        if not label.startswith("_") and label not in labels and line.get_linestyle() != "--":
            handles.append(line)
            labels.append(label)
    if limits_drawn:
        handles.append(Line2D([], [], color="0.3", **_LIMIT_STYLE))
        labels.append("limit (dashed, joint's colour)")
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8,
              borderaxespad=0.0)


def motion_figure(robot: Robot, tr: Trajectory, joints: Sequence[int] | None = None, *,
                  count: int = 600, title: str | None = None, vmax: NDArray | None = None,
                  amax: NDArray | None = None, jmax: NDArray | None = None) -> Figure:
    """Position, velocity, acceleration and jerk (columns) of each chosen joint (rows).

    Each panel's y axis names the quantity and its unit; the joint's position limits and its
    velocity, acceleration and jerk limits (`vmax`, `amax` SI, default the robot's; `jmax` SI,
    drawn only when given) are dashed lines where the curve comes near them.
    """
    joints = _joints(robot, joints, tr)
    t, values = _in_file_units(robot, tr, count)
    limits = _limits(robot, vmax, amax, jmax)
    fig = Figure(figsize=(15, 2.1 * len(joints) + 1.2), layout="constrained")
    axes = fig.subplots(len(joints), len(QUANTITIES), sharex=True, squeeze=False)
    for row, j in enumerate(joints):
        colour = COLOURS[row % len(COLOURS)]
        for col in range(len(QUANTITIES)):
            ax = axes[row, col]
            ax.plot(t, values[col][:, j], color=colour, lw=1.4, label=joint_label(robot, j))
            _draw_limit(ax, limits[col][j], values[col][:, j], "tab:red", label="limit")
            _knot_lines(ax, tr.knots)
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(QUANTITIES[col])
            ax.set_ylabel(f"{joint_label(robot, j)}\n({joint_unit(robot, j)}{SUFFIX[col]})"
                          if col == 0 else f"{joint_unit(robot, j)}{SUFFIX[col]}", fontsize=9)
            if any(line.get_label() == "limit" for line in ax.get_lines()):
                ax.legend(loc="best", fontsize=7)
            if row == len(joints) - 1:
                ax.set_xlabel("t (s)")
    fig.suptitle(figure_text(title or f"{robot.name}: {tr.label}, {tr.duration:.4g} s (dashed: "
                             f"the limits a curve comes near)"), fontsize=12)
    return fig


def tool_figure(robot: Robot, motions: Mapping[str, ToolMotion], *,
                title: str | None = None, yaw: bool = False) -> Figure:
    """The tool's position, linear velocity and linear acceleration (rows) per motion (columns).

    Components x, y, z in the base frame and, for velocity and acceleration, the magnitude; in
    the robot file's length unit. With `yaw` (a position + yaw task), a fourth row draws the
    tool's yaw (the heading of its x axis about the base z axis) in the file's angle unit.
    """
    if not motions:
        raise InputError("motions: expected at least one, found none")
    unit, angle = robot.units.length, robot.units.angle
    rows = 4 if yaw else 3
    fig = Figure(figsize=(4.2 * len(motions) + 2.4, 2.7 * rows + 0.4), layout="constrained")
    axes = fig.subplots(rows, len(motions), sharex=True, sharey="row", squeeze=False)
    labels = ("position", "velocity", "acceleration")
    for col, (name, m) in enumerate(motions.items()):
        data_rows = (m.position, m.velocity[:, :3], m.acceleration[:, :3])
        for row, data in enumerate(data_rows):
            ax = axes[row, col]
            data = robot.units.length_from_si(data)
            for i, axis in enumerate("xyz"):
                ax.plot(m.t, data[:, i], color=COLOURS[i], lw=1.5, label=axis)
            if row:
                ax.plot(m.t, np.linalg.norm(data, axis=1), color="k", lw=1.2, ls="-.",
                        label="magnitude")
            if col == 0:
                ax.set_ylabel(f"tool {labels[row]} ({unit}{SUFFIX[row]})")
            if len(motions) > 1 and row == 0:
                ax.set_title(figure_text(name))
            ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8,
                      borderaxespad=0.0) if col == len(motions) - 1 else None
        if yaw:
            ax = axes[3, col]
            heading = np.unwrap(np.arctan2(m.pose[:, 1, 0], m.pose[:, 0, 0]))
            ax.plot(m.t, robot.units.angle_from_si(heading), color=COLOURS[4], lw=1.5,
                    label="yaw")
            if col == 0:
                ax.set_ylabel(f"tool yaw ({angle})")
            if col == len(motions) - 1:
                ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8,
                          borderaxespad=0.0)
        for ax in axes[:, col]:
            ax.grid(alpha=0.3)
        axes[-1, col].set_xlabel("t (s)")
    only = next(iter(motions)) if len(motions) == 1 else None
    fig.suptitle(figure_text(title or (f"{robot.name}: tool motion ({only}), base frame" if only
                                       else f"{robot.name}: tool motion, base frame")),
                 fontsize=12)
    return fig
