"""Pictures of reachability maps and base placements: sections of a map coloured by its index,
the map in 3-D in the report's viewer (beside the arm), and the floor (or rail) region from
which every task pose is reached, with the chosen base.

Lengths on the axes are in the units given (the robot file's by default).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from armkit.model.robot import Units
from armkit.reach import Placement, ReachMap
from armkit.report.workspace import label_section

_CMAP = "viridis"
_OUTSIDE = "#e8e8e8"        # cells the map holds no voxel for
_BASE = {"marker": "+", "color": "tab:red", "s": 70, "linewidths": 1.4, "zorder": 4}
MOST_POINTS = 60_000        # voxels drawn in the 3-D view at most


def _index_label(m: ReachMap) -> str:
    return (f"reachability index: share of the {len(m.orientations)} orientations reached "
            f"({m.orientations.task})")


def default_height(m: ReachMap) -> float:
    """Height (m) of the default horizontal section: the middle of the voxel layer whose
    reachable voxels are the most."""
    k = m.voxels[m.count > 0, 2] if (m.count > 0).any() else m.voxels[:, 2]
    values, counts = np.unique(k, return_counts=True)
    return float((values[np.argmax(counts)] + 0.5) * m.resolution)


def map_figure(m: ReachMap, height: float | None = None, azimuth: float = 0.0,
               units: Units | None = None) -> Figure:
    """Two sections of a map coloured by its index: horizontal at `height` (m; default
    `default_height`), and vertical through the base z axis at `azimuth` (rad).

    Returns
    -------
    Figure
        Cells outside the map grey; a colour bar of the index from 0 to 1; the base origin as
        a red cross.
    """
    units = m.robot.units if units is None else units
    height = default_height(m) if height is None else height
    unit = units.length
    fig = Figure(figsize=(13, 5.4), layout="constrained")
    cmap = matplotlib.colormaps[_CMAP].with_extremes(bad=_OUTSIDE)
    image = None
    for k, section in enumerate((m.horizontal_section(height), m.vertical_section(azimuth)), 1):
        ax = fig.add_subplot(1, 2, k)
        image = ax.imshow(np.ma.masked_invalid(section.index), origin="lower", cmap=cmap,
                          vmin=0.0, vmax=1.0, extent=units.length_from_si(section.extent),
                          interpolation="nearest")
        ax.scatter([0], [0], **_BASE)
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.set_title(label_section(ax, section, units))
        ax.legend(handles=[Line2D([], [], marker="+", ls="", color="tab:red", ms=8,
                                  label="base origin"),
                           Patch(color=_OUTSIDE, label="outside the map")],
                  loc="best", fontsize=8)
    fig.colorbar(image, ax=fig.axes, shrink=0.85, label=_index_label(m))
    voxel = units.length_from_si(m.resolution)
    fig.suptitle(f"{m.robot.name}: reachability map, {voxel:.6g} {unit} voxels x "
                 f"{len(m.orientations)} orientations ({m.orientations.description}); "
                 f"reachable volume {m.volume:.4g} m\u00b3")
    return fig


def map_view(m: ReachMap, q=None, *, title: str = ""):
    """The map in 3-D in the report's viewer (`armkit.report.view`): the voxels that reach some
    orientation as points coloured by the index (with a colour bar), and the arm at q (n,)
    (default: the middle of its limits).

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go

    from armkit.report.view import show

    robot = m.robot
    if q is None:
        low, high = robot.sampling_limits
        q = 0.5 * (low + high)
    rows = np.flatnonzero(m.count > 0)
    if len(rows) > MOST_POINTS:             # every k-th voxel, evenly over the map
        rows = rows[np.linspace(0, len(rows) - 1, MOST_POINTS).astype(int)]
    fig = show(robot, q, title=title or f"{robot.name}: reachability map",
               also=m.centers[rows])
    p = m.centers[rows] * (1000.0 if robot.units.length == "mm" else 1.0)
    fig.add_trace(go.Scatter3d(
        x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="markers", name="reachable voxels",
        marker=dict(size=2.5, color=m.index[rows], colorscale="Viridis", cmin=0.0, cmax=1.0,
                    opacity=0.5, colorbar=dict(title="index", x=1.0)),
        hovertemplate="index %{marker.color:.2f}<extra></extra>"))
    return fig


