"""`armkit robots`, `armkit show ROBOT`, `armkit fk ROBOT Q...`."""

from __future__ import annotations

import dataclasses
from typing import Annotated

import numpy as np
import typer
from rich.table import Table
from rich.text import Text

import armkit
from armkit.cli.command import NUMBERS, JsonFlag, SiFlag, app, print_json, stdout
from armkit.cli.values import load_robot, number
from armkit.errors import InputError
from armkit.io.robot_files import robot_document
from armkit.model import SI, Robot, Units
from armkit.model.urdf import URDFTable
from armkit.spatial import matrix_to_rpy

RobotArg = Annotated[str, typer.Argument(help="Built-in name (see `armkit robots`), or a "
                                              "robot file (.yaml) or URDF file.",
                                         metavar="ROBOT")]


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def pose_view(T: np.ndarray, units: Units) -> dict:
    """A pose (4, 4) in SI as the numbers a person reads, in `units`."""
    p = units.length_from_si(T[..., :3, 3])
    M = np.array(T, dtype=float)
    M[..., :3, 3] = p
    return {"position": p, "rpy": units.angle_from_si(matrix_to_rpy(T[..., :3, :3])),
            "matrix": M}


def _kinds(robot: Robot) -> str:
    return "".join("R" if r else "P" for r in robot.chain.revolute)


@app.command()
def robots(as_json: JsonFlag = False) -> None:
    """List the built-in robots."""
    rows = []
    for name in armkit.robots():
        r = armkit.robot(name)
        rows.append({"name": name, "dof": r.n, "joints": _kinds(r),
                     "units": f"{r.units.length}/{r.units.angle}",
                     "description": r.description.split(". ")[0].rstrip(".")})
    if as_json:
        return print_json(rows)
    table = Table("name", "DOF", "joints", "units", "description", box=None)
    for row in rows:
        table.add_row(row["name"], str(row["dof"]), row["joints"], row["units"],
                      row["description"])
    stdout.print(table)


def _joint_rows(robot: Robot, units: Units) -> list[dict]:
    """The robot's joints as its file gives them, in `units`, including fixed rows."""
    if isinstance(robot.table, URDFTable):             # a URDF speaks m and rad
        to = {"xyz": units.length_from_si, "rpy": units.angle_from_si}
        return [{"name": j.name, "type": j.kind, "xyz": to["xyz"](j.xyz), "rpy": to["rpy"](j.rpy),
                 "axis": j.axis, "limits": None if j.limits is None else
                 (units.angle_from_si if j.kind != "prismatic" else units.length_from_si)(
                     [j.limits.lower, j.limits.upper]),
                 **({} if j.mimic is None else {"mimic": _mimic_text(j, units)})}
                for j in robot.table.joints]
    return robot_document(dataclasses.replace(robot, units=units))["joints"]


def _mimic_text(joint, units: Units) -> str:
    """``leader x multiplier + offset`` of a URDF mimic joint, the offset in `units`."""
    leader, multiplier, offset = joint.mimic
    to = units.length_from_si if joint.kind == "prismatic" else units.angle_from_si
    return f"{leader} x {multiplier:g} + {float(to(offset)):g}"


