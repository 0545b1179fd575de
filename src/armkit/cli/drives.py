"""`armkit send WAYPOINTS --map FILE` and `armkit sim-drive`: waypoints to Modbus TCP drives.

The drives package (and pymodbus) loads inside the commands, so other commands start without it.
"""

from __future__ import annotations

import logging
from importlib import resources
from pathlib import Path
from typing import Annotated

import typer

from armkit.cli.command import EXIT_FAILED, JsonFlag, app, print_json, stdout
from armkit.cli.values import TIMEOUT, number, robot_text
from armkit.errors import DriveError, InputError
from armkit.io.waypoints import read_waypoints

MapOption = Annotated[Path | None, typer.Option("--map", help="Register map file (YAML).")]
RobotOption = Annotated[str | None, typer.Option(
    "--robot", help="Robot the map drives (built-in name or robot file); overrides the map's.")]
HostOption = Annotated[str, typer.Option("--host", help="Drive address.")]
DEFAULT_MAP = "inspection_6dof.map.yaml"
# One default port for `send` and `sim-drive`, so that the two work together as they come:
# 5020, as a user may listen there without privileges (a real drive's 502 needs them).
DEFAULT_PORT = 5020


def _load_map(path: Path | None, robot: str | None):
    """The register map at `path`, or the built-in default (inspection_6dof)."""
    from armkit.io.register_maps import load_register_map

    if robot is not None:
        robot_text("--robot", robot)
    if path is not None:
        return load_register_map(path, robot)
    with resources.as_file(resources.files("armkit.drives") / DEFAULT_MAP) as default:
        return load_register_map(default, robot)


def _report(result: dict) -> None:
    if result["ok"]:
        stdout.print(f"sent {result['waypoints']} waypoints to {result['drive']} in "
                     f"{result['seconds'] * 1e3:.1f} ms; the drive took waypoints "
                     f"0..{result['last_accepted']}")
        return
    last = result["last_accepted"]
    stdout.print(f"send failed at waypoint {result['failed_waypoint']} of "
                 f"{result['waypoints']} (counted from 0): {result['cause']}")
    stdout.print(f"last accepted waypoint: {'none' if last is None else last}")
    if result["outcome_unknown"]:
        stdout.print(f"whether the drive took waypoint {result['failed_waypoint']}: unknown "
                     f"(its write left, no answer came back)")


@app.command()
def send(waypoints: Annotated[Path, typer.Argument(
             help="Waypoints file: CSV (header of joint names and optional t, s) or JSON, in "
                  "the robot file's units.")],
         map_file: Annotated[Path, typer.Option("--map", help="Register map file (YAML).")],
         host: HostOption = "127.0.0.1",
         port: Annotated[int, typer.Option(
             "--port", parser=number(1, 65535, integer=True),
             help="Drive's Modbus TCP port (the simulated drive's default; a real drive "
                  "usually listens on 502).")] = DEFAULT_PORT,
         robot: RobotOption = None,
         timeout: Annotated[float, typer.Option(
             "--timeout", parser=number(*TIMEOUT, unit="s"),
             help="Connect, response and acknowledgement time-out, s.")] = 1.0,
         retries: Annotated[int, typer.Option(
             "--retries", parser=number(0, 100, integer=True),
             help="Re-sends after a response time-out.")] = 0,
         dry_run: Annotated[bool, typer.Option("--dry-run", help="Check and encode, do not "
                                               "connect.")] = False,
         as_json: JsonFlag = False) -> None:
    """Check waypoints against the limits, then send them to a drive over Modbus TCP."""
    from armkit.drives import check_waypoints, send_waypoints

    register_map = _load_map(map_file, robot)
    model = register_map.robot
    q_file, t = read_waypoints(waypoints, model)
    q = check_waypoints(register_map, model.q_to_si(q_file), t)
    m = register_map
    write = {"device_id": m.device_id, "address": m.block_start, "count": m.block_count,
             "acknowledge_reads": [list(r) for r in m.ack_reads]}
    if dry_run:
        blocks = m.encode(q)
        if as_json:
            return print_json({"ok": True, "dry_run": True, "robot": model.name,
                               "waypoints": len(q), "velocity_checked": t is not None,
                               "write": write, "registers": blocks})
        stdout.print(f"{len(q)} waypoints within the joint limits of {model.name}"
                     + (" and, with their times, the velocity limits" if t is not None else
                        " (no times: velocity limits not checked)"))
        stdout.print(f"each: one FC16 write of {m.block_count} registers at "
                     f"{m.block_start}..{m.block_start + m.block_count - 1} to device "
                     f"{m.device_id}; nothing sent (--dry-run)")
        return
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)   # failures come in the report
    try:
        sent = send_waypoints(register_map, q, t, host=host, port=port, timeout=timeout,
                              retries=retries, ack_timeout=timeout)
        result = {"ok": True, "last_accepted": sent.last_accepted, "seconds": sent.seconds}
    except DriveError as err:
        result = {"ok": False, "failed_waypoint": err.waypoint, "cause": err.cause,
                  "last_accepted": err.last_accepted, "outcome_unknown": err.outcome_unknown}
    result.update(waypoints=len(q), drive=f"{host}:{port}", write=write)
    if as_json:
        print_json(result)
    else:
        _report(result)
    if not result["ok"]:
        raise typer.Exit(EXIT_FAILED)


@app.command("sim-drive")
def sim_drive(port: Annotated[int, typer.Option(
                  "--port", parser=number(0, 65535, integer=True),
                  help="Port to listen on; 0 picks a free one.")] = DEFAULT_PORT,
              map_file: MapOption = None,
              host: Annotated[str, typer.Option("--host", help="Address to listen on.")]
              = "127.0.0.1",
              robot: RobotOption = None) -> None:
    """Run the simulated Modbus TCP drive in the foreground (Ctrl-C stops it)."""
    from armkit.drives import SimDrive

    register_map = _load_map(map_file, robot)
    sim = SimDrive(register_map, host, port)
    # pymodbus logs a failed bind on its own; the one line below says it for armkit.
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

    def ready():
        stdout.print(f"simulated drive for {register_map.robot.name} "
                     f"({register_map.n} joints, device {register_map.device_id}) listening "
                     f"on {host}:{sim.port}; Ctrl-C stops it", markup=False)
        stdout.file.flush()

    try:
        sim.serve_forever(ready)
    except KeyboardInterrupt:
        pass
    except DriveError:
        raise InputError(f"--port: expected a port free to listen on at {host}, found {port} "
                         f"in use (or {host} is not an address of this machine)") from None
