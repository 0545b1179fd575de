"""An interactive 3-D view of an arm (plotly): its links as their collision capsules (or a
URDF's visual meshes), a frame at the base, at every joint and at the tool, the floor, the
obstacles around it, and optionally a motion played with play/pause and a time slider.

`show` returns the figure (a notebook shows it; ``.write_html`` saves it), also as
`armkit.show`. `view_page` makes the page of `armkit view`: one HTML file,
plotly inside, with a slider per joint that moves the arm in the page, its forward kinematics
computed by the page's own script from the chain's numbers (`armkit.model.chain.KernelChain`),
and the tool's pose shown. Nothing is loaded from the network. Lengths are shown in the robot
file's unit; names from files are shown as text (`armkit.report.text`).
"""

from __future__ import annotations

import base64
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import plotly.graph_objects as go
from numpy.typing import ArrayLike, NDArray
from plotly.offline import get_plotlyjs

from armkit.io.visuals import Visuals
from armkit.kinematics.forward import fk, fk_frames
from armkit.model.robot import Robot, joint_array
from armkit.planning import ArmGeometry, Box, Capsule, Cylinder, Sphere, arm_geometry
from armkit.report.text import page_text, plotly_text
from armkit.trajectory.piecewise import Trajectory

ARM_COLOUR, OBSTACLE_COLOUR, PATH_COLOUR, TARGET_COLOUR = "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e"
AXIS_COLOURS = ("#e41a1c", "#2ca02c", "#1f5fd6")     # x, y, z
SIDES = 14          # facets around a capsule or cylinder
FRAMES = 60         # most animation frames of a motion
ARM_OPACITY = 0.45  # the frames and the path stay visible through the links
REACH_SAMPLES = 400 # configurations whose link frames `view_page` keeps in view
EYE = (1.35, -1.35, 0.85)   # the camera, from the centre, in the scene's own units


@dataclass(frozen=True)
class Bodies:
    """The arm's surfaces in their links' frames: vertices (v, 3) m, the link frame each
    vertex rides on (v,) (0 base, i after joint i, as `armkit.fk_frames`), triangles (f, 3);
    `source` says what they are ("collision capsules", "URDF visual meshes")."""

    vertices: NDArray
    link: NDArray
    faces: NDArray
    source: str


def _ring(a: NDArray, b: NDArray, r: float) -> tuple[NDArray, NDArray]:
    """Two vectors across the segment a -> b, of length r, for a ring around it."""
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


def capsule_bodies(geometry: ArmGeometry) -> Bodies:
    """The arm's collision capsules as surfaces in their links' frames."""
    vertices, links, faces, count = [], [], [], 0
    for link, a, b, r in zip(geometry.link, geometry.a, geometry.b, geometry.radius):
        v, f = tube(a, b, r)
        vertices.append(v)
        links.append(np.full(len(v), link))
        faces.append(f + count)
        count += len(v)
    if not vertices:
        return Bodies(np.zeros((0, 3)), np.zeros(0, int), np.zeros((0, 3), int),
                      "collision capsules")
    return Bodies(np.vstack(vertices), np.concatenate(links), np.vstack(faces),
                  "collision capsules")


def visual_bodies(visuals: Visuals, geometry: ArmGeometry | None = None) -> Bodies:
    """A URDF's visual elements (`armkit.io.visuals.read_visuals`) as surfaces; with
    `geometry`, the collision capsules of the links that have no visual element too."""
    vertices, links, faces, count = [], [], [], 0
    for shape in visuals.shapes:
        T = shape.T
        if shape.kind == "mesh":
            v, f = shape.vertices @ T[:3, :3].T + T[:3, 3], shape.faces
        elif shape.kind == "box":
            v, f = box_mesh(shape.size, T)
        elif shape.kind == "sphere":
            v, f = sphere_mesh(T[:3, 3], shape.size[0])
        else:
            half = T[:3, 2] * shape.size[1] / 2
            v, f = tube(T[:3, 3] - half, T[:3, 3] + half, shape.size[0], caps="flat")
        vertices.append(v)
        links.append(np.full(len(v), shape.link))
        faces.append(f + count)
        count += len(v)
    if geometry is not None:
        covered = {shape.link for shape in visuals.shapes}
        capsules = capsule_bodies(geometry)
        keep = ~np.isin(capsules.link, list(covered))
        kept_faces = capsules.faces[keep[capsules.faces].all(axis=1)]
        index = np.cumsum(keep) - 1
        vertices.append(capsules.vertices[keep])
        links.append(capsules.link[keep])
        faces.append(index[kept_faces] + count)
    return Bodies(np.vstack(vertices), np.concatenate(links), np.vstack(faces).astype(int),
                  "URDF visual meshes")


