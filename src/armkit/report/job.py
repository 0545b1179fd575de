"""The end-to-end job's report: ``report.html`` (opens offline), ``summary.json`` and figures.

The page shows the outcome first, then an interactive 3-D view of the arm moving along the
planned motion among the obstacles, the joint curves with their limits, the tool's path, the IK
solutions considered and the one chosen, the planner's statistics, the waypoints as sent and as
the drive holds them, and the final error. Every script, style and image is inside the folder
or inline.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path

import numpy as np

from armkit.task import JobResult

STYLE = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#222;background:#fafafa}
main{max-width:1100px;margin:auto;padding:16px 24px}
h1{font-size:1.5em;margin:.2em 0} h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ddd}
.outcome{padding:10px 14px;border-radius:6px;font-size:1.05em}
.ok{background:#e3f4e1;border:1px solid #8bc58a} .failed{background:#fbe4e2;border:1px solid #e29a93}
table{border-collapse:collapse;font-size:.9em;margin:.5em 0}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right} th{background:#f0f0f0}
td.l,th.l{text-align:left} tr.chosen td{background:#fff6d5;font-weight:600}
img{max-width:100%;border:1px solid #ddd;background:white} .note{color:#555;font-size:.9em}
"""


def _num(x, digits: int = 3):
    return None if x is None or not np.isfinite(x) else round(float(x), digits)


def _q(robot, q) -> list | None:
    return None if q is None else np.round(robot.q_from_si(np.asarray(q)), 4).tolist()


def _pose(T, units) -> dict | None:
    from armkit.spatial import matrix_to_rpy

    if T is None:
        return None
    return {"xyz": np.round(units.length_from_si(T[:3, 3]), 4).tolist(),
            "rpy": np.round(units.angle_from_si(matrix_to_rpy(T[:3, :3])), 4).tolist()}


def summary(result: JobResult) -> dict:
    """The job as one JSON-serialisable document, lengths and angles in the task's units and
    joint values in the robot file's units (SI where the key says ``_m``)."""
    task, robot = result.task, result.task.robot
    u = task.units
    plan = result.plan
    doc = {
        "task": task.name, "robot": robot.name,
        "units": {"task": {"length": u.length, "angle": u.angle},
                  "joints": list(robot.joint_units)},
        "success": bool(result.success), "reason": result.reason or "ok",
        "stopped_at": result.stopped_at or None, "drive": result.drive,
        "target": {"in_camera": _pose(task.T_camera_target, u),
                   "in_base": _pose(result.T_base_target, u)},
        "detection": None if result.detection is None else _detection(result.detection, u),
        "q_current": _q(robot, result.q_current),
        "ik": None if result.solutions is None else {
            "solutions": _q(robot, result.solutions),
            "within_limits": result.within_limits.tolist(),
            "collision_free": result.collision_free.tolist(),
            "clearance_m": [_num(c, 6) for c in result.clearance],
            "chosen": result.chosen if result.chosen >= 0 else None, "why": result.choice},
        "plan": None if plan is None else {
            "success": bool(plan.success), "reason": plan.reason, "planner": plan.planner,
            "planning_time_s": _num(plan.planning_time, 6),
            "shortcut_time_s": _num(plan.shortcut_time, 6),
            "iterations": int(plan.iterations), "states_checked": int(plan.states_checked),
            "raw_vertices": len(plan.raw_path), "raw_length": _num(plan.raw_length, 6),
            "length": _num(plan.length, 6), "path": _q(robot, plan.path)},
        "trajectory": None if result.trajectory is None else {
            "duration_s": _num(result.trajectory.duration, 4), "how": result.trajectory_note},
        "waypoints": None if result.q is None else {
            "t_s": np.round(result.t, 4).tolist(), "q": _q(robot, result.q)},
        "sent": result.sent,
        "executed": None if result.executed_q is None else {
            "samples": len(result.executed_q)},
        "q_final": _q(robot, result.q_final),
        "position_error": None if not np.isfinite(result.position_error) else {
            "m": float(result.position_error),
            u.length: float(u.length_from_si(result.position_error)),
            "drive_resolution_m": float(result.resolution)},
        "timings_s": {k: round(v, 4) for k, v in result.timings.items()},
    }
    return doc


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


def _table(header: list[str], rows: list[list], chosen: int | None = None,
           left: int = 0) -> str:
    cls = lambda i: ' class="l"' if i < left else ""
    out = ["<table><tr>" + "".join(f"<th{cls(i)}>{html.escape(h)}</th>"
                                   for i, h in enumerate(header)) + "</tr>"]
    for r, row in enumerate(rows):
        mark = ' class="chosen"' if r == chosen else ""
        out.append(f"<tr{mark}>" + "".join(f"<td{cls(i)}>{html.escape(str(c))}</td>"
                                           for i, c in enumerate(row)) + "</tr>")
    return "\n".join(out + ["</table>"])


