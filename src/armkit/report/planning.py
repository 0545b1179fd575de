"""Planning pictures: the arm along its path among the obstacles (3-D), and the joints along it.

Lengths and angles in the units given (the robot file's by default).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from armkit.kinematics import fk
from armkit.model.robot import Units
from armkit.planning.collision import arm_capsules
from armkit.planning.scene import Box, Cylinder, Sphere

_FACES = ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5))


def _draw_obstacle(ax, o, scale: float) -> None:
    style = {"color": "tab:gray", "alpha": 0.25}
    if isinstance(o, Box):
        c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * o.size / 2
        v = (c @ o.pose[:3, :3].T + o.pose[:3, 3]) * scale
        ax.add_collection3d(Poly3DCollection([v[list(f)] for f in _FACES], facecolor="tab:gray",
                                             alpha=0.2, edgecolor="dimgray", linewidths=0.4))
        return
    u, w = np.meshgrid(np.linspace(0, 2 * np.pi, 24), np.linspace(0, np.pi, 12))
    if isinstance(o, Sphere):
        p = np.stack([np.cos(u) * np.sin(w), np.sin(u) * np.sin(w), np.cos(w)], -1) * o.radius
        p = p + o.center
    elif isinstance(o, Cylinder):
        h = np.linspace(-o.length / 2, o.length / 2, 12)[:, None]
        p = np.stack([o.radius * np.cos(u), o.radius * np.sin(u),
                      np.broadcast_to(h, u.shape)], -1) @ o.pose[:3, :3].T + o.pose[:3, 3]
    else:
        ax.plot(*(np.array([o.a, o.b]) * scale).T, color="tab:gray", alpha=0.5,
                linewidth=max(1.0, o.radius * 200))
        return
    p = p * scale
    ax.plot_wireframe(p[..., 0], p[..., 1], p[..., 2], linewidth=0.3, **style)


def path_figure(checker, path: np.ndarray, units: Units | None = None) -> Figure:
    """The arm's parts (capsules, spheres) at every waypoint of path (k, n) among the checker's
    obstacles, and each joint along the path with its limits.

    Parameters
    ----------
    checker : CollisionChecker
        Robot, geometry and scene.
    path : ndarray, (k, n)
        rad / m.
    units : Units, optional
        Of the axes; the robot's file units if None.
    """
    robot, geometry, scene = checker.robot, checker.geometry, checker.scene
    units = robot.units if units is None else units
    scale = float(units.length_from_si(1.0))
    fig = Figure(figsize=(14, 6), layout="constrained")
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    for o in scene:
        _draw_obstacle(ax, o, scale)
    colours = colormaps["viridis"](np.linspace(0, 1, len(path)))
    spheres = np.all(geometry.a == geometry.b, axis=1)
    for q, colour in zip(path, colours):
        a, b = arm_capsules(robot, geometry, q)
        for s, e in zip(a[~spheres] * scale, b[~spheres] * scale):
            ax.plot(*np.array([s, e]).T, color=colour, linewidth=2.5, solid_capstyle="round")
        if spheres.any():                   # sphere parts: their centres, sized by radius
            ax.scatter(*(a[spheres] * scale).T, color=colour, alpha=0.35,
                       s=(geometry.radius[spheres] * 400) ** 2, linewidths=0)
    tool = fk(robot, path)[:, :3, 3] * scale
    ax.plot(*tool.T, color="tab:red", linewidth=1.2, marker=".")
    points = np.vstack([tool, np.zeros((1, 3))] + [np.array([o.pose[:3, 3] if hasattr(o, "pose")
                                                             else getattr(o, "center", o.a)])
                                                   * scale for o in scene])
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-9) * 1.2
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    for name, setter in (("x", ax.set_xlabel), ("y", ax.set_ylabel), ("z", ax.set_zlabel)):
        setter(f"{name} ({units.length})")
    ax.set_title(f"{robot.name}: {len(path)} waypoints among {len(scene)} obstacles")
    ax.legend(handles=[Line2D([], [], color=colours[0], linewidth=2.5, label="arm at start"),
                       Line2D([], [], color=colours[-1], linewidth=2.5, label="arm at goal"),
                       Line2D([], [], color="tab:red", marker=".", label="tool path")],
              loc="upper left")
    ax2 = fig.add_subplot(1, 2, 2)
    values = robot.q_from_si(path)
    lower, upper = robot.q_from_si(robot.lower), robot.q_from_si(robot.upper)
    for j, name in enumerate(robot.joint_names):
        line, = ax2.plot(values[:, j], marker="o", markersize=3,
                         label=f"{name} ({robot.joint_units[j]})")
        for limit in (lower[j], upper[j]):
            if np.isfinite(limit):
                ax2.axhline(limit, color=line.get_color(), linestyle=":", linewidth=0.8)
    ax2.set_xlabel("waypoint")
    ax2.set_ylabel(f"joint value ({', '.join(sorted(set(robot.joint_units)))}); "
                   f"dotted: limits")
    ax2.set_title("joints along the path")
    ax2.legend(loc="best", fontsize="small")
    return fig


def save_path_figure(checker, path: np.ndarray, folder: str | Path,
                     units: Units | None = None) -> Path:
    """Write `path_figure` as ``<robot>_path.png`` in folder; returns the file's path."""
    out = Path(folder) / f"{checker.robot.name}_path.png"
    path_figure(checker, path, units).savefig(out, dpi=110)
    return out
