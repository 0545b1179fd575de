"""An interactive 3-D view of an arm: its links as their collision capsules, its joint frames,
the obstacles around it, and optionally a motion played with play/pause and a time slider.

Written with plotly for offline use: `write_view` puts plotly's script inside the page (one file
to pass around) or beside it (``plotly.min.js`` in the same folder); nothing is loaded from the
network. Lengths are shown in the robot file's unit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.model.robot import Robot, joint_array

ARM_COLOUR, OBSTACLE_COLOUR, PATH_COLOUR, TARGET_COLOUR = "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e"
SIDES = 14          # facets around a capsule or cylinder
FRAMES = 60         # most animation frames of a motion


def _ring(a: NDArray, b: NDArray, r: float) -> tuple[NDArray, NDArray]:
    """Two unit vectors across the segment a -> b, for a ring of radius r around it."""
    d = b - a
    z = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-12 else np.array([0.0, 0, 1])
    x = np.cross(np.eye(3)[np.argmin(np.abs(z))], z)
    x /= np.linalg.norm(x)
    return r * x, r * np.cross(z, x)


def tube(a: ArrayLike, b: ArrayLike, r: float, caps: str = "round") -> tuple[NDArray, NDArray]:
    """A closed mesh around the segment a -> b (3,): a capsule (round caps) or a cylinder
    (flat caps). Returns vertices (v, 3) and triangles (f, 3)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    u, v = _ring(a, b, r)
    z = b - a
    z = z / np.linalg.norm(z) if np.linalg.norm(z) > 1e-12 else np.array([0.0, 0, 1])
    phi = np.linspace(0, 2 * np.pi, SIDES, endpoint=False)
    circle = np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v          # (S, 3)
    if caps == "flat":
        rings, poles = [a + circle, b + circle], np.array([a, b])
    else:           # hemispheres: rings at latitudes -60, -30, 0 deg around each end
        levels = [(np.sin(t), np.cos(t)) for t in np.linspace(-np.pi / 2, 0, 4)[1:]]
        rings = [a + z * r * s + circle * c for s, c in levels]
        rings += [b - z * r * s + circle * c for s, c in reversed(levels)]
        poles = np.array([a - z * r, b + z * r])
    body = np.vstack(rings)
    vertices = np.vstack([body, poles])
    k = len(rings)
    faces = []
    for i in range(k - 1):
        for j in range(SIDES):
            p, q = i * SIDES + j, i * SIDES + (j + 1) % SIDES
            faces += [(p, q, p + SIDES), (q, q + SIDES, p + SIDES)]
    bottom, cap = k * SIDES, k * SIDES + 1
    for j in range(SIDES):
        faces.append((bottom, (j + 1) % SIDES, j))
        faces.append((cap, (k - 1) * SIDES + j, (k - 1) * SIDES + (j + 1) % SIDES))
    return vertices, np.array(faces)


def box_mesh(size: ArrayLike, pose: ArrayLike) -> tuple[NDArray, NDArray]:
    """A box of edges `size` (3,) centred on `pose` (4, 4): vertices (8, 3), triangles (12, 3)."""
    h = np.asarray(size, float) / 2
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    T = np.asarray(pose, float)
    vertices = corners @ T[:3, :3].T + T[:3, 3]
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return vertices, faces


def sphere_mesh(center: ArrayLike, r: float) -> tuple[NDArray, NDArray]:
    """A ball as a mesh: a capsule of zero length."""
    c = np.asarray(center, float)
    return tube(c, c + np.array([0, 0, 1e-9]), r)