def _fmt(x: float) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.3f}"


def tool_path_figure(result: JobResult):
    """The tool's path in 3-D (task length units) with the waypoints, the target and the
    obstacles."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from armkit.kinematics import fk
    from armkit.report.view import obstacle_mesh

    task, robot = result.task, result.task.robot
    u = task.units
    s = u.length_from_si(1.0)
    fig = Figure(figsize=(7.5, 6.5), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    points = [u.length_from_si(result.T_base_target[:3, 3])[None]]
    if result.trajectory is not None:
        q = result.trajectory.sample_uniform(300).q
        p = u.length_from_si(fk(robot, q)[:, :3, 3])
        ax.plot(*p.T, color="tab:green", lw=2, label="tool path (planned motion)")
        w = u.length_from_si(fk(robot, result.q)[:, :3, 3])
        ax.scatter(*w.T, color="tab:blue", s=18, label=f"{len(w)} waypoints sent")
        points += [p]
    if result.executed_q is not None and len(result.executed_q):
        e = u.length_from_si(fk(robot, result.executed_q)[:, :3, 3])
        ax.plot(*e.T, color="tab:purple", lw=1, ls="--", label="tool as the drive reported it")
    t = points[0][0]
    ax.scatter(*t, color="tab:orange", s=80, marker="*", label="target")
    for o in task.scene or ():
        v, f = obstacle_mesh(o)
        ax.add_collection3d(Poly3DCollection(v[f] * s, alpha=0.25, facecolor="tab:red",
                                             edgecolor="none"))
        points.append(v * s)
    ax.plot([], [], color="tab:red", alpha=0.4, lw=6, label="obstacles")
    allp = np.vstack(points)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    c, h = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-9) * 1.05
    for set_lim, i in ((ax.set_xlim, 0), (ax.set_ylim, 1), (ax.set_zlim, 2)):
        set_lim(c[i] - h, c[i] + h)
    ax.set_xlabel(f"x ({u.length})")
    ax.set_ylabel(f"y ({u.length})")
    ax.set_zlabel(f"z ({u.length})")
    ax.set_title(f"{robot.name}: tool path to the target")
    ax.legend(loc="upper left", fontsize=8)
    return fig


def write_report(result: JobResult, folder: str | Path) -> list[Path]:
    """Write ``report.html``, ``summary.json``, the figures and ``plotly.min.js`` to `folder`.

    Returns
    -------
    list of Path
        The files written, the page first.
    """
    from armkit.report.trajectory import motion_figure
    from armkit.report.view import robot_view, write_plotly_script

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    task, robot = result.task, result.task.robot
    doc = summary(result)
    written = []
    (folder / "summary.json").write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n",
                                         encoding="utf-8")
    figures = []
    if result.trajectory is not None:
        motion_figure(robot, result.trajectory).savefig(folder / "joints.png", dpi=90)
        figures.append(("Joint motion (limits drawn)", "joints.png"))
    if result.T_base_target is not None:
        tool_path_figure(result).savefig(folder / "tool_path.png", dpi=90)
        figures.append(("The tool's path", "tool_path.png"))
    motion = result.trajectory.sample_uniform(200) if result.trajectory is not None else None
    q_view = motion.q if motion is not None else (result.q_current if result.q_current is not None
                                                   else task.start if task.start is not None
                                                   else np.zeros(robot.n))
    view = robot_view(robot, q_view, scene=task.scene, target=result.T_base_target,
                      t=None if motion is None else motion.t,
                      title=f"{robot.name}: the planned motion among the obstacles")
    write_plotly_script(folder)
    view_div = view.to_html(full_html=False, include_plotlyjs=False, auto_play=False,
                            div_id="view3d")
    page = _page(result, doc, figures, view_div)
    (folder / "report.html").write_text(page, encoding="utf-8")
    written = [folder / "report.html", folder / "summary.json", folder / "plotly.min.js"]
    return written + [folder / name for _, name in figures]


def _page(result: JobResult, doc: dict, figures, view_div: str) -> str:
    task, robot = result.task, result.task.robot
    u = task.units
    jn = [f"{n} ({unit})" for n, unit in zip(robot.joint_names, robot.joint_units)]
    ok = result.success
    if ok:
        head = (f"Done: the tool is {u.length_from_si(result.position_error):.4f} {u.length} "
                f"from the target (the drive's resolution allows "
                f"{u.length_from_si(result.resolution):.4f} {u.length}).")
    else:
        head = f"Stopped at {result.stopped_at or 'the end'}: {result.reason}"
    parts = [f"<h1>armkit run: {html.escape(task.name)}</h1>",
             f'<p class="note">robot {html.escape(robot.name)} ({robot.n} joints); '
             f"{html.escape(result.drive)}; lengths in {u.length}, angles in {u.angle}</p>",
             f'<div class="outcome {"ok" if ok else "failed"}">{html.escape(head)}</div>',
             "<h2>The motion in 3-D</h2>",
             '<p class="note">Links as their collision capsules, obstacles in red; drag to '
             "turn, scroll to zoom, play/pause and the slider below the view.</p>", view_div]
    target = dict(doc["target"])
    if doc["detection"] is not None:
        target["in_sensor"] = doc["detection"]["in_sensor"]
    parts += ["<h2>Target</h2>", _table(
        ["frame", f"x, y, z ({u.length})", f"roll, pitch, yaw ({u.angle})"],
        [[k.replace("_", " "), ", ".join(f"{v:.2f}" for v in p["xyz"]),
          ", ".join(f"{v:.2f}" for v in p["rpy"])] for k, p in target.items() if p], left=1)]
    if doc["detection"] is not None:
        d = doc["detection"]
        parts += [f'<p class="note">Found in the point cloud {html.escape(str(d["cloud"]))}: '
                  f'{html.escape(d["reason"])}; wall inliers {d["wall_inliers"]}, cluster '
                  f'{d["cluster_size"]} points, circle fit RMS '
                  f'{d[f"fit_rms_{u.length}"]} {u.length}.</p>']
    if result.solutions is not None:
        rows = [[i + 1, *[f"{v:.3f}" for v in q], "yes" if lim else "no",
                 "yes" if free else "no", _fmt(u.length_from_si(c))]
                for i, (q, lim, free, c) in enumerate(zip(robot.q_from_si(result.solutions),
                                                          result.within_limits,
                                                          result.collision_free,
                                                          result.clearance))]
        parts += ["<h2>Inverse kinematics: every solution considered</h2>",
                  _table(["#", *jn, "within limits", "collision-free",
                          f"clearance ({u.length})"], rows,
                         chosen=result.chosen if result.chosen >= 0 else None),
                  f'<p class="note">{html.escape(result.choice or "none chosen")}</p>']
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
    if result.trajectory is not None:
        parts.append(f'<p class="note">Trajectory: {result.trajectory.duration:.3f} s; '
                     f"{html.escape(result.trajectory_note)}.</p>")
    if result.q is not None:
        held = _held(result)
        rows = []
        for k, (t, q) in enumerate(zip(result.t, robot.q_from_si(result.q))):
            sent = result.sent is not None and k <= result.sent["last_accepted"]
            rows.append([k, f"{t:.3f}", *[f"{v:.3f}" for v in q], "yes" if sent else "no",
                         *([f"{v:.3f}" for v in held[k]] if sent and held is not None else [])])
        extra = [f"held: {n}" for n in jn] if held is not None else []
        parts += ["<h2>Waypoints: as sent and as the drive holds them</h2>",
                  _table(["#", "t (s)", *jn, "acknowledged", *extra], rows)]
    for title, name in figures:
        parts += [f"<h2>{html.escape(title)}</h2>", f'<img src="{name}" alt="{html.escape(title)}">']
    if np.isfinite(result.position_error):
        parts += ["<h2>Final error</h2>", _table(["", "value"], [
            ["joints at arrival", ", ".join(f"{v:.4f}" for v in robot.q_from_si(result.q_final))],
            [f"tool position error ({u.length})", f"{u.length_from_si(result.position_error):.5f}"],
            [f"drive's resolution at the tool ({u.length})",
             f"{u.length_from_si(result.resolution):.5f}"]], left=1)]
    parts += ["<h2>Timings</h2>", _table(["step", "s"], [[k, f"{v:.3f}"] for k, v in
                                                       result.timings.items()], left=1),
              '<p class="note">Also in this folder: summary.json (everything above, machine '
              "readable).</p>"]
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>armkit run: {html.escape(task.name)}</title><style>{STYLE}</style>"
            '<script src="plotly.min.js"></script></head><body><main>\n'
            + "\n".join(parts) + "\n</main></body></html>\n")


def _held(result: JobResult):
    """The waypoints as the drive's registers hold them (file units): encoded and decoded as
    the register map does, which is what the client's read-back compares against."""
    m = result.drive_map
    if m is None:
        return None
    return m.decode_file(m.encode_file(result.task.robot.q_from_si(result.q)))
