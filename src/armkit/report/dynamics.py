"""Figures of joint torques: each joint's torque over time with its limits drawn.

`torque_figure` returns a `matplotlib.figure.Figure`; ``fig.savefig("torques.png")`` writes it.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from armkit.dynamics.torques import TorqueProfile
from armkit.model.robot import Robot
from armkit.report.text import figure_text
from armkit.report.trajectory import COLOURS, joint_label


def torque_figure(robot: Robot, profiles: TorqueProfile | Mapping[str, TorqueProfile], *,
                  title: str | None = None) -> Figure:
    """Joint torques over time, one panel per joint, the torque limits as dashed lines.

    Parameters
    ----------
    robot : Robot
        Gives the joints' names and kinds (N m for revolute, N for prismatic joints).
    profiles : TorqueProfile or mapping of str to TorqueProfile
        From `armkit.dynamics.torque_profile`; several (one per motion, by label) share the
        panels.
    title : str, optional

    Returns
    -------
    Figure
        A joint's panel shows its limit where the profile has one, and marks each profile's
        peak; a torque beyond the limit is drawn in red.

    Example
    -------
    >>> ur5 = armkit.robot("ur5")
    >>> move = armkit.quintic(np.zeros(6), np.deg2rad([90, -90, 90, 0, 0, 0]), 2.0)
    >>> fig = torque_figure(ur5, armkit.torque_profile(ur5, move))
    >>> len(fig.axes)
    6
    """
    if isinstance(profiles, TorqueProfile):
        profiles = {"": profiles}
    n = robot.n
    columns = 2 if n > 3 else 1
    rows = -(-n // columns)
    fig = Figure(figsize=(6.0 * columns, 1.9 * rows + 0.8), layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False, sharex=True).ravel()
    for j in range(n):
        ax = axes[j]
        unit = "N m" if robot.chain.revolute[j] else "N"
        limit = np.inf
        for k, (label, p) in enumerate(profiles.items()):
            colour = COLOURS[k % len(COLOURS)]
            ax.plot(p.t, p.torque[:, j], color=colour, lw=1.2, label=figure_text(label) if label else None)
            beyond = np.abs(p.torque[:, j]) > p.limits[j]
            if beyond.any():
                ax.plot(p.t[beyond], p.torque[beyond, j], ".", color="tab:red", ms=2)
            at = int(np.argmax(np.abs(p.torque[:, j])))
            ax.plot(p.t[at], p.torque[at, j], "o", color=colour, ms=4)
            limit = min(limit, p.limits[j])
        if np.isfinite(limit):
            for sign in (1, -1):
                ax.axhline(sign * limit, color="black", ls="--", lw=0.9,
                           label="limit" if sign == 1 else None)
        ax.axhline(0.0, color="0.8", lw=0.6)
        ax.set_title(joint_label(robot, j), fontsize=9, loc="left")
        ax.set_ylabel(f"torque ({unit})")
        ax.grid(alpha=0.3)
    for ax in axes[n:]:
        ax.set_visible(False)
    for ax in axes[max(n - columns, 0):n]:
        ax.set_xlabel("t (s)")
    handles, labels = axes[0].get_legend_handles_labels()
    if labels:
        fig.legend(handles, labels, loc="outside lower center", ncols=len(labels),
                   fontsize=8)
    fig.suptitle(figure_text(title or f"{robot.name}: joint torques"), fontsize=11)
    return fig