def obstacle_mesh(obstacle) -> tuple[NDArray, NDArray]:
    """The mesh (vertices (v, 3), triangles (f, 3)) of a `Box`, `Sphere`, `Cylinder` or
    `Capsule`, m."""
    from armkit.planning import Box, Capsule, Cylinder, Sphere

    if isinstance(obstacle, Box):
        return box_mesh(obstacle.size, obstacle.pose)
    if isinstance(obstacle, Sphere):
        return sphere_mesh(obstacle.center, obstacle.radius)
    if isinstance(obstacle, Cylinder):
        axis = obstacle.pose[:3, 2] * obstacle.length / 2
        c = obstacle.pose[:3, 3]
        return tube(c - axis, c + axis, obstacle.radius, caps="flat")
    if isinstance(obstacle, Capsule):
        return tube(obstacle.a, obstacle.b, obstacle.radius)
    raise TypeError(f"obstacle: expected Box, Sphere, Cylinder or Capsule, found "
                    f"{type(obstacle).__name__}")


def _merged(meshes) -> tuple[NDArray, NDArray]:
    vertices, faces, count = [], [], 0
    for v, f in meshes:
        vertices.append(v)
        faces.append(f + count)
        count += len(v)
    if not vertices:
        return np.zeros((0, 3)), np.zeros((0, 3), int)
    return np.vstack(vertices), np.vstack(faces)


def _mesh_trace(go, vertices, faces, colour, name, opacity=1.0, scale=1.0):
    return go.Mesh3d(x=vertices[:, 0] * scale, y=vertices[:, 1] * scale, z=vertices[:, 2] * scale,
                     i=faces[:, 0], j=faces[:, 1], k=faces[:, 2], color=colour, opacity=opacity,
                     name=name, showlegend=True, flatshading=True, hoverinfo="name")


def _arm_traces(go, robot: Robot, geometry, q: NDArray, scale: float):
    from armkit.kinematics import fk_frames
    from armkit.planning.collision import arm_capsules

    a, b = arm_capsules(robot, geometry, q)
    vertices, faces = _merged(tube(a[i], b[i], geometry.radius[i]) for i in range(len(a)))
    origins = fk_frames(robot, q)[:, :3, 3] * scale
    return [_mesh_trace(go, vertices, faces, ARM_COLOUR, "arm (collision capsules)", 0.85, scale),
            go.Scatter3d(x=origins[:, 0], y=origins[:, 1], z=origins[:, 2], mode="lines+markers",
                         line=dict(color="black", width=4), marker=dict(size=3, color="black"),
                         name="joint frames (origins)")]


def robot_view(robot: Robot, q: ArrayLike, *, scene=None, geometry=None, t: ArrayLike | None = None,
               target: ArrayLike | None = None, title: str = ""):
    """A plotly figure of the arm at q (n,), or playing the motion q (k, n) at times t (k,) s.

    Parameters
    ----------
    scene : armkit.planning.Scene, optional
        Obstacles, drawn in red.
    geometry : armkit.planning.ArmGeometry, optional
        The link capsules (default: `armkit.planning.arm_geometry`).
    target : array_like (4, 4), optional
        A target pose, drawn as a marker with its axes.

    Returns
    -------
    plotly.graph_objects.Figure
        With play/pause buttons and a time slider when q holds several configurations.
    """
    import plotly.graph_objects as go

    from armkit.kinematics import fk
    from armkit.planning import arm_geometry

    q = joint_array(robot, q)
    Q = q.reshape(-1, robot.n)
    geometry = geometry if geometry is not None else arm_geometry(robot)
    unit = robot.units.length
    scale = 1000.0 if unit == "mm" else 1.0
    traces = _arm_traces(go, robot, geometry, Q[0], scale)
    tool = fk(robot, Q)[:, :3, 3] * scale
    if len(Q) > 1:
        traces.append(go.Scatter3d(x=tool[:, 0], y=tool[:, 1], z=tool[:, 2], mode="lines",
                                   line=dict(color=PATH_COLOUR, width=5), name="tool path"))
    for o in (scene or ()):
        v, f = obstacle_mesh(o)
        traces.append(_mesh_trace(go, v, f, OBSTACLE_COLOUR, o.name or type(o).__name__.lower(),
                                  0.6, scale))
    if target is not None:
        T = np.asarray(target, float)
        p = T[:3, 3] * scale
        traces.append(go.Scatter3d(x=[p[0]], y=[p[1]], z=[p[2]], mode="markers",
                                   marker=dict(size=7, color=TARGET_COLOUR, symbol="diamond"),
                                   name="target"))
        ends = p + 0.1 * scale * T[:3, :3].T
        for axis, colour in zip(ends, ("red", "green", "blue")):
            traces.append(go.Scatter3d(x=[p[0], axis[0]], y=[p[1], axis[1]], z=[p[2], axis[2]],
                                       mode="lines", line=dict(color=colour, width=4),
                                       showlegend=False, hoverinfo="skip"))
    fig = go.Figure(data=traces)
    everything = np.vstack([tool] + [np.c_[tr.x, tr.y, tr.z] for tr in traces])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-3 * scale) * 1.1
    axes = {f"{c}axis": dict(title=f"{c} ({unit})", range=[centre[i] - half, centre[i] + half])
            for i, c in enumerate("xyz")}
    fig.update_layout(title=title or f"{robot.name}", scene=dict(aspectmode="cube", **axes),
                      margin=dict(l=0, r=0, t=40, b=0), height=640,
                      legend=dict(x=0.01, y=0.99, bgcolor="rgba(255,255,255,0.7)"))
    if len(Q) > 1:
        _animate(go, fig, robot, geometry, Q, t, scale)
    return fig


