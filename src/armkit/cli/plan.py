"""`armkit plan FILE.yaml`: a collision-free path and its waypoints, in the file's units."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from armkit.cli.command import EXIT_FAILED, JsonFlag, SiFlag, app, output_folder, print_json, stdout
from armkit.cli.values import number, shown
from armkit.io.documents import SEED
from armkit.errors import InputError
from armkit.model import SI

MAX_WAYPOINTS = 100_000         # as planning files allow (armkit.io.scene)


@app.command(name="plan")
def plan_command(
    file: Annotated[Path, typer.Argument(help="Planning file (.yaml): robot, obstacles, start, "
                                              "goal or goal_pose, planner settings.")],
    planner: Annotated[str | None, typer.Option(
        help="One of rrtconnect, rrt, rrtstar (default: the file's, else rrtconnect).")] = None,
    seed: Annotated[int | None, typer.Option(help="Seed (default: the file's).",
                                             parser=number(*SEED, integer=True))] = None,
    time_limit: Annotated[float | None, typer.Option(
        "--time-limit", help="Seconds for the whole search, at most 3600 (default: the "
        "file's, else 10).", parser=number(0.0, 3600.0, unit="s"))] = None,
    waypoints: Annotated[int | None, typer.Option(
        help="Resample the path to N waypoints evenly spaced in joint space.")] = None,
    out: Annotated[Path | None, typer.Option(
        help="Folder for the picture of the arm along the path.")] = None,
    as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """Plan a collision-free path; exit 1 with the reason when none is found."""
    from armkit.io.scene import read_planning_problem
    from armkit.planning import PLANNERS, CollisionChecker, PlanSettings, arm_geometry, plan

    if planner is not None and planner not in PLANNERS:
        raise InputError(f"--planner: expected one of {', '.join(PLANNERS)}, found "
                         f"{shown(planner)}")
    if waypoints is not None and not 2 <= waypoints <= MAX_WAYPOINTS:
        raise InputError(f"--waypoints: expected a whole number from 2 to {MAX_WAYPOINTS}, "
                         f"found {waypoints}")
    problem = read_planning_problem(file)
    robot, units = problem.robot, (SI if si else problem.units)
    if out is not None:
        out = output_folder(out, files=(f"{robot.name}_path.png",))
    settings = dict(problem.settings)
    for key, value in (("planner", planner), ("seed", seed), ("waypoints", waypoints),
                       ("time_limit", time_limit)):
        if value is not None:
            settings[key] = value
    resolution = settings.pop("resolution", 0.005)
    checker = CollisionChecker(robot, problem.scene, arm_geometry(robot, problem.radius),
                               resolution=resolution)
    result = plan(checker, problem.start, problem.goal, PlanSettings(**settings),
                  goal_pose=problem.goal_pose)
    figure = None
    if out is not None and result.success:
        from armkit.report.planning import save_path_figure
        figure = str(save_path_figure(checker, result.path, out, units))
    q_units = [units.of_joint(r) for r in robot.chain.revolute]
    convert = (lambda q: q) if si else robot.q_from_si
    doc = {"robot": robot.name, "success": result.success, "reason": result.reason,
           "planner": result.planner, "units": {"length": units.length, "angle": units.angle},
           "joint_units": q_units, "resolution": float(units.length_from_si(resolution)),
           "waypoints": convert(result.path) if result.success else [],
           "planning_time_s": result.planning_time, "total_time_s": result.total_time,
           "iterations": result.iterations, "states_checked": result.states_checked,
           "length_before_shortcut": result.raw_length, "length": result.length,
           "goals": convert(result.goals) if len(result.goals) else [], "figure": figure}
    if as_json:
        print_json(doc)
    else:
        _show(doc, robot)
    if not result.success:
        raise typer.Exit(EXIT_FAILED)


def _show(doc: dict, robot) -> None:
    if not doc["success"]:
        stdout.print(f"no path: {doc['reason']}  ({doc['iterations']} iterations, "
                     f"{doc['planning_time_s'] * 1e3:.3g} ms)")
        return
    stdout.print(f"{doc['planner']}: path found in {doc['planning_time_s'] * 1e3:.3g} ms "
                 f"({doc['iterations']} iterations, {doc['states_checked']} states checked); "
                 f"joint-space length {doc['length_before_shortcut']:.4g} -> {doc['length']:.4g}"
                 f"; every edge certified free (pieces down to {doc['resolution']:g} "
                 f"{doc['units']['length']})")
    table = Table("#", *[f"{n} ({u})" for n, u in zip(robot.joint_names, doc["joint_units"])],
                  box=None, title="waypoints", title_justify="left")
    for i, q in enumerate(doc["waypoints"]):
        table.add_row(str(i), *[f"{v:.6g}" for v in q])
    stdout.print(table)
    if doc["figure"]:
        stdout.print(f"figure: {doc['figure']}")
