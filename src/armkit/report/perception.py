"""The picture of a detection: the cloud along the wall, the target cluster and its circle, and a
side view of the heights above the wall. Lengths in the cloud file's units."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle as CirclePatch
from matplotlib.patches import Rectangle

from armkit.perception.synthetic import target_frame
from armkit.report.calibration import plain
from armkit.perception.target import TargetResult

SHOWN = 30_000          # points drawn at most per layer (the rest adds ink, not information)
_SCALE = {"m": 1.0, "mm": 1e3}


def _thin(mask: np.ndarray) -> np.ndarray:
    idx = np.flatnonzero(mask)
    return idx[::max(len(idx) // SHOWN, 1)]


def detection_figure(result: TargetResult) -> Figure:
    """Three panels: the whole cloud along the wall (wall inliers, candidates, the target
    cluster), the target close up with the fitted circle, its centre and the naive centroid,
    and the heights above the wall beside the target.

    Parameters
    ----------
    result : TargetResult

    Returns
    -------
    Figure
    """
    unit = result.file_units
    k = _SCALE.get(unit, 1.0)
    p = result.points
    fig = Figure(figsize=(17, 5.4), layout="constrained")
    axes = fig.subplots(1, 3, width_ratios=(1.2, 1, 1))
    plane = result.plane
    if plane is None or not plane.inliers.any():
        axes[0].scatter(p[:, 1] * k, p[:, 2] * k, s=0.5, color="0.6", rasterized=True,
                        label="cloud (sensor y, z)")
        axes[0].set_xlabel(f"sensor y ({unit})")
        axes[0].set_ylabel(f"sensor z ({unit})")
        axes[0].legend(loc="upper right")
        for ax in axes[1:]:
            ax.set_axis_off()
        fig.suptitle(plain(textwrap.fill(f"no target: {result.reason}", 160)))
        return fig
    T_wall = target_frame(plane.normal, -plane.offset * plane.normal)
    u, v, n = T_wall[:3, 0], T_wall[:3, 1], T_wall[:3, 2]
    xy = np.column_stack([p @ u, p @ v]) * k
    h = (p @ n + plane.offset) * k
    layers = [(plane.inliers & ~result.cluster_mask, "0.65", 0.4, "wall inliers"),
              (~plane.inliers & ~result.candidate_mask & ~result.cluster_mask, "tab:purple", 1.5,
               "other points (outliers, behind the wall)"),
              (result.candidate_mask & ~result.cluster_mask, "tab:orange", 3,
               "candidates off the wall"),
              (result.cluster_mask, "tab:blue", 3,
               "target cluster" if result.kind == "pipe" else "rim (wall points)")]
    ax = axes[0]
    for mask, colour, size, label in layers:
        idx = _thin(mask)
        ax.scatter(xy[idx, 0], xy[idx, 1], s=size, color=colour, linewidths=0, rasterized=True,
                   label=f"{label} ({int(mask.sum()):,})")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"along the wall, u ({unit})")
    ax.set_ylabel(f"along the wall, v ({unit})")
    ax.set_title(f"cloud along the fitted wall (RMS {plane.rms * k:.3g} {unit})")
    ok = result.success
    if ok:
        c = np.array([result.centre @ u, result.centre @ v]) * k
        r = result.radius * k
        ax.add_patch(Rectangle((c[0] - 3 * r, c[1] - 3 * r), 6 * r, 6 * r, fill=False,
                               color="tab:red", lw=1, label="close-up"))
    ax.legend(loc="upper right", fontsize=7)

    ax = axes[1]
    near = result.cluster_mask | result.candidate_mask
    if ok:
        near = near | (np.abs(xy[:, 0] - c[0]) < 3 * r) & (np.abs(xy[:, 1] - c[1]) < 3 * r)
    for mask, colour, size, label in layers:
        idx = _thin(mask & near)
        ax.scatter(xy[idx, 0], xy[idx, 1], s=size * 2, color=colour, linewidths=0,
                   rasterized=True, label=label)
    if ok:
        ax.add_patch(CirclePatch(c, r, fill=False, color="tab:red", lw=1.5,
                                 label=f"fitted circle, r = {r:.4g} {unit}"
                                       + (" (known)" if result.radius_known else "")))
        ax.scatter(*c, marker="+", s=80, color="tab:red", label="centre", zorder=4)
        if np.isfinite(result.centroid).all():
            g = np.array([result.centroid @ u, result.centroid @ v]) * k
            ax.scatter(*g, marker="x", s=40, color="k", zorder=4,
                       label="cluster centroid (biased)")
        ax.set_xlim(c[0] - 3 * r, c[0] + 3 * r)
        ax.set_ylim(c[1] - 3 * r, c[1] + 3 * r)
    ax.set_aspect("equal")
    ax.set_xlabel(f"u ({unit})")
    ax.set_ylabel(f"v ({unit})")
    ax.set_title("target close up" if ok else "candidates")
    ax.legend(loc="upper right", fontsize=7)

    ax = axes[2]
    for mask, colour, size, label in layers:
        idx = _thin(mask & near)
        ax.scatter(xy[idx, 0], h[idx], s=size * 2, color=colour, linewidths=0, rasterized=True,
                   label=label)
    ax.axhline(0.0, color="0.3", lw=1, label="wall (fitted plane)")
    if ok:
        height = (result.centre @ n + plane.offset) * k
        if result.kind == "pipe":
            ax.axhline(height, color="tab:red", lw=1, ls="--", label=f"mouth, {height:.4g} {unit}")
        ax.axvline(c[0] - r, color="tab:red", lw=0.8, ls=":", label="circle's extent")
        ax.axvline(c[0] + r, color="tab:red", lw=0.8, ls=":")
        ax.set_xlim(c[0] - 3 * r, c[0] + 3 * r)
        top = max(float(h[result.cluster_mask].max(initial=0.0)), 2 * r)
        ax.set_ylim(-2 * r, top + 2 * r)
    ax.set_xlabel(f"u ({unit})")
    ax.set_ylabel(f"height above the wall ({unit})")
    ax.set_title("side view")
    ax.legend(loc="upper right", fontsize=7)
    title = (f"{result.kind} found: centre ({', '.join(f'{x:.4g}' for x in result.centre * k)}) "
             f"{unit} in the sensor frame" if ok else f"no target: {result.reason}")
    fig.suptitle(plain(textwrap.fill(title, 160)))
    return fig


def save_detection_figure(result: TargetResult, folder: Path, stem: str = "detection") -> Path:
    """Write `detection_figure(result)` as folder/stem.png; returns the path."""
    path = Path(folder) / f"{stem}.png"
    detection_figure(result).savefig(path, dpi=110)
    return path