def _animate(go, fig, robot, geometry, Q, t, scale) -> None:
    t = np.arange(len(Q), dtype=float) if t is None else np.asarray(t, float)
    pick = np.unique(np.linspace(0, len(Q) - 1, min(FRAMES, len(Q))).round().astype(int))
    frames = [go.Frame(data=_arm_traces(go, robot, geometry, Q[i], scale), traces=[0, 1],
                       name=f"{t[i]:.2f}") for i in pick]
    fig.frames = frames
    step_ms = max(20, int(1000 * (t[-1] - t[0]) / max(len(pick) - 1, 1)))
    play = dict(label="play", method="animate",
                args=[None, dict(frame=dict(duration=step_ms, redraw=True), fromcurrent=True,
                                 transition=dict(duration=0))])
    pause = dict(label="pause", method="animate",
                 args=[[None], dict(frame=dict(duration=0, redraw=False), mode="immediate")])
    fig.update_layout(
        updatemenus=[dict(type="buttons", direction="left", x=0.0, y=0.0, xanchor="left",
                          yanchor="top", buttons=[play, pause])],
        sliders=[dict(active=0, x=0.12, y=0.0, len=0.86, currentvalue=dict(prefix="t = ",
                                                                          suffix=" s"),
                      steps=[dict(label=f.name, method="animate",
                                  args=[[f.name], dict(mode="immediate",
                                                       frame=dict(duration=0, redraw=True))])
                             for f in frames])])


def write_view(fig, path: str | Path, *, script: str = "inline") -> Path:
    """Write a figure as an HTML page that opens offline.

    Parameters
    ----------
    script : {"inline", "beside"}
        plotly's script inside the page, or as ``plotly.min.js`` in the page's folder.
    """
    import plotly.io as pio

    path = Path(path)
    if script == "beside":
        write_plotly_script(path.parent)
        pio.write_html(fig, path, include_plotlyjs="plotly.min.js", full_html=True,
                       auto_play=False)
    else:
        pio.write_html(fig, path, include_plotlyjs=True, full_html=True, auto_play=False)
    return path


def write_plotly_script(folder: Path) -> Path:
    """plotly's script, from the installed package, as ``plotly.min.js`` in `folder`."""
    from plotly.offline import get_plotlyjs

    path = Path(folder) / "plotly.min.js"
    path.write_text(get_plotlyjs(), encoding="utf-8")
    return path