def _placed(bodies: Bodies, frames: NDArray) -> NDArray:
    """Body vertices in the base frame, for link frames (n_joints + 1, 4, 4)."""
    T = frames[bodies.link]
    return np.einsum("vij,vj->vi", T[:, :3, :3], bodies.vertices) + T[:, :3, 3]


def _axes(frames: NDArray, length: float) -> list[NDArray]:
    """Line segments (3 points each: start, end, a gap) of the x, y and z axes of frames."""
    o = frames[:, :3, 3]
    gap = np.full_like(o, np.nan)
    return [np.stack([o, o + length * frames[:, :3, k], gap], axis=1).reshape(-1, 3)
            for k in range(3)]


def _line(points: NDArray, **style) -> go.Scatter3d:
    return go.Scatter3d(x=points[:, 0], y=points[:, 1], z=points[:, 2], mode="lines", **style)


def _arm_traces(robot: Robot, bodies: Bodies, q: NDArray, scale: float,
                length: float) -> list:
    """The arm at q: its surfaces, its frames' axes (x, y, z), and its skeleton (the joint
    origins, base to tool, with markers)."""
    frames = fk_frames(robot, q)
    v = (_placed(bodies, frames) * scale).astype(np.float32)      # for the picture only
    f = bodies.faces.astype(np.int32)
    traces = [go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1], k=f[:, 2],
                        color=ARM_COLOUR,
                        opacity=ARM_OPACITY, flatshading=True, name=f"arm ({bodies.source})",
                        showlegend=True, hoverinfo="name")]
    for k, points in enumerate(_axes(frames, length)):
        traces.append(_line(points * scale, line=dict(color=AXIS_COLOURS[k], width=5),
                            name="frames: x y z axes" if k == 0 else "",
                            legendgroup="axes", showlegend=k == 0, hoverinfo="skip"))
    o = frames[:, :3, 3] * scale
    traces.append(go.Scatter3d(x=o[:, 0], y=o[:, 1], z=o[:, 2], mode="lines+markers",
                               line=dict(color="black", width=3),
                               marker=dict(size=3, color="black"),
                               name="joint origins, base to tool", hoverinfo="skip"))
    return traces


def _floor(lo: NDArray, hi: NDArray, z: float) -> tuple[NDArray, float]:
    """Grid lines over [lo, hi] (x, y) at height z, a round spacing; and that spacing."""
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-9))
    step = 10.0 ** np.floor(np.log10(span / 8))
    step *= 5 if span / step > 40 else 2 if span / step > 16 else 1
    xs = np.arange(np.floor(lo[0] / step), np.ceil(hi[0] / step) + 1) * step
    ys = np.arange(np.floor(lo[1] / step), np.ceil(hi[1] / step) + 1) * step
    segments = [[[x, ys[0], z], [x, ys[-1], z], [np.nan] * 3] for x in xs]
    segments += [[[xs[0], y, z], [xs[-1], y, z], [np.nan] * 3] for y in ys]
    return np.array(segments, float).reshape(-1, 3), step


