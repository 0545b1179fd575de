"""The end-to-end job's report: ``summary.json``, the figures, and ``report.html``, one page
that holds everything (plotly's script once, the figures as data URIs) and opens alone.

The page shows the outcome first, then an interactive 3-D view of the arm moving along the
planned motion among the obstacles, the target, the IK solutions considered and the one chosen,
the planner's statistics, the motion and the checks it passed, the waypoints as sent and as the
drive holds them, the joint curves with their limits, the tool's path around the obstacles, and
the final error.

`check_report` runs before the job: the folder and every file of the report writable, and every
name from the task's files drawn once, so that nothing written after the arm has moved can fail
for a reason known before.
"""

from __future__ import annotations

import base64
import io
import json
import math
import os
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from armkit.errors import InputError
from armkit.io.tasks import CloudTarget, Task
from armkit.job.run import JobResult
from armkit.job.steps import motion_limits
from armkit.kinematics.forward import fk, fk_frames
from armkit.report.text import figure_text, page_text
from armkit.report.dynamics import torque_figure
from armkit.report.trajectory import motion_figure
from armkit.report.view import obstacle_mesh, plotly_script, show
from armkit.spatial import matrix_to_rpy

FILES = ("summary.json", "joints.png", "torques.png", "tool_path.png", "report.html")
"""What `write_report` writes, in this order: the record first."""

