"""Register map files (YAML): the schema, its checks, and the `RegisterMap` they load into.

A register map file names the robot whose joints it drives; every number a joint register holds
is ``value in the robot file's units x scale``::

    robot: inspection_6dof          # built-in name, or a robot file relative to this file
    device_id: 1                    # Modbus unit id
    word_order: big                 # default of every joint: big | little (high word first?)
    byte_order: big                 # default of every joint: big | little (within a register)
    readback: true                  # read the targets back after each write and compare
    joints:                         # one per moving joint, in the robot's order
      - {name: q1, target: 0, actual: 20, type: int32, scale: 1000}   # 1000 counts per deg
    command:
      waypoint: 12                  # waypoint index, written with the targets in one request
      enable: 16                    # 1 written here before the first waypoint (optional)
      lock: 17                      # exclusive-access register: the owner's token (optional)
      reset: 18                     # non-zero written here clears a fault (optional)
    status:
      accepted: 13                  # index of the last waypoint the drive took
      state: 14                     # bit field; bit `fault_bit` set means a fault
      fault_bit: 15
      fault: 15                     # fault code, 0 for none
    out_of_limits:                  # how the drive refuses a target outside its joint limits,
      response: exception           # NaN or inf: exception (Modbus exception 3) | fault
      fault_code: 0x8612            # the fault code of `fault`

Holding registers, addressed from 0. A waypoint is one FC16 write covering every target and
the waypoint index, so these must form one contiguous run of at most 123 registers. The loader
also refuses overlapping registers, addresses outside 0..65535, and a joint whose limits times
its scale do not fit its data type; every mistake is one `ModelFileError` naming the file and
the field.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field

from armkit.drives.registers import MAX_WRITE, JointRegister, RegisterMap
from armkit.errors import ArmkitError, ModelFileError
from armkit.io.documents import StrictModel, named_file, read_text, read_yaml, validated
from armkit.model import Robot
from armkit.io.robot_files import robot as load_robot_by_name

DataType = Literal["int16", "uint16", "int32", "float32"]
Order = Literal["big", "little"]
Address = Annotated[int, Field(ge=0, le=65535, strict=True)]
Word = Annotated[int, Field(ge=1, le=65535, strict=True)]
# Bounds that no real register map comes near (123 joints of 8 fields fill about 1,000 values).
MAX_FILE_BYTES = 256_000
QUOTED_OR_COMMENT = re.compile(r"'[^'\n]*'|\"(?:[^\"\\\n]|\\.)*\"|#[^\n]*")
FLOW_BRACKETS = re.compile(r"[\[\]{}]")
MAX_NODES = 10_000
MAX_DEPTH = 8


# --- the file ----------------------------------------------------------------------------------

class JointField(StrictModel):
    name: str | None = None
    target: Address
    actual: Address | None = None
    type: DataType
    scale: float = Field(1.0, gt=0, le=1e12, allow_inf_nan=False, strict=True)
    word_order: Order | None = None
    byte_order: Order | None = None


class CommandField(StrictModel):
    waypoint: Address | None = None
    enable: Address | None = None
    lock: Address | None = None
    reset: Address | None = None


class StatusField(StrictModel):
    accepted: Address | None = None
    state: Address | None = None
    fault_bit: int = Field(15, ge=0, le=15, strict=True)
    fault: Address | None = None


class OutOfLimitsField(StrictModel):
    response: Literal["exception", "fault"] = "exception"
    fault_code: Word = 0x8612


class RegisterMapFile(StrictModel):
    robot: str | None = None
    device_id: int = Field(1, ge=0, le=255, strict=True)
    word_order: Order = "big"
    byte_order: Order = "big"
    readback: bool = Field(True, strict=True)
    joints: list[JointField] = Field(min_length=1, max_length=MAX_WRITE)
    command: CommandField = CommandField()
    status: StatusField = StatusField()
    out_of_limits: OutOfLimitsField = OutOfLimitsField()


# --- loading -----------------------------------------------------------------------------------

def load_register_map(path: str | Path, robot: str | Path | Robot | None = None) -> RegisterMap:
    """Load and check a register map file (YAML).

    Parameters
    ----------
    path : str or Path
    robot : name, robot file or Robot, optional
        The robot the map drives; overrides the file's ``robot`` field.

    Raises
    ------
    ModelFileError
        For every mistake: ``map.yaml: joints[2].target: expected a register of its own,
        found 4..5, which joints[1].target also uses (3..4)``.
    """
    try:
        size = Path(path).stat().st_size
    except (OSError, ValueError):
        size = 0                               # read_yaml names the reason
    if size > MAX_FILE_BYTES:
        raise ModelFileError(str(path), "", f"a register map of at most {MAX_FILE_BYTES} bytes",
                             f"{size} bytes")
    line = _too_deep(read_text(path))
    if line is not None:
        raise ModelFileError(str(path), f"line {line}", f"fields nested at most {MAX_DEPTH} "
                             "deep", "deeper nesting of [ ] or { }")
    try:
        document = read_yaml(path)
    except RecursionError:                     # the YAML parser recurses once per level
        raise ModelFileError(str(path), "", f"fields nested at most {MAX_DEPTH} deep",
                             "deeper nesting") from None
    return parse_register_map(document, str(path), robot)


def parse_register_map(document: Any, path: str = "<register map>",
                       robot: str | Path | Robot | None = None) -> RegisterMap:
    """A RegisterMap from a parsed register-map document; `path` names it in messages.

    Raises
    ------
    ModelFileError
    """
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping of fields (robot, joints, command, status)",
                             type(document).__name__)
    _check_size(document, path)
    spec = validated(path, document, RegisterMapFile)
    model = _robot(spec, path, robot)
    joints = _joints(spec, path, model)
    _check_acknowledgement(spec, path)
    _check_addresses(spec, joints, path)
    command, status, refusal = spec.command, spec.status, spec.out_of_limits
    return RegisterMap(model, joints, spec.device_id, command.waypoint, command.enable,
                       status.accepted, status.state, status.fault, status.fault_bit,
                       spec.readback, path, command.lock, command.reset, refusal.response,
                       refusal.fault_code)


def _too_deep(text: str) -> int | None:
    """The line (from 1) where [ ] and { } first nest deeper than MAX_DEPTH in a YAML text,
    quoted strings and comments aside; None if they never do.

    PyYAML's scanner takes time quadratic in this depth (5 s for 3,000 levels), so a few
    kilobytes of brackets are refused before it sees them.
    """
    depth = 0
    for number, line in enumerate(text.splitlines(), start=1):
        for bracket in FLOW_BRACKETS.findall(QUOTED_OR_COMMENT.sub("", line)):
            depth = depth + 1 if bracket in "[{" else max(depth - 1, 0)
            if depth > MAX_DEPTH:
                return number
    return None


def _check_size(document: Any, path: str) -> None:
    """Refuse a document too large or too deeply nested for a register map before anything
    looks at it: YAML aliases can make a few hundred bytes into a tree of billions of nodes
    (shared, so cheap to build, but not to validate or print)."""
    budget = MAX_NODES
    stack = [(document, 0, "")]
    while stack:
        node, depth, where = stack.pop()
        budget -= 1
        if budget < 0:
            raise ModelFileError(path, where or "top level", f"a register map of at most "
                                 f"{MAX_NODES} values (YAML aliases count each time used)",
                                 "more")
        if depth > MAX_DEPTH:
            raise ModelFileError(path, where, f"fields nested at most {MAX_DEPTH} deep",
                                 "deeper nesting")
        if isinstance(node, dict):
            stack.extend((v, depth + 1, f"{where}.{str(k)[:40]}" if where else str(k)[:40])
                         for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, depth + 1, f"{where}[{i}]") for i, v in enumerate(node))


def _robot(spec: RegisterMapFile, path: str, given) -> Robot:
    if given is not None:
        return load_robot_by_name(given)
    if spec.robot is None:
        raise ModelFileError(path, "robot", "the robot the map drives (a built-in name or a "
                             "robot file)", "nothing")
    try:
        return load_robot_by_name(named_file(spec.robot, path, "robot"))
    except ModelFileError:
        raise
    except (ArmkitError, OSError, ValueError) as err:   # ValueError: a NUL in the name
        found = spec.robot if len(spec.robot) <= 60 else spec.robot[:57] + "..."
        raise ModelFileError(path, "robot", "a built-in robot name or a robot file",
                             repr(found)) from err


def _joints(spec: RegisterMapFile, path: str, robot: Robot) -> tuple[JointRegister, ...]:
    if len(spec.joints) != robot.n:
        raise ModelFileError(path, "joints", f"{robot.n} entries (the joints of {robot.name})",
                             str(len(spec.joints)))
    with_actual = [j.actual is not None for j in spec.joints]
    lower, upper = robot.q_from_si(robot.lower), robot.q_from_si(robot.upper)
    out = []
    for i, (j, name) in enumerate(zip(spec.joints, robot.joint_names)):
        where = f"joints[{i}]"
        if j.name is not None and j.name != name:
            found = j.name if len(j.name) <= 60 else j.name[:57] + "..."
            raise ModelFileError(path, f"{where}.name",
                                 f"{name!r} (joint {i + 1} of {robot.name})", repr(found))
        if any(with_actual) and not with_actual[i]:
            raise ModelFileError(path, f"{where}.actual", "an actual-position register, as the "
                                 "other joints have", "none")
        joint = JointRegister(name, j.target, j.type, j.scale, j.word_order or spec.word_order,
                              j.byte_order or spec.byte_order, j.actual)
        lo, hi = joint.counts([lower[i], upper[i]])
        low, high = joint.counts_range
        if not (low <= lo and hi <= high):
            unit = robot.joint_units[i]
            raise ModelFileError(
                path, f"{where}.type", f"a type that holds the joint's limits "
                f"{lower[i]:g}..{upper[i]:g} {unit} at scale {j.scale:g} "
                f"({lo:.6g}..{hi:.6g} counts)", f"{j.type} ({low:.6g}..{high:.6g})")
        out.append(joint)
    return tuple(out)


def _check_acknowledgement(spec: RegisterMapFile, path: str) -> None:
    if (spec.command.waypoint is None) != (spec.status.accepted is None):
        given, missing = (("command.waypoint", "status.accepted")
                          if spec.status.accepted is None else
                          ("status.accepted", "command.waypoint"))
        raise ModelFileError(path, missing, f"a register, since {given} is given (the drive "
                             "acknowledges a waypoint by copying its index)", "none")
    if not spec.readback and spec.status.accepted is None:
        raise ModelFileError(path, "readback", "true, or command.waypoint and status.accepted "
                             "(a way to acknowledge each waypoint)", "false and neither")
    if (spec.out_of_limits.response == "fault" and spec.status.state is None
            and spec.status.fault is None):
        raise ModelFileError(path, "out_of_limits.response", "exception, since the map has no "
                             "status.state or status.fault to report a fault", "fault")


def _check_addresses(spec: RegisterMapFile, joints: tuple[JointRegister, ...],
                     path: str) -> None:
    """Every register inside 0..65535 and used once; the waypoint one contiguous write."""
    used: list[tuple[str, int, int]] = []            # (field, first, last)
    for i, joint in enumerate(joints):
        used.append((f"joints[{i}].target", joint.target, joint.target + joint.count - 1))
        if joint.actual is not None:
            used.append((f"joints[{i}].actual", joint.actual, joint.actual + joint.count - 1))
    for group in ("command", "status"):
        for key, value in getattr(spec, group):
            if value is not None and key != "fault_bit":
                used.append((f"{group}.{key}", value, value))
    for name, first, last in used:
        if last > 65535:
            raise ModelFileError(path, name, "registers within 0..65535",
                                 f"{_span(first, last)} (2 registers from {first})")
    ordered = sorted(used, key=lambda u: (u[1], u[2]))
    for (name_a, first_a, last_a), (name_b, first_b, last_b) in zip(ordered, ordered[1:]):
        if first_b <= last_a:
            raise ModelFileError(path, name_b, "a register of its own",
                                 f"{_span(first_b, last_b)}, which {name_a} also uses "
                                 f"({_span(first_a, last_a)})")
    block = [u for u in ordered if u[0].endswith(".target") or u[0] == "command.waypoint"]
    first, last = block[0][1], max(u[2] for u in block)
    if last - first + 1 > MAX_WRITE:
        raise ModelFileError(path, "joints", f"a waypoint (targets and command.waypoint) of at "
                             f"most {MAX_WRITE} registers, one FC16 write",
                             f"{last - first + 1} registers ({_span(first, last)})")
    for (_, _, last_a), (name_b, first_b, _) in zip(block, block[1:]):
        if first_b > last_a + 1:
            raise ModelFileError(path, name_b, "the targets and command.waypoint in one "
                                 "contiguous run of registers (one write covers them all)",
                                 f"a gap at {_span(last_a + 1, first_b - 1)}")


def _span(first: int, last: int) -> str:
    return str(first) if first == last else f"{first}..{last}"
