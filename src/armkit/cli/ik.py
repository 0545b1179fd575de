"""`armkit ik ROBOT --pose X Y Z [--rpy R P Y | --yaw Y] [--q0 ...] [--all]`."""

from __future__ import annotations

from typing import Annotated, Optional

import numpy as np
import typer
from rich.table import Table

from armkit.cli.command import EXIT_FAILED, JsonFlag, SiFlag, app, print_json, stdout
from armkit.cli.robots import RobotArg
from armkit.cli.values import load_robot, number, parse_numbers
from armkit.errors import InputError
from armkit.kinematics.ik import CRITERIA, METHODS, NAMED_MASKS, IKSolver
from armkit.model import SI
from armkit.spatial import pose_from_xyz_rpy

Triple = tuple[float, float, float]
# Angles typed at the command line, deg or rad: a million turns is past any meaning.
ANGLE = 4e8


@app.command(name="ik")
def ik_command(
    robot: RobotArg,
    pose: Annotated[Triple, typer.Option(
        "--pose", metavar="X Y Z", parser=number(),
        help="Target position: three numbers separated by spaces, file units.")],
    rpy: Annotated[Optional[Triple], typer.Option(
        "--rpy", metavar="R P Y", parser=number(-ANGLE, ANGLE),
        help="Target roll pitch yaw (three numbers separated by spaces), file units: a full "
             "orientation.")] = None,
    yaw: Annotated[Optional[float], typer.Option(
        "--yaw", parser=number(-ANGLE, ANGLE),
        help="Target yaw only (position + yaw task), file units.")] = None,
    pitch: Annotated[Optional[float], typer.Option(
        "--pitch", parser=number(-ANGLE, ANGLE),
        help="Tool pitch in the vertical plane through the target (yaw-and-pitch arms), file "
             "units.")] = None,
    q0: Annotated[Optional[str], typer.Option(
        "--q0", help="Current configuration, file units, spaces or commas between the values, "
                     "e.g. '0 -90 90 0 0 0'.")] = None,
    all_solutions: Annotated[bool, typer.Option(
        "--all", help="List every closed-form solution (an arm without one: says so).")] = False,
    mask: Annotated[Optional[str], typer.Option(
        "--mask", help=f"Task: {', '.join(NAMED_MASKS)} (default: from --rpy/--yaw).")] = None,
    method: Annotated[str, typer.Option(help=f"One of {', '.join(METHODS)}.")] = "auto",
    criterion: Annotated[str, typer.Option(
        help=f"Choice among solutions: {', '.join(CRITERIA)}.")] = "nearest",
    as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """Joint values that reach a target pose; exit 1 with the reason if none does."""
    model = load_robot(robot)
    u = model.units
    given = [name for name, v in (("--rpy", rpy), ("--yaw", yaw), ("--pitch", pitch))
             if v is not None]
    if len(given) > 1:
        raise InputError(f"{', '.join(given)}: expected one of them, found {len(given)}")
    if pitch is not None:       # the vertical plane through the base axis and the target
        angles = (0.0, pitch, float(u.angle_from_si(np.arctan2(pose[1], pose[0]))))
    else:
        angles = rpy if rpy is not None else (0.0, 0.0, yaw if yaw is not None else 0.0)
    T = pose_from_xyz_rpy(u.length_to_si(pose), u.angle_to_si(angles))
    if mask is None and rpy is None and pitch is None:
        mask = "position+yaw" if yaw is not None else "position"
    start = None if q0 is None else model.q_to_si(parse_numbers("--q0", q0, model.n))
    solver = IKSolver(model)
    result = solver.solve(T, start, mask=mask, method=method, criterion=criterion)
    # An arm without a closed form has no list of solutions: --all then shows the numeric one
    # and says so, rather than refusing the request.
    solutions = (solver.solutions(T, mask=mask)
                 if all_solutions and solver.family is not None else None)
    out = SI if si else model.units
    as_q = (lambda q: q) if si else model.q_from_si
    doc = {"robot": model.name, "units": {"length": out.length, "angle": out.angle},
           "target": {"position": list(pose) if not si else u.length_to_si(pose),
                      "rpy": list(angles) if not si else u.angle_to_si(angles)},
           "mask": result.mask, "success": result.success, "reason": str(result.reason),
           "q": as_q(result.q), "position_error": out.length_from_si(result.position_error),
           "rotation_error": out.angle_from_si(result.rotation_error),
           "method": str(result.method), "iterations": result.iterations,
           "criterion": result.criterion,
           "closed_form": solver.family.name if solver.family is not None else None}
    if solutions is not None:
        doc["solutions"] = [{"q": as_q(q), "within_limits": bool(ok)}
                            for q, ok in zip(solutions.q, solutions.within_limits)]
    if as_json:
        print_json(doc)
    else:
        _show(model, doc, all_solutions)
    if not result.success:
        raise typer.Exit(EXIT_FAILED)


def _show(model, doc: dict, listed: bool) -> None:
    units = doc["units"]
    names = model.joint_names
    if listed and doc["closed_form"] is None:
        stdout.print(f"closed form: none for {model.name} (its geometry has none); the numeric "
                     f"solution follows")
    elif listed and not doc["solutions"]:
        stdout.print("closed form: no solution reaches the target")
    elif listed:
        table = Table(*names, "within limits", title=f"closed-form solutions ({units['angle']}, "
                      f"{units['length']})", box=None, title_justify="left")
        for s in doc["solutions"]:
            table.add_row(*[f"{v:.4f}" for v in s["q"]], "yes" if s["within_limits"] else "no")
        stdout.print(table)
    verdict = "solved" if doc["success"] else f"failed: {doc['reason']}"
    stdout.print(f"{verdict}  (task {doc['mask']}, {doc['method']}, "
                 f"{doc['iterations']} iterations)")
    stdout.print("q: " + "  ".join(f"{n}={v:.6g}" for n, v in zip(names, np.ravel(doc["q"]))))
    stdout.print(f"error: position {doc['position_error']:.3g} {units['length']}, "
                 f"rotation {doc['rotation_error']:.3g} {units['angle']}")
