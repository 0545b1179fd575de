"""`armkit demo`: the end-to-end job on its built-in defaults, as far as it is built."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from armkit.cli.app import EXIT_FAILED, JsonFlag, app, output_folder, print_json, stdout
from armkit.spatial import matrix_to_rpy
from armkit.task import run_demo


def _pose(T: np.ndarray, units) -> tuple[np.ndarray, float]:
    """Position (file length units) and heading (file angle units) of a pose."""
    return units.length_from_si(T[:3, 3]), float(units.angle_from_si(matrix_to_rpy(T[:3, :3])[2]))


@app.command()
def demo(out: Annotated[Path, typer.Option(help="Folder for the figures.")] = Path("armkit-out"),
         as_json: JsonFlag = False) -> None:
    """Run the end-to-end job on the built-in water-supply robot and task."""
    report = run_demo(output_folder(out))
    robot, u = report.robot, report.robot.units
    seen, seen_yaw = _pose(report.task.target_in_camera, u)
    target, target_yaw = _pose(report.T_base_target, u)
    ik = report.ik
    if as_json:
        print_json({
            "robot": robot.name, "units": {"length": u.length, "angle": u.angle},
            "target": {"in_camera": {"position": seen, "yaw": seen_yaw},
                       "in_base": {"position": target, "yaw": target_yaw}},
            "ik": {"success": ik.success, "reason": str(ik.reason), "q": robot.q_from_si(ik.q),
                   "solutions": robot.q_from_si(report.solutions.q),
                   "within_limits": report.solutions.within_limits},
            "trajectory": None if report.trajectory is None else {
                "law": "quintic 10-15-6", "duration": report.trajectory.duration},
            "waypoints": {"t": report.t, "q": robot.q_from_si(report.q)},
            "drive": None if report.sent is None else {
                "waypoints": report.sent.waypoints, "last_accepted": report.sent.last_accepted,
                "seconds": report.sent.seconds},
            "figures": [str(p) for p in report.figures], "not_built": list(report.not_built)})
        raise typer.Exit(0 if ik.success else EXIT_FAILED)
    stdout.rule(f"armkit demo: {robot.name} ({robot.n} joints, file units {u.length}/{u.angle})")
    stdout.print(f"1. target: the camera sees the inlet at {_vector(seen)} {u.length}, heading "
                 f"{seen_yaw:.1f} {u.angle};\n   in the arm's base frame: {_vector(target)} "
                 f"{u.length}, yaw {target_yaw:.1f} {u.angle}")
    table = Table(*robot.joint_names, "within limits", box=None,
                  title=f"2. inverse kinematics ({ik.mask}): every solution", title_justify="left")
    for q, ok in zip(robot.q_from_si(report.solutions.q), report.solutions.within_limits):
        table.add_row(*[f"{v:.2f}" for v in q], "yes" if ok else "no")
    stdout.print(table)
    if not ik.success:
        stdout.print(f"   no solution: {ik.reason}")
        raise typer.Exit(EXIT_FAILED)
    stdout.print(f"   chosen, nearest the current configuration: {_vector(robot.q_from_si(ik.q))}")
    stdout.print(f"3. trajectory: quintic (10-15-6 law), {report.trajectory.duration:.3f} s, "
                 f"the shortest within the joint velocity and acceleration limits")
    table = Table("t (s)", *robot.joint_names, box=None, title_justify="left",
                  title=f"4. {len(report.t)} waypoints ({u.length}, {u.angle})")
    for t, q in zip(report.t, robot.q_from_si(report.q)):
        table.add_row(f"{t:.3f}", *[f"{v:.2f}" for v in q])
    stdout.print(table)
    stdout.print(f"5. drive: the simulated Modbus TCP drive took waypoints 0..{report.sent.last_accepted} "
                 f"in {report.sent.seconds * 1e3:.1f} ms, each written whole and acknowledged")
    stdout.print("6. figures: " + ", ".join(str(p) for p in report.figures))
    stdout.print("\nNot built yet: " + "; ".join(report.not_built) + ".")


def _vector(v) -> str:
    return " ".join(f"{x:.1f}" for x in np.ravel(v))
