"""`armkit traj`: a point-to-point or via-point trajectory case, its peaks and its figures.

The case (`armkit.io.trajectory_cases`) comes from a YAML file or from options (options
override the file), in the robot file's units. Positions outside the joint limits are bad
input (exit 2); velocities and accelerations beyond the limits are reported per joint, where
and by how much, and make the exit status 1 unless ``--allow-limits``; so do torques beyond
the torque limits, reported for a robot with inertias (`armkit.dynamics.torque_profile`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from armkit import trajectory as tj
from armkit.cli.command import (EXIT_FAILED, NUMBERS, JsonFlag, SiFlag, app, output_folder,
                                print_json, stdout)
from armkit.cli.values import COORDINATE, DURATION, LIMIT, number, parse_numbers, robot_text
from armkit.io.trajectory_cases import LimitExcess, TrajectoryCase, limit_excesses, read_case
from armkit.model import SI, Robot


def _numbers(name: str, text: str | None, low: float = -COORDINATE,
             high: float = COORDINATE) -> list[float] | None:
    return None if text is None else parse_numbers(f"--{name}", text, low=low, high=high)


def _rows(robot: Robot, tr: tj.Trajectory, s: tj.Stats, joints: list[int], units) -> list[dict]:
    """Peaks per joint in `units` (the file's, or SI), with the acceleration steps at the ends."""
    scale = robot.q_from_si(np.ones(robot.n)) if units is not SI else np.ones(robot.n)
    steps = tj.knot_jumps(tr).jump[[0, -1], 2]
    # Rounding leaves steps of 1e-15 where the conditions make them zero.
    steps = np.where(np.abs(steps) > 1e-9 * (1.0 + s.peak_acceleration), steps, 0.0) * scale
    return [{"joint": robot.joint_names[j], "number": j + 1,
             "unit": units.of_joint(robot.chain.revolute[j]),
             "peak_velocity": s.peak_velocity[j] * scale[j],
             "peak_acceleration": s.peak_acceleration[j] * scale[j],
             "peak_jerk": s.peak_jerk[j] * scale[j],
             "squared_jerk": s.squared_jerk[j] * scale[j] ** 2,
             "acceleration_step_at_start": steps[0, j],
             "acceleration_step_at_end": steps[1, j]} for j in joints]


def _fmt(x: float) -> str:
    return f"{x:.4g}"


@app.command(context_settings=NUMBERS)
def traj(
    case: Annotated[str, typer.Argument(help="A trajectory case file (.yaml, see the README), or "
                                             "a robot (built-in name or robot file) with the "
                                             "case given by options.")],
    start: Annotated[str | None, typer.Option(help="Start, all joints, file units, e.g. "
                                                   "--start=0,-90,0,0,0,0.")] = None,
    goal: Annotated[str | None, typer.Option(help="Goal, all joints, file units.")] = None,
    profile: Annotated[list[str] | None, typer.Option(
        help="cubic, quintic, trapezoidal or jerk-limited; repeat to compare "
             "(default quintic).")] = None,
    duration: Annotated[float | None, typer.Option(
        help="s, for cubic and quintic (default: shortest in limits).",
        parser=number(*DURATION, unit="s"))] = None,
    times: Annotated[str | None, typer.Option(help="Knot times (s), e.g. 0,2,4,5.")] = None,
    point: Annotated[list[str] | None, typer.Option(
        help="Via point (values of --joints, file units); repeat once per knot.")] = None,
    joints: Annotated[str | None, typer.Option(
        help="The joints --point gives, 1-based numbers or names (default all).")] = None,
    hold: Annotated[str | None, typer.Option(help="Where the other joints stay "
                                                  "(all joints, file units; default 0).")] = None,
    pattern: Annotated[list[str] | None, typer.Option(
        help="Degrees per segment, e.g. 4-5-5; repeat to compare (default 3-3-3, 4-5-5, "
             "5-5-5 for three segments).")] = None,
    velocity: Annotated[str | None, typer.Option(help="Velocity limit(s), file units/s.")] = None,
    acceleration: Annotated[str | None, typer.Option(help="Acceleration limit(s), "
                                                          "file units/s^2.")] = None,
    jerk: Annotated[str | None, typer.Option(help="Jerk limit(s), file units/s^3 (needed for "
                                                  "jerk-limited).")] = None,
    sync: Annotated[str | None, typer.Option(help="time (default) or phase (a straight "
                                                  "line in joint space).")] = None,
    out: Annotated[Path, typer.Option(help="Directory for the figures.")] = Path("."),
    allow_limits: Annotated[bool, typer.Option(
        "--allow-limits", help="Exit 0 even where velocities, accelerations or torques go "
                               "beyond the limits (they are still reported).")] = False,
    as_json: JsonFlag = False,
    si: SiFlag = False,
) -> None:
    """Point-to-point or via-point trajectories: the table of peaks, and their figures."""
    overrides = {"start": _numbers("start", start), "goal": _numbers("goal", goal),
                 "profiles": profile, "duration": duration,
                 "times": _numbers("times", times, -DURATION[1], DURATION[1]),
                 "points": [_numbers("point", p) for p in point] if point else None,
                 "joints": joints.replace(",", " ").split() if joints else None,
                 "hold": _numbers("hold", hold), "patterns": pattern, "sync": sync,
                 "velocity": _numbers("velocity", velocity, *LIMIT),
                 "acceleration": _numbers("acceleration", acceleration, *LIMIT),
                 "jerk": _numbers("jerk", jerk, *LIMIT)}
    robot_text("case", case)
    spec = read_case(case, overrides)
    robot = spec.robot
    stem = Path(case).stem if spec.source else f"{robot.name}_traj"
    out = output_folder(out, files=(f"{stem}_joints.png", f"{stem}_tool.png"))
    table = tj.compare(spec.trajectories)
    excesses = limit_excesses(spec)
    units = SI if si else robot.units
    figures = _figures(spec, out, stem)
    results = [{"label": label, "duration": s.duration, "knots": spec.trajectories[label].knots,
                "joints": _rows(robot, spec.trajectories[label], s, spec.moving, units)}
               for label, s in table.items()]
    beyond = [_excess_row(robot, e, units) for e in excesses]
    torques = _torque_rows(robot, spec.trajectories)
    over = [row for t in torques for row in t["joints"] if row["ratio"] > 1]
    if as_json:
        print_json({"robot": robot.name, "units": {"length": units.length,
                                                   "angle": units.angle},
                    "case": "via points" if spec.via else "point to point",
                    "trajectories": results, "figures": [str(f) for f in figures],
                    "limits": {"within": not excesses, "allowed": allow_limits,
                               "beyond": beyond},
                    "torques": torques})
    else:
        _print(robot, results, figures)
        _print_excesses(beyond, allow_limits)
        _print_torques(robot, torques, allow_limits)
    if (excesses or over) and not allow_limits:
        raise typer.Exit(EXIT_FAILED)


def _torque_rows(robot: Robot, trajectories: dict) -> list[dict]:
    """Each trajectory's peak joint torques against the torque limits (N m, N), when the robot
    has inertias (`armkit.dynamics.torque_profile`); none otherwise."""
    if robot.inertia is None:
        return []
    from armkit.dynamics import torque_profile

    rows = []
    for label, tr in trajectories.items():
        profile = torque_profile(robot, tr)
        rows.append({"label": label, "joints": [
            {"joint": robot.joint_names[j], "number": j + 1,
             "unit": "N m" if robot.chain.revolute[j] else "N",
             "peak": profile.peak[j], "time": profile.peak_time[j],
             "limit": profile.limits[j], "ratio": profile.ratio[j]} for j in range(robot.n)]})
    return rows


def _print_torques(robot: Robot, torques: list[dict], allowed: bool) -> None:
    if not torques:
        return
    table = Table("trajectory", "joint", "peak |torque|", "at t (s)", "limit", box=None,
                  title=f"{robot.name}: peak joint torques", title_justify="left")
    for t in torques:
        for i, row in enumerate(t["joints"]):
            table.add_row(t["label"] if i == 0 else "",
                          f"{row['number']} {row['joint']} ({row['unit']})", _fmt(row["peak"]),
                          f"{row['time']:.3g}",
                          _fmt(row["limit"]) if np.isfinite(row["limit"]) else "")
    stdout.print(table)
    over = [f"{t['label']}: joint {row['number']} {row['joint']} {row['ratio']:.3g} times its "
            f"limit" for t in torques for row in t["joints"] if row["ratio"] > 1]
    if over:
        stdout.print(f"beyond the torque limits{' (allowed: --allow-limits)' if allowed else ''}"
                     ": " + "; ".join(over), markup=False)
    else:
        stdout.print("within the torque limits")


def _excess_row(robot: Robot, e: LimitExcess, units) -> dict:
    """A limit excess in `units` (the file's, or SI) for print and JSON."""
    scale = 1.0 if units is SI else float(robot.q_from_si(np.ones(robot.n))[e.joint])
    unit = units.of_joint(robot.chain.revolute[e.joint])
    return {"trajectory": e.trajectory, "joint": robot.joint_names[e.joint],
            "number": e.joint + 1, "quantity": e.quantity, "time": e.time,
            "peak": e.peak * scale, "limit": e.limit * scale, "ratio": e.ratio,
            "unit": f"{unit}/s" if e.quantity == "velocity" else f"{unit}/s²"}


def _print_excesses(beyond: list[dict], allowed: bool) -> None:
    if not beyond:
        stdout.print("within the velocity and acceleration limits")
        return
    stdout.print(f"beyond the limits{' (allowed: --allow-limits)' if allowed else ''}:")
    for b in beyond:
        stdout.print(f"  {b['trajectory']}: joint {b['number']} {b['joint']} {b['quantity']} "
                     f"{_fmt(b['peak'])} {b['unit']} at t = {b['time']:.3g} s, limit "
                     f"{_fmt(b['limit'])} {b['unit']} ({b['ratio']:.3g} times)", markup=False)


def _figures(spec: TrajectoryCase, out: Path, stem: str) -> list[Path]:
    # Here, not at the top: matplotlib would slow down every other command's start.
    from armkit.report.trajectory import patterns_figure, tool_figure

    robot, trajectories = spec.robot, spec.trajectories
    shown = spec.moving or list(range(robot.n))
    title = (f"{robot.name}: joint{'s' if len(shown) > 1 else ''} "
             + ", ".join(str(j + 1) for j in shown) +
             (" through via points at t = " + ", ".join(
                 f"{t:g}" for t in next(iter(trajectories.values())).knots) + " s" if spec.via
              else ", point to point"))
    joints = patterns_figure(robot, trajectories, shown, rows=3 if spec.via else 4, title=title,
                             vmax=spec.velocity_limits, amax=spec.acceleration_limits)
    tool = tool_figure(robot, {k: tj.tool_motion(robot, v) for k, v in trajectories.items()})
    paths = [out / f"{stem}_joints.png", out / f"{stem}_tool.png"]
    for fig, path in zip((joints, tool), paths):
        fig.savefig(path, dpi=100)
    return paths


def _print(robot: Robot, results: list[dict], figures: list[Path]) -> None:
    table = Table("trajectory", "joint", "peak |v|", "peak |a|", "peak |j|", "∫j²dt",
                  "a step at ends", box=None, title=f"{robot.name}: peaks per joint",
                  title_justify="left")
    for r in results:
        for i, row in enumerate(r["joints"]):
            table.add_row(f"{r['label']} {_fmt(r['duration'])} s" if i == 0 else "",
                          f"{row['number']} {row['joint']} ({row['unit']})",
                          *(_fmt(row[k]) for k in ("peak_velocity", "peak_acceleration",
                                                   "peak_jerk", "squared_jerk")),
                          f"{_fmt(row['acceleration_step_at_start'])}, "
                          f"{_fmt(row['acceleration_step_at_end'])}")
    stdout.print(table)
    stdout.print("per unit of each joint: v /s, a /s², j /s³, ∫j²dt unit²/s⁵ (steps not "
                 "included)")
    stdout.print("figures: " + ", ".join(str(f) for f in figures))
