"""`armkit dynamics ROBOT --q ...`: joint torques, gravity torques and the mass matrix of one
configuration, in the robot file's units (torques in N m for revolute and N for prismatic
joints, whatever the file's length and angle units)."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from armkit.cli.command import EXIT_FAILED, NUMBERS, JsonFlag, SiFlag, app, print_json, stdout
from armkit.cli.robots import RobotArg
from armkit.cli.values import check_number, load_robot, parse_numbers
from armkit.dynamics import (coriolis, gravity_torques, inverse_dynamics, mass_matrix,
                             with_payload)
from armkit.errors import InputError
from armkit.model import SI, Robot

MASS = (0.0, 1e4)       # kg: a payload an arm could carry


def _joint_values(name: str, text: str | None, robot: Robot) -> list[float] | None:
    if text is None:
        return None
    values = parse_numbers(name, text)
    if len(values) != robot.n:
        raise InputError(f"{name}: expected {robot.n} values (the joints of {robot.name}), "
                         f"found {len(values)}")
    return values


def _payload(text: str, robot: Robot) -> Robot:
    """The robot holding the payload typed as ``MASS [X Y Z]`` (kg, file length units, the
    tool frame)."""
    values = parse_numbers("--payload", text)
    if len(values) not in (1, 4):
        raise InputError(f"--payload: expected MASS or MASS X Y Z (kg, {robot.units.length}), "
                         f"found {len(values)} numbers")
    mass = check_number("--payload", values[0], *MASS, unit="kg")
    return with_payload(robot, mass, robot.units.length_to_si(values[1:] or [0.0, 0.0, 0.0]))


def _fmt(x: float) -> str:
    return f"{x:.6g}"


@app.command(context_settings=NUMBERS)
def dynamics(
    robot: RobotArg,
    q: Annotated[str, typer.Option("--q", help="Joint positions, file units, e.g. "
                                               "--q \"0 -90 90 0 0 0\".")],
    qd: Annotated[str | None, typer.Option("--qd", help="Joint velocities, file units/s "
                                                        "(default 0).")] = None,
    qdd: Annotated[str | None, typer.Option("--qdd", help="Joint accelerations, file "
                                                          "units/s^2 (default 0).")] = None,
    payload: Annotated[str | None, typer.Option(help="A payload at the tool: MASS (kg) and "
                                                     "optionally its centre X Y Z (file "
                                                     "length units, tool frame).")] = None,
    as_json: JsonFlag = False,
    si: SiFlag = False,
) -> None:
    """Joint torques of a motion, the torques that hold the arm against gravity, and the mass
    matrix; exit 1 where a torque is beyond the robot's torque limits."""
    model = load_robot(robot)
    values = {name: _joint_values(f"--{name}", text, model)
              for name, text in (("q", q), ("qd", qd), ("qdd", qdd))}
    if payload is not None:
        model = _payload(payload, model)
    to_si = model.q_to_si(np.ones(model.n))         # SI per file unit, per joint
    q_si = model.q_to_si(values["q"])
    qd_si = np.zeros(model.n) if values["qd"] is None else np.asarray(values["qd"]) * to_si
    qdd_si = np.zeros(model.n) if values["qdd"] is None else np.asarray(values["qdd"]) * to_si
    tau = inverse_dynamics(model, q_si, qd_si, qdd_si)
    gravity = gravity_torques(model, q_si)
    velocity = coriolis(model, q_si, qd_si)
    M = mass_matrix(model, q_si)
    units = SI if si else model.units
    # tau = M qdd: with qdd in file units / s^2, each column takes its joint's SI per file unit.
    M_shown = M if si else M * to_si[None, :]
    limits = model.torque_limits
    beyond = [name for name, t, limit in zip(model.joint_names, tau, limits) if abs(t) > limit]
    torque_units = ["N m" if r else "N" for r in model.chain.revolute]
    joint_units = [units.of_joint(r) for r in model.chain.revolute]
    if as_json:
        print_json({"robot": model.name, "units": {"length": units.length, "angle": units.angle},
                    "torque_units": torque_units,
                    "payload": None if model.inertia.payload is None else
                    {"mass": model.inertia.payload.mass,
                     "com": units.length_from_si(model.inertia.payload.com)},
                    "torque": tau, "gravity_torque": gravity, "coriolis_torque": velocity,
                    "mass_matrix": M_shown, "torque_limits": limits,
                    "within_limits": not beyond, "beyond_limits": beyond})
    else:
        table = Table("joint", "torque", "gravity", "Coriolis", "limit", "unit", box=None,
                      title=f"{model.name}: joint torques", title_justify="left")
        for j, (name, t, g, c, limit, unit) in enumerate(zip(
                model.joint_names, tau, gravity, velocity, limits, torque_units)):
            table.add_row(f"{j + 1} {name}", _fmt(t), _fmt(g), _fmt(c),
                          _fmt(limit) if np.isfinite(limit) else "", unit)
        stdout.print(table)
        table = Table("", *(str(j + 1) for j in range(model.n)), box=None,
                      title_justify="left", title="mass matrix: N m (or N) per "
                      "joint acceleration, " + ", ".join(f"{u}/s²" for u in joint_units))
        for j, row in enumerate(M_shown):
            table.add_row(str(j + 1), *(f"{x:.4g}" for x in row))
        stdout.print(table)
        if beyond:
            stdout.print(f"beyond the torque limits: {', '.join(beyond)}")
    if beyond:
        raise typer.Exit(EXIT_FAILED)
