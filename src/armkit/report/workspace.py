"""Workspace pictures: the point cloud in 3-D with its XY, XZ and YZ projections, and sections.

Lengths on the axes are in the units given (the robot file's by default); projections and
sections keep x, y and z to one scale.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Rectangle
from matplotlib.ticker import MaxNLocator

from armkit.model.robot import Units
from armkit.report.text import figure_text
from armkit.sampled_workspace import Workspace

_POINT = {"s": 0.6, "alpha": 0.35, "linewidths": 0, "color": "tab:blue", "rasterized": True}
_BASE = {"marker": "+", "color": "tab:red", "s": 60, "linewidths": 1.2, "zorder": 3}
_PROJECTIONS = (("x", "y", 0, 1), ("x", "z", 0, 2), ("y", "z", 1, 2))
_REACH = {"color": "tab:red", "ls": "--", "lw": 1.0, "alpha": 0.8}


def workspace_figure(ws: Workspace, units: Units | None = None) -> Figure:
    """The tool positions of `ws.cloud` in 3-D, then projected on XY, XZ and YZ.

    Parameters
    ----------
    ws : Workspace
    units : Units or None
        Length unit of the axes; the robot file's units if None.

    Returns
    -------
    Figure
        Four panels side by side; the base origin marked with a red cross.
    """
    units = ws.robot.units if units is None else units
    p = units.length_from_si(ws.cloud)
    unit = units.length
    fig = Figure(figsize=(18, 4.8), layout="constrained")
    grid = fig.add_gridspec(1, 4, width_ratios=(1.25, 1, 1, 1))
    ax = fig.add_subplot(grid[0], projection="3d")
    ax.scatter(p[:, 0], p[:, 1], p[:, 2], c=p[:, 2], cmap="viridis", s=1.0, alpha=0.6,
               linewidths=0, rasterized=True)
    ax.scatter([0], [0], [0], **_BASE)
    span = np.ptp(p, axis=0) if len(p) else np.ones(3)
    ax.set_box_aspect(np.maximum(span, 1e-9 + span.max() * 0.05), zoom=0.9)
    for axis, name in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz"):
        axis.set_major_locator(MaxNLocator(4))
        axis.set_label_text(f"{name} ({unit})")
    ax.tick_params(labelsize=7)
    ax.set_title("3-D cloud (colour: z)")
    for k, (u, v, i, j) in enumerate(_PROJECTIONS, start=1):
        ax = fig.add_subplot(grid[k])
        ax.scatter(p[:, i], p[:, j], label="tool positions", **_POINT)
        ax.scatter([0], [0], label="base origin", **_BASE)
        # The reach bounds every projection: the largest distance from the base origin, and
        # on XY the largest distance from the base z axis.
        radius = float(units.length_from_si(ws.radial_reach if k == 1 else ws.reach))
        ax.add_patch(Circle((0.0, 0.0), radius, fill=False, label="reach"
                            if k != 1 else "reach from the z axis", **_REACH))
        ax.set_aspect("equal", adjustable="datalim")
        ax.xaxis.set_major_locator(MaxNLocator(5))
        ax.yaxis.set_major_locator(MaxNLocator(5))
        ax.set_xlabel(f"{u} ({unit})")
        ax.set_ylabel(f"{v} ({unit})")
        ax.set_title(f"{u.upper()}{v.upper()} projection")
        ax.grid(alpha=0.3)
        ax.legend(handles=[
            Line2D([], [], marker=".", ls="", color=_POINT["color"], label="tool positions"),
            Line2D([], [], marker="+", ls="", color=_BASE["color"], ms=8, label="base origin"),
            Line2D([], [], label="reach from the z axis" if k == 1 else "reach", **_REACH)],
            loc="upper right", fontsize=7)
    fig.suptitle(f"{figure_text(ws.robot.name)}: workspace of the tool origin, "
                 f"{ws.samples:,} samples (showing {len(p):,})")
    return fig


def default_height(ws: Workspace) -> float:
    """Height of the default horizontal section (m): the middle of the voxel layer halfway
    between the z bounds."""
    layer = np.floor((ws.lower[2] + ws.upper[2]) / 2.0 / ws.resolution)
    return float((layer + 0.5) * ws.resolution)


def label_section(ax, section, units: Units) -> str:
    """Label the axes of a section's panel (x, y; or r, z) in `units`, and return where the
    section lies, in words: its height, or the azimuth of its vertical plane. `section`: a
    `Section` or anything with its ``plane`` and ``position``."""
    unit = units.length
    if section.plane == "horizontal":
        ax.set_xlabel(f"x ({unit})")
        ax.set_ylabel(f"y ({unit})")
        return f"z = {units.length_from_si(section.position):.6g} {unit}"
    ax.set_xlabel(f"r ({unit}), signed distance from the z axis")
    ax.set_ylabel(f"z ({unit})")
    return (f"vertical plane through the z axis, azimuth "
            f"{units.angle_from_si(section.position):.6g} {units.angle}")


def section_figure(ws: Workspace, height: float | None = None, azimuth: float = 0.0,
                   units: Units | None = None) -> Figure:
    """A horizontal section at `height` and a vertical one through the base z axis.

    Parameters
    ----------
    ws : Workspace
    height : float or None
        m; if None, the middle of the voxel layer halfway between the z bounds.
    azimuth : float
        rad, direction of the vertical plane from the x axis.
    units : Units or None
        Units of the axes and titles; the robot file's units if None.

    Returns
    -------
    Figure
        Two panels: occupied cells (x, y) at the height, and (r, z) in the vertical plane,
        each titled with its occupied area.
    """
    units = ws.robot.units if units is None else units
    height = default_height(ws) if height is None else height
    unit = units.length
    fig = Figure(figsize=(12, 5.2), layout="constrained")
    voxel = units.length_from_si(ws.resolution)
    plt_blue = matplotlib.colormaps["Blues"](1 / 1.4)      # the colour of an occupied cell
    sections = (ws.horizontal_section(height), ws.vertical_section(azimuth))
    for k, section in enumerate(sections, start=1):
        ax = fig.add_subplot(1, 2, k)
        ax.imshow(section.occupied, origin="lower", cmap="Blues", vmin=0, vmax=1.4,
                  extent=units.length_from_si(section.extent), interpolation="nearest")
        area = float(units.length_from_si(units.length_from_si(section.area)))
        where = label_section(ax, section, units)
        ax.scatter([0], [0], label="base origin", **_BASE)
        ax.add_patch(Rectangle((0, 0), 0, 0, color=plt_blue, label=f"occupied {voxel:.6g} "
                               f"{unit} cell"))
        ax.set_aspect("equal")
        ax.margins(0.03)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
        ax.set_title(f"{where}\noccupied area {area:.4g} {unit}\u00b2")
    voxel = units.length_from_si(ws.resolution)
    fig.suptitle(f"{figure_text(ws.robot.name)}: workspace sections, {voxel:.6g} {unit} cells, "
                 f"{ws.samples:,} samples")
    return fig


def save_workspace_figures(ws: Workspace, out: str | Path, height: float | None = None,
                           azimuth: float = 0.0, units: Units | None = None,
                           dpi: int = 90) -> list[Path]:
    """Write ``<robot>_workspace.png`` and ``<robot>_sections.png`` into the folder `out`.

    Returns
    -------
    paths : list of Path
        The two files written (the folder is created if missing).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{ws.robot.name}_workspace.png", out / f"{ws.robot.name}_sections.png"]
    workspace_figure(ws, units).savefig(paths[0], dpi=dpi)
    section_figure(ws, height, azimuth, units).savefig(paths[1], dpi=dpi)
    return paths
