"""Calibration pictures: an accuracy report's per-point errors, and a kinematic calibration's
residuals before and after."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from armkit.calibration.accuracy import AccuracyReport
from armkit.calibration.identify import CalibrationResult
from armkit.model.robot import Units

_AXIS_COLORS = ("tab:red", "tab:green", "tab:blue")


def plain(text: str) -> str:
    """Text from a file (a robot's name) as a figure shows it: as written. Matplotlib reads
    text between two dollar signs as math markup (and fails on a name such as
    ``ws$\\frac{$``); escaped dollars are drawn as dollars."""
    return str(text).replace("$", r"\$")


def accuracy_figure(report: AccuracyReport, units: Units) -> Figure:
    """Left: each point's error along x, y and z with the per-axis bias; right: each point's
    error length with its mean, rms and the tolerance (when one was given)."""
    def length(x):          # file units, without the last-bit noise of the mm <-> m round trip
        return np.round(units.length_from_si(x), 9)

    unit = units.length
    e, d = length(report.errors), length(report.distances)
    points = np.arange(1, len(d) + 1)
    fig = Figure(figsize=(12, 4.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    width = 0.8 / 3
    for k, (name, color) in enumerate(zip("xyz", _AXIS_COLORS)):
        left.bar(points + (k - 1) * width, e[:, k], width, color=color, label=f"error {name}")
        left.axhline(float(length(report.bias[k])), color=color, linestyle="--", linewidth=1,
                     label=f"bias {name} = {float(length(report.bias[k])):.3g} {unit}")
    left.axhline(0.0, color="black", linewidth=0.8)
    left.set(xlabel="point", ylabel=f"measured - commanded ({unit})",
             title="error per axis", xticks=points)
    left.legend(fontsize=8, ncols=2)
    right.bar(points, d, 0.6, color="tab:gray", label="error length")
    right.axhline(float(length(report.mean)), color="tab:blue", linestyle="--",
                  label=f"mean {float(length(report.mean)):.3g} {unit}")
    right.axhline(float(length(report.rms)), color="tab:orange", linestyle=":",
                  label=f"rms {float(length(report.rms)):.3g} {unit}")
    if report.tolerance is not None:
        right.axhline(float(length(report.tolerance)), color="tab:red", linewidth=1.5,
                      label=f"limit {float(length(report.tolerance)):.3g} {unit}")
    right.set(xlabel="point", ylabel=f"|measured - commanded| ({unit})",
              title="error length", xticks=points, ylim=(0, None))
    right.legend(fontsize=8)
    return fig


def calibration_figure(result: CalibrationResult, units: Units) -> Figure:
    """Position error per measurement before and after calibration (and on the hold-out set)."""
    unit = units.length
    floor = float(units.length_from_si(1e-9))            # a log axis cannot show an exact 0

    def length(x):
        return np.maximum(units.length_from_si(x), floor)

    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.subplots()
    k = np.arange(1, len(result.residuals_before) + 1)
    ax.plot(k, length(result.residuals_before), "o", color="tab:gray", label="fit set, nominal")
    ax.plot(k, length(result.residuals_after), "o", color="tab:blue", label="fit set, identified")
    if result.holdout_before.size:
        h = np.arange(len(k) + 1, len(k) + 1 + len(result.holdout_before))
        ax.plot(h, length(result.holdout_before), "s", color="tab:gray", mfc="none",
                label="hold-out, nominal")
        ax.plot(h, length(result.holdout_after), "s", color="tab:orange", mfc="none",
                label="hold-out, identified")
    ax.set(xlabel="measurement", ylabel=f"position error ({unit})", yscale="log",
           title=f"{plain(result.robot.name)}: kinematic calibration")
    ax.legend(fontsize=8)
    return fig


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Write a figure as PNG; returns the path."""
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