def placement_figure(placement: Placement, units: Units | None = None) -> Figure:
    """Where the base can stand: on a floor, the best score over the yaws at each position
    and the share of yaws from which every pose is reached, with the chosen base (a star, its
    x axis an arrow) and the task poses; on a rail, the score along it.

    Parameters
    ----------
    units : Units, optional
        Length and angle units of the axes (default: m and deg).
    """
    units = Units("m", "deg") if units is None else units
    unit = units.length
    grid = placement.grid
    ok = placement.feasible.reshape(grid.shape)
    score = placement.score.reshape(grid.shape)
    what = ("worst pose's reachability index" if placement.criterion == "reachability"
            else "worst pose's manipulability")
    task = units.length_from_si(placement.task[:, :3, 3])
    if grid.kind == "floor":
        fig = Figure(figsize=(13, 5.6), layout="constrained")
        xs, ys = units.length_from_si(grid.axes["x"]), units.length_from_si(grid.axes["y"])
        half = units.length_from_si(grid.step) / 2
        extent = [xs[0] - half, xs[-1] + half, ys[0] - half, ys[-1] + half]
        with np.errstate(all="ignore"):
            best = np.where(ok.any(axis=2), np.nanmax(np.where(ok, score, -np.inf), axis=2),
                            np.nan)
        share = ok.mean(axis=2)
        panels = ((best, what, _CMAP, None), (share, "share of the yaws that reach every pose",
                                              "Greens", (0.0, 1.0)))
        for k, (values, label, cmap, limits) in enumerate(panels, 1):
            ax = fig.add_subplot(1, 2, k)
            colours = matplotlib.colormaps[cmap].with_extremes(bad=_OUTSIDE)
            vmin, vmax = limits or (np.nanmin(values) if np.isfinite(values).any() else 0,
                                    np.nanmax(values) if np.isfinite(values).any() else 1)
            image = ax.imshow(np.ma.masked_invalid(np.where(share > 0, values, np.nan)),
                              origin="lower", extent=extent, cmap=colours, vmin=vmin,
                              vmax=vmax, interpolation="nearest")
            fig.colorbar(image, ax=ax, shrink=0.85, label=label)
            ax.scatter(task[:, 0], task[:, 1], marker="x", color="black", s=30, zorder=5,
                       label="task poses (x, y)")
            if placement.best is not None:
                p = units.length_from_si(placement.T_world_base[:3, 3])
                axis = placement.T_world_base[:2, 0] * 4 * half
                ax.scatter([p[0]], [p[1]], marker="*", s=220, color="tab:red", zorder=6,
                           edgecolors="white", label="chosen base")
                ax.annotate("", xy=(p[0] + axis[0], p[1] + axis[1]), xytext=(p[0], p[1]),
                            arrowprops=dict(arrowstyle="->", color="tab:red", lw=1.8),
                            zorder=6)
            ax.set_xlabel(f"x ({unit})")
            ax.set_ylabel(f"y ({unit})")
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
            ax.legend(handles=ax.get_legend_handles_labels()[0]
                      + [Patch(color=_OUTSIDE, label="no yaw reaches every pose")],
                      loc="best", fontsize=8)
        fig.axes[0].set_title("best over the yaws")
        fig.axes[2].set_title("yaws that work")
    else:
        fig = Figure(figsize=(11, 4.6), layout="constrained")
        ax = fig.add_subplot(1, 1, 1)
        s = units.length_from_si(grid.axes["s"])
        for k, yaw in enumerate(grid.axes["yaw"]):
            ax.plot(s, score[:, k], marker=".", ms=3,
                    label=f"yaw {units.angle_from_si(yaw):.4g} {units.angle}")
        reach = ok.any(axis=1)
        ax.fill_between(s, 0, 1, where=reach, transform=ax.get_xaxis_transform(),
                        color="tab:green", alpha=0.12, label="every pose reached")
        if placement.best is not None:
            chosen = s[placement.best // grid.shape[1]]
            ax.axvline(chosen, color="tab:red", lw=1.5, label=f"chosen: s = {chosen:.6g} {unit}")
        ax.set_xlabel(f"s ({unit}), along the rail from its start")
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    margin = ("" if placement.best is None else
              f"; margin {units.length_from_si(placement.margin[placement.best]):.4g} {unit}, "
              f"yaw margin {units.angle_from_si(placement.yaw_margin):.4g} {units.angle}")
    fig.suptitle(f"base placement for {len(placement.task)} task poses: "
                 f"{int(placement.feasible.sum()):,} of {len(grid):,} bases reach them all"
                 + margin)
    return fig


def save_map_figures(m: ReachMap, out: str | Path, height: float | None = None,
                     azimuth: float = 0.0, units: Units | None = None,
                     dpi: int = 90) -> list[Path]:
    """Write ``<robot>_reach.png`` (sections) and ``<robot>_reach.html`` (the 3-D view, which
    opens offline) into the folder `out`; returns their paths."""
    from armkit.report.view import write_figure

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{m.robot.name}_reach.png", out / f"{m.robot.name}_reach.html"]
    map_figure(m, height, azimuth, units).savefig(paths[0], dpi=dpi)
    write_figure(map_view(m), paths[1])
    return paths


def save_placement_figure(placement: Placement, path: str | Path,
                          units: Units | None = None, dpi: int = 90) -> Path:
    """Write the placement's picture (PNG) to `path`."""
    path = Path(path)
    placement_figure(placement, units).savefig(path, dpi=dpi)
    return path
