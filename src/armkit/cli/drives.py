"""`armkit send WAYPOINTS --map FILE` and `armkit sim-drive`: waypoints to Modbus TCP drives.

The drives package (and pymodbus) loads inside the commands, so other commands start without it.
"""

from __future__ import annotations

import csv
import json
import logging
from importlib import resources
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from armkit.cli.app import EXIT_FAILED, JsonFlag, app, print_json, stdout
from armkit.errors import DriveError, ModelFileError
from armkit.model import Robot
from armkit.io.documents import read_text

MapOption = Annotated[Path | None, typer.Option("--map", help="Register map file (YAML).")]
RobotOption = Annotated[str | None, typer.Option(
    "--robot", help="Robot the map drives (built-in name or robot file); overrides the map's.")]
HostOption = Annotated[str, typer.Option("--host", help="Drive address.")]
TIME_COLUMNS = ("t", "time")
DEFAULT_MAP = "inspection_6dof.map.yaml"


def read_waypoints(path: Path, robot: Robot) -> tuple[np.ndarray, np.ndarray | None]:
    """Waypoints (N, n) and times (N,) or None from a CSV or JSON file, in the robot file's units.

    CSV: one waypoint a row; a header row names the joints and, optionally, a time column
    ``t`` (s). Without a header: n columns, or n + 1 with the time first. JSON: a list of rows
    as in CSV, or ``{"q": [[...], ...], "t": [...]}``.

    Raises
    ------
    ModelFileError
    """
    text = read_text(path)
    if Path(path).suffix.lower() == ".json":
        return _json_waypoints(text, str(path), robot)
    # (line number, row) of the rows that hold anything, so errors name the file's own lines.
    rows = [(line, row) for line, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and any(c.strip() for c in row)]
    if not rows:
        raise ModelFileError(str(path), "", "waypoints, one a row", "an empty file")
    header = None
    if not _numbers(rows[0][1]):
        header = [c.strip() for c in rows[0][1]]
        rows = rows[1:]
    columns = _columns(header, str(path), robot)
    q, t = [], []
    for line, row in rows:
        values = _numbers(row)
        width = len(columns) if header else len(row)
        if values is None or len(values) != width or (not header and width not in
                                                      (robot.n, robot.n + 1)):
            expected = (f"{len(columns)} numbers ({', '.join(header)})" if header else
                        f"{robot.n} numbers (the joints of {robot.name}), or {robot.n + 1} "
                        f"with the time first")
            raise ModelFileError(str(path), f"line {line}", expected,
                                 ", ".join(c.strip() for c in row))
        if header:
            q.append([values[columns.index(name)] for name in robot.joint_names])
            if "t" in columns:
                t.append(values[columns.index("t")])
        else:
            q.append(values[-robot.n:])
            if width == robot.n + 1:
                t.append(values[0])
    if not q:
        raise ModelFileError(str(path), "", "at least one waypoint", "a header only")
    return np.array(q), (np.array(t) if t else None)


def _numbers(row: list[str]) -> list[float] | None:
    try:
        return [float(c) for c in row]
    except ValueError:
        return None


def _columns(header: list[str] | None, path: str, robot: Robot) -> list[str]:
    if header is None:
        return []
    columns = ["t" if c.lower() in TIME_COLUMNS else c for c in header]
    missing = [name for name in robot.joint_names if name not in columns]
    unknown = [c for c in columns if c != "t" and c not in robot.joint_names]
    if missing or unknown or len(set(columns)) != len(columns):
        raise ModelFileError(path, "line 1", f"a header naming each joint of {robot.name} once "
                             f"({', '.join(robot.joint_names)}) and optionally t",
                             ", ".join(header))
    return columns


def _json_waypoints(text: str, path: str, robot: Robot):
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise ModelFileError(path, f"line {err.lineno}", "valid JSON", err.msg) from None
    if isinstance(doc, dict):
        unknown = set(doc) - {"q", "t"}
        if "q" not in doc or unknown:
            raise ModelFileError(path, "", 'fields "q" and optionally "t"',
                                 ", ".join(sorted(map(repr, unknown))) or "no \"q\"")
        q, t = doc["q"], doc.get("t")
    else:
        q, t = doc, None
    try:
        q = np.array(q, dtype=float)
        t = None if t is None else np.array(t, dtype=float)
    except (TypeError, ValueError):
        raise ModelFileError(path, "q", "rows of numbers", "something else") from None
    if q.ndim != 2 or q.shape[1] not in (robot.n, robot.n + 1) or len(q) == 0:
        raise ModelFileError(path, "q", f"rows of {robot.n} numbers (the joints of "
                             f"{robot.name}), or {robot.n + 1} with the time first",
                             f"shape {q.shape}")
    if q.shape[1] == robot.n + 1:
        if t is not None:
            raise ModelFileError(path, "t", "times in one place: a first column or \"t\"",
                                 "both")
        q, t = q[:, 1:], q[:, 0]
    return q, t


def _load_map(path: Path | None, robot: str | None):
    """The register map at `path`, or the built-in default (inspection_6dof)."""
    from armkit.drives import load_register_map

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
         port: Annotated[int, typer.Option("--port", help="Drive's Modbus TCP port.")] = 502,
         robot: RobotOption = None,
         timeout: Annotated[float, typer.Option("--timeout", help="Connect and response "
                                                "time-out, s.")] = 1.0,
         retries: Annotated[int, typer.Option("--retries", help="Re-sends after a response "
                                              "time-out.")] = 0,
         dry_run: Annotated[bool, typer.Option("--dry-run", help="Check and encode, do not "
                                               "connect.")] = False,
         as_json: JsonFlag = False) -> None:
    """Check waypoints against the limits, then send them to a drive over Modbus TCP."""
    from armkit.drives import check_waypoints, load_register_map, send_waypoints

    register_map = load_register_map(map_file, robot)
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
                              retries=retries)
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
def sim_drive(port: Annotated[int, typer.Option("--port", help="Port to listen on; 0 picks a "
                                                "free one.")] = 5020,
              map_file: MapOption = None,
              host: Annotated[str, typer.Option("--host", help="Address to listen on.")]
              = "127.0.0.1",
              robot: RobotOption = None) -> None:
    """Run the simulated Modbus TCP drive in the foreground (Ctrl-C stops it)."""
    from armkit.drives import SimDrive

    register_map = _load_map(map_file, robot)
    sim = SimDrive(register_map, host, port)

    def ready():
        stdout.print(f"simulated drive for {register_map.robot.name} "
                     f"({register_map.n} joints, device {register_map.device_id}) listening "
                     f"on {host}:{sim.port}; Ctrl-C stops it", markup=False)
        stdout.file.flush()

    try:
        sim.serve_forever(ready)
    except KeyboardInterrupt:
        pass