STYLE = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#222;background:#fafafa}
main{max-width:1200px;margin:auto;padding:16px 24px}
h1{font-size:1.5em;margin:.2em 0} h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ddd}
.outcome{padding:10px 14px;border-radius:6px;font-size:1.05em}
.ok{background:#e3f4e1;border:1px solid #8bc58a} .failed{background:#fbe4e2;border:1px solid #e29a93}
table{border-collapse:collapse;font-size:.9em;margin:.5em 0}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right} th{background:#f0f0f0}
td.l,th.l{text-align:left} tr.chosen td{background:#fff6d5;font-weight:600}
img{max-width:100%;border:1px solid #ddd;background:white} .note{color:#555;font-size:.9em}
"""


# --- before the job -------------------------------------------------------------------------

def check_report(task: Task, folder: str | Path) -> Path:
    """Check that the report can be written, before anything moves.

    The folder is created if missing; each of `FILES` must be a file that can be written (or
    none yet, in a folder that can be written); every name from the task's files (task,
    robot, joints, obstacles) is drawn once as the figures will draw it.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    InputError
        ``--out: expected a folder armkit can write report.html in, found a directory``.
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (OSError, ValueError) as err:
        raise InputError(f"--out: expected a folder armkit can write, found {folder} "
                         f"({getattr(err, 'strerror', None) or err})") from None
    if not folder.is_dir():
        raise InputError(f"--out: expected a folder, found {folder} (not a directory)")
    for name in FILES:
        path = folder / name
        existed = path.exists()
        if existed and not path.is_file():
            raise InputError(f"--out: expected a folder armkit can write {name} in, found "
                             f"{path} is not a regular file")
        try:
            with open(path, "a", encoding="utf-8"):
                pass
        except OSError as err:
            raise InputError(f"--out: expected a folder armkit can write {name} in, found "
                             f"{path}: {err.strerror or err}") from None
        if not existed:
            os.unlink(path)
    names = [task.name, task.robot.name, *task.robot.joint_names,
             *(o.name for o in task.scene if o.name)]
    figure = Figure(figsize=(2, 2))
    axes = figure.add_subplot()
    for name in names:
        axes.set_title(figure_text(name))
    figure.savefig(io.BytesIO(), format="png", dpi=20)
    return folder


# --- the record -----------------------------------------------------------------------------

def _num(x, digits: int = 3):
    return None if x is None or not np.isfinite(x) else round(float(x), digits)


def _q(robot, q) -> list | None:
    return None if q is None else np.round(robot.q_from_si(np.asarray(q)), 4).tolist()


def _pose(T, units) -> dict | None:
    if T is None:
        return None
    return {"xyz": np.round(units.length_from_si(T[:3, 3]), 4).tolist(),
            "rpy": np.round(units.angle_from_si(matrix_to_rpy(T[:3, :3])), 4).tolist()}


def summary(result: JobResult) -> dict:
    """The job as one JSON-serialisable document, lengths and angles in the task's units and
    joint values in the robot file's units (SI where the key says ``_m`` or ``_s``)."""
    task, robot = result.task, result.task.robot
    u = task.units
    target, choice, plan, motion = result.target, result.ik, result.plan, result.motion
    sent, arrival, final = result.sent, result.arrival, result.final
    per_s = [f"{unit}/s" for unit in robot.joint_units]
    return {
        "task": task.name, "robot": robot.name,
        "units": {"task": {"length": u.length, "angle": u.angle},
                  "joints": list(robot.joint_units)},
        "success": bool(result.success), "reason": result.reason or "ok",
        "stopped_at": result.stopped_at or None, "drive": result.drive,
        "target": {"in_camera": None if isinstance(task.target, CloudTarget) else
                   _pose(task.target.T_camera_target, u),
                   "in_base": None if target is None else _pose(target.T_base_target, u)},
        "detection": None if target is None or target.detection is None else
        _detection(target.detection, u),
        "q_current": _q(robot, result.q_current),
        "ik": None if choice is None or choice.solutions is None else {
            "solutions": _q(robot, choice.solutions),
            "within_limits": choice.within_limits.tolist(),
            "collision_free": choice.collision_free.tolist(),
            "clearance_m": [_num(c, 6) for c in choice.clearance],
            "chosen": choice.chosen if choice.chosen >= 0 else None, "why": choice.why},
        "plan": None if plan is None else {
            "success": bool(plan.success), "reason": plan.reason, "planner": plan.planner,
            "planning_time_s": _num(plan.planning_time, 6),
            "shortcut_time_s": _num(plan.shortcut_time, 6),
            "iterations": int(plan.iterations), "states_checked": int(plan.states_checked),
            "raw_vertices": len(plan.raw_path), "raw_length": _num(plan.raw_length, 6),
            "length": _num(plan.length, 6), "path": _q(robot, plan.path)},
        "motion": None if motion is None or motion.trajectory is None else {
            "duration_s": _num(motion.trajectory.duration, 4), "how": motion.how,
            "peak_jerk": dict(zip([f"{n} ({unit}^3)" for n, unit in zip(robot.joint_names,
                                                                          per_s)],
                                  _peaks(robot, motion.trajectory)))},
        "checks": None if result.checks is None else dict(result.checks.items),
        "torques": None if result.checks is None or result.checks.torques is None else {
            "peak": [_num(x, 4) for x in result.checks.torques.peak],
            "limit": [_num(x, 4) for x in result.checks.torques.limits],
            "units": ["N m" if r else "N" for r in robot.chain.revolute]},
        "waypoints": None if motion is None or motion.q is None else {
            "t_s": np.round(motion.t, 4).tolist(), "q": _q(robot, motion.q)},
        "sent": None if sent is None else {"waypoints": sent.waypoints,
                                           "last_accepted": sent.last_accepted},
        "executed": {"samples": len(result.executed[0])},
        "q_reported": None if arrival is None else _q(robot, arrival.q_reported),
        "q_final": None if arrival is None else _q(robot, arrival.q_final),
        "position_error": None if final is None else {
            "m": float(final.position_error), u.length: float(u.length_from_si(
                final.position_error)), "drive_resolution_m": float(final.resolution)},
        "timings_s": {k: round(v, 4) for k, v in result.timings.items()},
    }


def _peaks(robot, trajectory) -> list[float]:
    """Peak |jerk| of each joint (file units/s^3), on 10 kHz samples."""
    s = trajectory.sample(np.arange(trajectory.start, trajectory.end, 1e-4))
    return [round(float(v), 3) for v in robot.q_from_si(np.abs(s.qddd).max(axis=0))]


def _detection(found, units) -> dict:
    """What the cloud search found, in the task's units."""
    return {"cloud": found.source, "success": bool(found.success), "reason": found.reason,
            "kind": found.kind, "in_sensor": _pose(found.T_sensor_target, units)
            if found.success else None,
            f"radius_{units.length}": _num(units.length_from_si(found.radius), 3)
            if found.success else None, "radius_known": bool(found.radius_known),
            "wall_inliers": int(found.plane_inliers), "cluster_size": int(found.cluster_size),
            f"fit_rms_{units.length}": _num(units.length_from_si(found.fit_rms), 4),
            "points_dropped": int(found.dropped)}


# --- the figures ----------------------------------------------------------------------------

def tool_path_figure(result: JobResult) -> Figure:
    """The tool's path around the obstacles: in 3-D, seen from above (x, y) and from the side
    (x, z), with the waypoints sent, the target, the arm at the start and at the end (its joint
    origins), and the path as the drive reported it; task length units."""
    task, robot = result.task, result.task.robot
    u = task.units
    fig = Figure(figsize=(15, 5.4), layout="constrained")
    ax3 = fig.add_subplot(1, 3, 1, projection="3d")
    top, side = fig.add_subplot(1, 3, 2), fig.add_subplot(1, 3, 3)
    drawn: list[NDArray] = []
    for o in task.scene:
        v, f = obstacle_mesh(o)
        v = u.length_from_si(v)
        drawn.append(v)
        for ax, (i, j) in ((top, (0, 1)), (side, (0, 2))):
            try:
                hull = v[:, [i, j]][ConvexHull(v[:, [i, j]]).vertices]
            except QhullError:                  # flat in this view
                continue
            ax.fill(hull[:, 0], hull[:, 1], color="tab:red", alpha=0.35, lw=0)
        ax3.add_collection3d(Poly3DCollection(v[f], facecolor="tab:red", alpha=0.25,
                                              edgecolor="none"))
    motion = result.motion
    if motion is not None and motion.trajectory is not None:
        q = motion.trajectory.sample_uniform(400).q
        p = u.length_from_si(fk(robot, q)[:, :3, 3])
        w = u.length_from_si(fk(robot, motion.q)[:, :3, 3])
        drawn += [p, w]
        for ax, idx in ((ax3, [0, 1, 2]), (top, [0, 1]), (side, [0, 2])):
            ax.plot(*p[:, idx].T, color="tab:green", lw=2.5, zorder=3,
                    label="tool path (planned motion)")
            ax.scatter(*w[:, idx].T, s=22, zorder=4, facecolor="white", edgecolor="tab:blue",
                       linewidth=1.2, label=f"{len(w)} waypoints sent")
        for k, (q_arm, shade) in enumerate(((q[0], "0.55"), (q[-1], "0.2"))):
            o = u.length_from_si(fk_frames(robot, q_arm)[:, :3, 3])
            drawn.append(o)
            for ax, idx in ((ax3, [0, 1, 2]), (top, [0, 1]), (side, [0, 2])):
                ax.plot(*o[:, idx].T, color=shade, lw=1.2, marker="o", ms=3,
                        label="arm at the start" if k == 0 else "arm at the end")
    executed = result.executed[1]
    if len(executed):
        e = u.length_from_si(fk(robot, executed)[:, :3, 3])
        for ax, idx in ((ax3, [0, 1, 2]), (top, [0, 1]), (side, [0, 2])):
            ax.plot(*e[:, idx].T, color="tab:purple", lw=1, ls="--",
                    label="tool as the drive reported it")
    if result.target is not None and result.target.T_base_target is not None:
        t = u.length_from_si(result.target.T_base_target[:3, 3])
        drawn.append(t[None])
        for ax, idx in ((ax3, [0, 1, 2]), (top, [0, 1]), (side, [0, 2])):
            ax.scatter(*t[idx], color="tab:orange", s=90, marker="*", zorder=4, label="target")
    for ax in (top, side):
        ax.fill([], [], color="tab:red", alpha=0.35, label="obstacles")
    points = np.vstack(drawn) if drawn else np.zeros((1, 3))
    lo, hi = points.min(axis=0), points.max(axis=0)
    c, h = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-9) * 1.08
    for set_lim, i in ((ax3.set_xlim, 0), (ax3.set_ylim, 1), (ax3.set_zlim, 2)):
        set_lim(c[i] - h, c[i] + h)
    ax3.set_xlabel(f"x ({u.length})", labelpad=8)
    ax3.set_ylabel(f"y ({u.length})", labelpad=8)
    ax3.set_zlabel(f"z ({u.length})", labelpad=8)
    ax3.set_box_aspect((1, 1, 1), zoom=0.85)
    ax3.set_title("in 3-D")
    for ax, (i, j), name in ((top, (0, 1), "from above"), (side, (0, 2), "from the side")):
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{'xyz'[i]} ({u.length})")
        ax.set_ylabel(f"{'xyz'[j]} ({u.length})")
        ax.set_title(name)
        ax.grid(alpha=0.3)
    side.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.suptitle(f"{figure_text(robot.name)}: the tool's path to the target, around the "
                 f"obstacles (base frame)", fontsize=12)
    return fig


def _png(fig: Figure, path: Path) -> bytes:
    """Save a figure as PNG to `path`; its bytes."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    data = buffer.getvalue()
    path.write_bytes(data)
    return data


# --- the page -------------------------------------------------------------------------------

def write_report(result: JobResult, folder: str | Path) -> list[Path]:
    """Write the report into `folder`: ``summary.json`` first, then the figures
    (``joints.png``; ``torques.png`` for a robot with inertias; ``tool_path.png``), then
    ``report.html``, which holds them all.

    Returns
    -------
    list of Path
        The files written, in that order.

    Raises
    ------
    OSError
        If a file cannot be written (`check_report` finds what can be found before the job).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    task, robot = result.task, result.task.robot
    doc = summary(result)
    written = [folder / "summary.json"]
    written[0].write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    figures = []
    motion = result.motion
    if motion is not None and motion.trajectory is not None:
        V, A, J = motion_limits(task)
        fig = motion_figure(robot, motion.trajectory, vmax=V, amax=A, jmax=J)
        figures.append(("Joint motion (limits dashed)", _png(fig, folder / "joints.png")))
        written.append(folder / "joints.png")
    if result.checks is not None and result.checks.torques is not None:
        fig = torque_figure(robot, result.checks.torques)
        figures.append(("Joint torques (limits dashed)", _png(fig, folder / "torques.png")))
        written.append(folder / "torques.png")
    if result.target is not None and result.target.T_base_target is not None:
        figures.append(("The tool's path around the obstacles",
                        _png(tool_path_figure(result), folder / "tool_path.png")))
        written.append(folder / "tool_path.png")
    (folder / "report.html").write_text(_page(result, doc, figures), encoding="utf-8")
    return written + [folder / "report.html"]


def _table(header: list[str], rows: list[list], chosen: int | None = None,
           left: int = 0) -> str:
    cls = lambda i: ' class="l"' if i < left else ""
    out = ["<table><tr>" + "".join(f"<th{cls(i)}>{page_text(h)}</th>"
                                   for i, h in enumerate(header)) + "</tr>"]
    for r, row in enumerate(rows):
        mark = ' class="chosen"' if r == chosen else ""
        out.append(f"<tr{mark}>" + "".join(f"<td{cls(i)}>{page_text(c)}</td>"
                                           for i, c in enumerate(row)) + "</tr>")
    return "\n".join(out + ["</table>"])


def _fmt(x: float | None) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.3f}"