def show(robot: Robot, q: ArrayLike | Trajectory, *, scene=None,
               geometry: ArmGeometry | None = None, bodies: Bodies | None = None,
               t: ArrayLike | None = None, target: ArrayLike | None = None,
               title: str = "", also: ArrayLike | None = None) -> go.Figure:
    """A plotly figure of the arm at q (n,), or playing a motion.

    Parameters
    ----------
    q : array_like (n,) or (k, n), or Trajectory
        One configuration, or a motion: configurations at times `t` (k,) s, or a trajectory
        (sampled at 200 instants).
    scene : armkit.planning.Scene, optional
        Obstacles, drawn in red.
    geometry : armkit.planning.ArmGeometry, optional
        The link capsules (default: `armkit.planning.arm_geometry`).
    bodies : Bodies, optional
        The arm's surfaces instead of its capsules (a URDF's visual meshes).
    target : array_like (4, 4), optional
        A target pose, drawn as a marker with its axes.
    title : str
        Shown as text.
    also : array_like (k, 3), optional
        Points (m, base frame) the view must hold too, such as where the arm can reach.

    Returns
    -------
    plotly.graph_objects.Figure
        With play/pause buttons and a time slider when q holds several configurations. The
        floor (a grid at the base's height, or below everything), a frame at the base, every
        joint and the tool, and the whole scene are in view.
    """
    if isinstance(q, Trajectory):
        motion = q.sample_uniform(200)
        Q, t = motion.q, motion.t
    else:
        Q = joint_array(robot, q).reshape(-1, robot.n)
    bodies = bodies if bodies is not None else capsule_bodies(
        geometry if geometry is not None else arm_geometry(robot))
    unit = robot.units.length
    scale = 1000.0 if unit == "mm" else 1.0
    tool = fk(robot, Q)[:, :3, 3] * scale
    # Everything the view must hold: the arm all along the motion, obstacles, the target.
    every = [tool, fk_frames(robot, Q[:: max(1, len(Q) // 20)])[..., :3, 3].reshape(-1, 3)
             * scale, _placed(bodies, fk_frames(robot, Q[0])) * scale]
    obstacles = [(o, *obstacle_mesh(o)) for o in (scene or ())]
    every += [v * scale for _, v, _ in obstacles]
    if target is not None:
        every.append(np.asarray(target, float)[None, :3, 3] * scale)
    if also is not None:
        every.append(np.asarray(also, float).reshape(-1, 3) * scale)
    arm = np.vstack(every[:3])
    points = np.vstack(every)
    lo, hi = points.min(axis=0), points.max(axis=0)
    size = float(np.max(hi - lo))
    length = 0.08 * size
    traces = _arm_traces(robot, bodies, Q[0], scale, length / scale)
    if len(Q) > 1:
        traces.append(go.Scatter3d(x=tool[:, 0], y=tool[:, 1], z=tool[:, 2], mode="lines",
                                   line=dict(color=PATH_COLOUR, width=7), name="tool path"))
    for o, v, f in obstacles:
        v = v * scale
        traces.append(go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1],
                                k=f[:, 2], color=OBSTACLE_COLOUR, opacity=0.55,
                                flatshading=True, showlegend=True, hoverinfo="name",
                                name=plotly_text(o.name or type(o).__name__.lower())))
    if target is not None:
        T = np.asarray(target, float)
        p = T[:3, 3] * scale
        traces.append(go.Scatter3d(x=[p[0]], y=[p[1]], z=[p[2]], mode="markers",
                                   marker=dict(size=7, color=TARGET_COLOUR, symbol="diamond"),
                                   name="target"))
        for k, points in enumerate(_axes(T[None], 1.5 * length / scale)):
            traces.append(_line(points * scale, line=dict(color=AXIS_COLOURS[k], width=4),
                                showlegend=False, hoverinfo="skip"))
    floor_z = min(0.0, float(lo[2]))
    pad = 0.08 * size
    grid, _ = _floor(lo[:2] - pad, hi[:2] + pad, floor_z)
    traces.append(_line(grid, line=dict(color="#bbbbbb", width=1), name="floor",
                        hoverinfo="skip"))
    fig = go.Figure(data=traces)
    lo = np.minimum(lo, [grid[:, 0][~np.isnan(grid[:, 0])].min(),
                         grid[:, 1][~np.isnan(grid[:, 1])].min(), floor_z]) - pad
    hi = np.maximum(hi, [np.nanmax(grid[:, 0]), np.nanmax(grid[:, 1]), floor_z]) + pad
    extent = hi - lo
    aspect = extent / extent.max()
    axes = {f"{c}axis": dict(title=f"{c} ({unit})", range=[lo[i], hi[i]],
                             backgroundcolor="white", gridcolor="#e5e5e5")
            for i, c in enumerate("xyz")}
    # The camera on the arm, closer when the view holds far more than the arm (a reach).
    middle = (arm.min(axis=0) + arm.max(axis=0)) / 2
    centre = (middle - (lo + hi) / 2) / extent * aspect
    zoom = float(np.clip(1.8 * np.ptp(arm, axis=0).max() / extent.max(), 0.4, 1.0))
    eye = centre + zoom * np.array(EYE)
    fig.update_layout(
        title=plotly_text(title or robot.name), height=760, margin=dict(l=0, r=0, t=40, b=0),
        scene=dict(aspectmode="manual", aspectratio=dict(zip("xyz", aspect)),
                   camera=dict(eye=dict(zip("xyz", eye)), center=dict(zip("xyz", centre))),
                   **axes),
        legend=dict(x=0.01, y=0.98, bgcolor="rgba(255,255,255,0.75)"),
        meta=dict(axis_length=length / scale))        # m, the frames' axes
    if len(Q) > 1:
        _animate(fig, robot, bodies, Q, t, scale, length / scale)
    return fig


def _animate(fig: go.Figure, robot: Robot, bodies: Bodies, Q: NDArray, t, scale: float,
             length: float) -> None:
    t = np.arange(len(Q), dtype=float) if t is None else np.asarray(t, float)
    pick = np.unique(np.linspace(0, len(Q) - 1, min(FRAMES, len(Q))).round().astype(int))
    moving = list(range(5))              # the arm's surfaces, three axes, the skeleton
    frames = [go.Frame(data=_arm_traces(robot, bodies, Q[i], scale, length), traces=moving,
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


def plotly_script() -> str:
    """plotly's script, from the installed package, for a page that needs no network."""
    return get_plotlyjs()


# --- the page with joint sliders ------------------------------------------------------------

PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
body{{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#222}}
#wrap{{display:flex;height:100vh}} #view{{flex:1;min-width:0;height:100vh}}
#panel{{width:330px;padding:12px 16px;overflow-y:auto;border-left:1px solid #ddd;background:#fafafa}}
h1{{font-size:1.1em;margin:.2em 0 .6em}} label{{display:block;font-size:.85em;margin-top:.6em}}
input[type=range]{{width:100%}} .value{{float:right;font-variant-numeric:tabular-nums}}
pre{{font-size:.85em;background:white;border:1px solid #ddd;padding:6px;white-space:pre-wrap}}
.note{{color:#555;font-size:.8em}}
</style>
<script>{plotly}</script></head><body><div id="wrap"><div id="view"></div>
<div id="panel"><h1>{title}</h1>{sliders}
<h2 style="font-size:1em;margin-top:1.2em">Tool pose (base frame)</h2>
<pre id="tool-pose"></pre>
<p class="note">Forward kinematics runs in this page from the chain's numbers; drag to turn the
view, scroll to zoom. Lengths in {unit}, angles in {angle}.</p></div></div>
<script>
const figure = {figure};
const chain = {chain};
{script}
</script></body></html>
"""

SCRIPT = r"""
function mul(A, B) {            // 4 x 4 row-major products
  const C = new Array(16).fill(0);
  for (let i = 0; i < 4; i++) for (let k = 0; k < 4; k++) {
    const a = A[4 * i + k]; if (a === 0) continue;
    for (let j = 0; j < 4; j++) C[4 * i + j] += a * B[4 * k + j];
  }
  return C;
}
function motion(kind, v) {      // about or along z
  if (kind === 1) return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, v, 0, 0, 0, 1];
  const c = Math.cos(v), s = Math.sin(v);
  return [c, -s, 0, 0, s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
}
function frames(q) {            // link frames: base, after each joint, tool (SI, m)
  let T = chain.pre, out = [chain.base], moved = [];
  for (let i = 0; i < chain.kinds.length; i++) {
    const m = mul(T, motion(chain.kinds[i], chain.scale[i] * q[chain.source[i]] + chain.offsets[i]));
    moved.push(m);
    T = mul(m, chain.links[i]);
  }
  for (let i = 0; i + 1 < chain.kinds.length; i++) out.push(mul(moved[i], chain.after[i]));
  out.push(T);
  return out;
}
function rpy(T) {               // R = Rz(yaw) Ry(pitch) Rx(roll)
  return [Math.atan2(T[9], T[10]), Math.atan2(-T[8], Math.hypot(T[9], T[10])),
          Math.atan2(T[4], T[0])];
}
function typed(text, Kind) {   // a base64 string of little-endian values
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  return new Kind(bytes.buffer);
}
const bodyLink = typed(chain.body_link, Int32Array);
const bodyVertices = typed(chain.body_vertices, Float32Array);
const view = document.getElementById("view");
const sliders = Array.from(document.querySelectorAll("input[data-joint]"));
function update() {
  const q = sliders.map((s, j) => Number(s.value) * chain.to_si[j]);
  sliders.forEach((s) => { s.parentElement.querySelector(".value").textContent = Number(s.value).toPrecision(6); });
  const F = frames(q), k = chain.scale_view;
  const x = [], y = [], z = [];
  for (let v = 0; v < bodyLink.length; v++) {
    const T = F[bodyLink[v]];
    const p0 = bodyVertices[3 * v], p1 = bodyVertices[3 * v + 1], p2 = bodyVertices[3 * v + 2];
    x.push(k * (T[0] * p0 + T[1] * p1 + T[2] * p2 + T[3]));
    y.push(k * (T[4] * p0 + T[5] * p1 + T[6] * p2 + T[7]));
    z.push(k * (T[8] * p0 + T[9] * p1 + T[10] * p2 + T[11]));
  }
  const ax = [[], [], []], ay = [[], [], []], az = [[], [], []], ox = [], oy = [], oz = [];
  for (const T of F) {
    ox.push(k * T[3]); oy.push(k * T[7]); oz.push(k * T[11]);
    for (let c = 0; c < 3; c++) {
      ax[c].push(k * T[3], k * (T[3] + chain.axis_length * T[c]), null);
      ay[c].push(k * T[7], k * (T[7] + chain.axis_length * T[4 + c]), null);
      az[c].push(k * T[11], k * (T[11] + chain.axis_length * T[8 + c]), null);
    }
  }
  Plotly.restyle(view, {x: [x, ax[0], ax[1], ax[2], ox], y: [y, ay[0], ay[1], ay[2], oy],
                        z: [z, az[0], az[1], az[2], oz]}, [0, 1, 2, 3, 4]);
  const tool = F[F.length - 1], angles = rpy(tool);
  const out = document.getElementById("tool-pose");
  out.dataset.position = JSON.stringify([tool[3], tool[7], tool[11]]);
  out.dataset.matrix = JSON.stringify(tool);
  out.textContent = "x y z (" + chain.unit + "): " +
    [tool[3], tool[7], tool[11]].map((v) => (v * chain.length_from_si).toPrecision(7)).join("  ") +
    "\nroll pitch yaw (" + chain.angle + "): " +
    angles.map((v) => (v * chain.angle_from_si).toPrecision(7)).join("  ");
}
Plotly.newPlot(view, figure.data, figure.layout, {responsive: true}).then(update);
sliders.forEach((s) => s.addEventListener("input", update));
"""


def _chain_numbers(robot: Robot, bodies: Bodies, axis_length: float) -> dict:
    """What the page's script needs: the chain in kernel form (4 x 4 row-major lists), the
    arm's surfaces in their link frames, and the unit conversions."""
    k = robot.chain.kernel
    u = robot.units
    rows = lambda T: np.asarray(T, float).reshape(-1).tolist()
    return {"kinds": k.kinds.tolist(), "offsets": k.offsets.tolist(),
            "source": k.source.tolist(), "scale": k.scale.tolist(), "pre": rows(k.pre),
            "links": [rows(T) for T in k.links], "after": [rows(T) for T in k.after],
            "base": rows(robot.chain.T_base),
            "to_si": robot.q_to_si(np.ones(robot.n)).tolist(),
            "scale_view": 1000.0 if u.length == "mm" else 1.0,
            "length_from_si": float(u.length_from_si(1.0)),
            "angle_from_si": float(u.angle_from_si(1.0)), "unit": u.length,
            "angle": u.angle, "axis_length": axis_length,
            # The surfaces as base64 typed arrays: float32 (a micrometre's precision, for the
            # picture only; the tool pose is computed in doubles) and int32.
            "body_link": _base64(bodies.link, np.int32),
            "body_vertices": _base64(bodies.vertices, np.float32)}


def _base64(a: NDArray, dtype) -> str:
    """An array as base64 of its little-endian bytes (the page reads it as a typed array)."""
    return base64.b64encode(np.ascontiguousarray(a, np.dtype(dtype).newbyteorder("<"))
                            .tobytes()).decode("ascii")


def view_page(robot: Robot, q: ArrayLike, *, bodies: Bodies | None = None,
              title: str = "") -> str:
    """The HTML of `armkit view`: the arm at q (n,) with a slider per joint (file units,
    within its limits; one turn where it has none) that moves it in the page, and the tool's
    pose. One file: plotly's script is inside it.

    The page's tool pose is also in its ``#tool-pose`` element's data: ``data-position`` (m,
    base frame) and ``data-matrix`` (the 4 x 4 pose, row-major), at full precision.
    """
    q = joint_array(robot, q)
    lo, hi = robot.chain.sampling_limits
    # The view holds the arm wherever the sliders can take it.
    reach = fk_frames(robot, np.random.default_rng(0).uniform(lo, hi, (REACH_SAMPLES, robot.n)))
    fig = show(robot, q, bodies=bodies, title=title, also=reach[..., :3, 3])
    fig.update_layout(height=None, autosize=True)
    bodies = bodies if bodies is not None else capsule_bodies(arm_geometry(robot))
    lo_file, hi_file, q_file = (robot.q_from_si(v) for v in (lo, hi, q))
    sliders = "".join(
        f'<label>{page_text(name)} ({unit}) <span class="value"></span>'
        f'<input type="range" data-joint="{j}" min="{lo_file[j]:.17g}" '
        f'max="{hi_file[j]:.17g}" step="any" value="{q_file[j]:.17g}"></label>'
        for j, (name, unit) in enumerate(zip(robot.joint_names, robot.joint_units)))
    chain = _chain_numbers(robot, bodies, fig.layout.meta["axis_length"])
    return PAGE.format(title=page_text(title or robot.name), plotly=plotly_script(),
                       sliders=sliders, unit=page_text(robot.units.length),
                       angle=page_text(robot.units.angle), figure=fig.to_json(),
                       chain=json.dumps(chain), script=SCRIPT)


def write_page(text: str, path: str | Path) -> Path:
    """Write a page (UTF-8)."""
    path = Path(path)
    path.write_text(text, encoding="utf-8")
    return path


def write_figure(fig: go.Figure, path: str | Path) -> Path:
    """Write a plotly figure as one HTML page that opens offline (plotly's script inside)."""
    path = Path(path)
    fig.write_html(path, include_plotlyjs=True, full_html=True, auto_play=False)
    return path