@app.command()
def show(robot: RobotArg, as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """The robot's table, limits, base and tool, and its link frames at q = 0."""
    model = load_robot(robot)
    units = SI if si else model.units
    frames = armkit.fk_frames(model, np.zeros(model.n))
    names = ["base"] + [j.name for j in model.chain.joints[:-1]] + ["tool"]
    frame_rows = [{"frame": name, **pose_view(T, units)} for name, T in zip(names, frames)]
    joints = _joint_rows(model, units)
    collision = _collision_view(model, units)
    if as_json:
        return print_json({"name": model.name, "description": model.description,
                           "dof": model.n, "units": {"length": units.length,
                                                     "angle": units.angle},
                           "joints": joints,
                           "frames_at_zero": [{k: v for k, v in row.items() if k != "matrix"}
                                              for row in frame_rows],
                           "collision": collision})
    mimics = model.chain.n_joints + len(model.chain.leaders) - model.n
    stdout.print(Text.assemble(
        (model.name, "bold"), f"  {model.n} joints {_kinds(model)}"
        + (f" (and {mimics} mimic joint{'s' * (mimics > 1)})" if mimics else "")
        + f", file units {model.units.length}/{model.units.angle}"))
    if model.description:
        stdout.print(model.description)
    columns = list(dict.fromkeys(key for row in joints for key in row))
    table = Table(*columns, title=f"joints ({units.length}, {units.angle})", box=None,
                  title_justify="left")
    for row in joints:
        table.add_row(*[_cell(row.get(c)) for c in columns])
    stdout.print(table)
    table = Table("frame", f"x y z ({units.length})", f"roll pitch yaw ({units.angle})",
                  title="link frames at q = 0", box=None, title_justify="left")
    for row in frame_rows:
        table.add_row(row["frame"], _cell(row["position"]), _cell(row["rpy"]))
    stdout.print(table)
    table = Table("link", f"a ({units.length})", f"b ({units.length})",
                  f"radius ({units.length})", "from", box=None, title_justify="left",
                  title=f"collision capsules in link frames ({collision['source']})")
    for c in collision["capsules"]:
        table.add_row(str(c["link"]), _cell(c["a"]), _cell(c["b"]), _cell(c["radius"]),
                      c["from"])
    stdout.print(table)
    for note in collision["notes"]:
        stdout.print(f"note: {note}")
    stdout.print("self-collision skipped between links: "
                 + (", ".join(f"{i}-{j}" for i, j in collision["skip"]) or "none")
                 + " (and between adjacent links)")


def _collision_view(model: Robot, units: Units) -> dict:
    """The arm's capsules (`armkit.planning.arm_geometry`) in `units`."""
    from armkit.planning import arm_geometry

    g = arm_geometry(model)
    length = lambda x: units.length_from_si(np.round(x, 12) + 0.0)   # noqa: E731  (no -0, 1e-15)
    labels = g.labels or ("",) * len(g)
    return {"source": g.source, "skip": [list(p) for p in g.skip], "notes": list(g.notes),
            "capsules": [{"link": int(k), "a": length(a), "b": length(b),
                          "radius": float(length(r)), "from": label}
                         for k, a, b, r, label in zip(g.link, g.a, g.b, g.radius, labels)]}


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, (list, tuple, np.ndarray)):
        return "  ".join(_fmt(v) for v in np.ravel(value))
    return _fmt(value) if isinstance(value, float) else str(value)


@app.command(context_settings=NUMBERS)
def fk(robot: RobotArg,
       q: Annotated[list[float], typer.Argument(
           help="Joint values in the robot file's units (deg/mm for the papers' robots).",
           metavar="Q...", parser=number())],
       as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """The tool pose for one configuration."""
    model = load_robot(robot)
    if len(q) != model.n:
        raise InputError(f"Q: expected {model.n} joint values for {model.name}, found {len(q)}")
    q_si = model.q_to_si(q)
    T = armkit.fk(model, q_si)
    units = SI if si else model.units
    outside = [name for name, v, lo, hi in zip(model.joint_names, q_si, model.lower, model.upper)
               if not lo <= v <= hi]
    view = pose_view(T, units)
    if as_json:
        return print_json({"robot": model.name,
                           "units": {"length": units.length, "angle": units.angle},
                           "q": q_si if si else q, **view,
                           "outside_limits": outside})
    stdout.print(f"position ({units.length}):  {_cell(view['position'])}")
    stdout.print(f"roll pitch yaw ({units.angle}):  {_cell(view['rpy'])}")
    table = Table(box=None, show_header=False, title="T_base_tool", title_justify="left")
    for row in view["matrix"]:
        table.add_row(*[f"{v: .6f}" for v in row])
    stdout.print(table)
    if outside:
        stdout.print(f"note: outside the joint limits: {', '.join(outside)}")