def _view(result: JobResult) -> str:
    """The 3-D view as a div (plotly's script is in the page's head)."""
    task, robot = result.task, result.task.robot
    motion = result.motion
    q = (motion.trajectory if motion is not None and motion.trajectory is not None else
         result.q_current if result.q_current is not None else
         task.start if task.start is not None else np.clip(0.0, robot.lower, robot.upper))
    target = None if result.target is None else result.target.T_base_target
    fig = show(robot, q, scene=task.scene, target=target,
               title=f"{robot.name}: the planned motion among the obstacles")
    return fig.to_html(full_html=False, include_plotlyjs=False, auto_play=False,
                       div_id="view3d")


def _page(result: JobResult, doc: dict, figures: list[tuple[str, bytes]]) -> str:
    task, robot = result.task, result.task.robot
    u = task.units
    jn = [f"{n} ({unit})" for n, unit in zip(robot.joint_names, robot.joint_units)]
    final = result.final
    if result.success:
        head = (f"Done: the tool is {u.length_from_si(final.position_error):.4f} {u.length} "
                f"from the target (the drive's resolution allows "
                f"{u.length_from_si(final.resolution):.4f} {u.length}).")
    else:
        head = f"Stopped at {result.stopped_at or 'the end'}: {result.reason}"
    parts = [f"<h1>armkit run: {page_text(task.name)}</h1>",
             f'<p class="note">robot {page_text(robot.name)} ({robot.n} joints); '
             f"{page_text(result.drive)}; lengths in {u.length}, angles in {u.angle}</p>",
             f'<div class="outcome {"ok" if result.success else "failed"}">'
             f"{page_text(head)}</div>",
             "<h2>The motion in 3-D</h2>",
             '<p class="note">The arm as its collision capsules, with a frame at the base, at '
             "every joint and at the tool; obstacles in red, the tool's path in green. Drag to "
             "turn, scroll to zoom; play/pause and the slider below the view.</p>",
             _view(result)]
    target = dict(doc["target"])
    if doc["detection"] is not None:
        target["in_sensor"] = doc["detection"]["in_sensor"]
    parts += ["<h2>Target</h2>", _table(
        ["frame", f"x, y, z ({u.length})", f"roll, pitch, yaw ({u.angle})"],
        [[k.replace("_", " "), ", ".join(f"{v:.2f}" for v in p["xyz"]),
          ", ".join(f"{v:.2f}" for v in p["rpy"])] for k, p in target.items() if p], left=1)]
    if doc["detection"] is not None:
        d = doc["detection"]
        parts.append(f'<p class="note">Found in the point cloud {page_text(d["cloud"])}: '
                     f'{page_text(d["reason"])}; wall inliers {d["wall_inliers"]}, cluster '
                     f'{d["cluster_size"]} points, circle fit RMS '
                     f'{d[f"fit_rms_{u.length}"]} {u.length}.</p>')
    choice = result.ik
    if choice is not None and choice.solutions is not None:
        rows = [[i + 1, *[f"{v:.3f}" for v in q], "yes" if lim else "no",
                 "yes" if free else "no", _fmt(u.length_from_si(c))]
                for i, (q, lim, free, c) in enumerate(zip(robot.q_from_si(choice.solutions),
                                                          choice.within_limits,
                                                          choice.collision_free,
                                                          choice.clearance))]
        parts += ["<h2>Inverse kinematics: every solution considered</h2>",
                  _table(["#", *jn, "within limits", "collision-free",
                          f"clearance ({u.length})"], rows,
                         chosen=choice.chosen if choice.chosen >= 0 else None),
                  f'<p class="note">{page_text(choice.why or choice.reason)}</p>']
    if result.plan is not None:
        p = doc["plan"]
        parts += ["<h2>Planner</h2>", _table(["", "value"], [
            ["planner", p["planner"]], ["result", p["reason"]],
            ["planning time (ms)", _fmt((p["planning_time_s"] or 0) * 1e3)],
            ["iterations", p["iterations"]], ["states checked", p["states_checked"]],
            ["path before shortcutting: vertices, joint-space length", f"{p['raw_vertices']}, "
             f"{_fmt(p['raw_length'])}"],
            ["after shortcutting and resampling: length", _fmt(p["length"])],
            ["shortcutting (ms)", _fmt((p["shortcut_time_s"] or 0) * 1e3)]], left=1)]
    motion = result.motion
    if motion is not None and motion.trajectory is not None:
        parts += ["<h2>Motion</h2>",
                  f'<p class="note">{motion.trajectory.duration:.3f} s; '
                  f"{page_text(motion.how)}.</p>"]
        if result.checks is not None:
            parts.append(_table(["checked before sending", "verdict"],
                                [list(item) for item in result.checks.items], left=2))
    if motion is not None and motion.q is not None:
        held = _held(result)
        last = -1 if result.sent is None or result.sent.last_accepted is None else \
            result.sent.last_accepted
        rows = []
        for k, (t, q) in enumerate(zip(motion.t, robot.q_from_si(motion.q))):
            taken = k <= last
            rows.append([k, f"{t:.3f}", *[f"{v:.3f}" for v in q], "yes" if taken else "no",
                         *([f"{v:.3f}" for v in held[k]] if taken else [])])
        parts += ["<h2>Waypoints: as sent and as the drive holds them</h2>",
                  _table(["#", "t (s)", *jn, "acknowledged", *[f"held: {n}" for n in jn]],
                         rows)]
    for title, data in figures:
        uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
        parts += [f"<h2>{page_text(title)}</h2>",
                  f'<img src="{uri}" alt="{page_text(title)}">']
    if result.arrival is not None and result.arrival.q_reported is not None:
        rows = [["joints the drive last reported",
                 ", ".join(f"{v:.4f}" for v in robot.q_from_si(result.arrival.q_reported))]]
        if final is not None:
            rows += [[f"tool position error ({u.length})",
                      f"{u.length_from_si(final.position_error):.5f}"],
                     [f"drive's resolution at the tool ({u.length})",
                      f"{u.length_from_si(final.resolution):.5f}"]]
        parts += ["<h2>Where the drive ended</h2>", _table(["", "value"], rows, left=1)]
    parts += ["<h2>Timings</h2>", _table(["step", "s"], [[k, f"{v:.3f}"] for k, v in
                                                       result.timings.items()], left=1),
              '<p class="note">Beside this page: summary.json (everything above, machine '
              "readable) and the figures as PNG files. The page needs nothing else.</p>"]
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>armkit run: {page_text(task.name)}</title><style>{STYLE}</style>"
            f"<script>{plotly_script()}</script></head><body><main>\n"
            + "\n".join(parts) + "\n</main></body></html>\n")


def _held(result: JobResult) -> NDArray:
    """The waypoints as the drive's registers hold them (file units): encoded and decoded as
    the register map does, which is what the client's read-back compares against."""
    m = result.task.drive.register_map
    return m.decode_file(m.encode_file(result.task.robot.q_from_si(result.motion.q)))
