"""Register maps: where a drive keeps each joint's target, how the value is encoded, and which
registers command and report; waypoints to registers and back.

A register map file (YAML) names the robot whose joints it drives; every number a joint
register holds is ``value in the robot file's units x scale``::

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
    status:
      accepted: 13                  # index of the last waypoint the drive took
      state: 14                     # bit field; bit `fault_bit` set means a fault
      fault_bit: 15
      fault: 15                     # fault code, 0 for none

Holding registers, addressed from 0. A waypoint is one FC16 write covering every target and
the waypoint index, so these must form one contiguous run of at most 123 registers. The loader
also refuses overlapping registers, addresses outside 0..65535, and a joint whose limits times
its scale do not fit its data type; every mistake is one `ModelFileError` naming the file and
the field.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, ValidationError

from armkit.errors import ArmkitError, InputError, ModelFileError
from armkit.model import Robot, joint_array, robot as load_robot_by_name
from armkit.model.files import _Strict, read_yaml, validation_error

MAX_WRITE = 123   # registers in one FC16 request (Modbus application protocol, 6.12)
MAX_READ = 125    # registers in one FC3 request (6.3)

DataType = Literal["int16", "uint16", "int32", "float32"]
Order = Literal["big", "little"]
# Big-endian NumPy types: the bytes come out in Modbus order, high byte first.
DTYPES = {"int16": ">i2", "uint16": ">u2", "int32": ">i4", "float32": ">f4"}
FLOAT32_MAX = float(np.finfo(np.float32).max)

Address = Annotated[int, Field(ge=0, le=65535, strict=True)]


# --- the file ----------------------------------------------------------------------------------

class JointField(_Strict):
    name: str | None = None
    target: Address
    actual: Address | None = None
    type: DataType
    scale: float = Field(1.0, gt=0, allow_inf_nan=False)
    word_order: Order | None = None
    byte_order: Order | None = None


class CommandField(_Strict):
    waypoint: Address | None = None
    enable: Address | None = None


class StatusField(_Strict):
    accepted: Address | None = None
    state: Address | None = None
    fault_bit: int = Field(15, ge=0, le=15, strict=True)
    fault: Address | None = None


class RegisterMapFile(_Strict):
    robot: str | None = None
    device_id: int = Field(1, ge=0, le=255, strict=True)
    word_order: Order = "big"
    byte_order: Order = "big"
    readback: bool = True
    joints: list[JointField] = Field(min_length=1)
    command: CommandField = CommandField()
    status: StatusField = StatusField()


# --- the model ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class JointRegister:
    """Where and how one joint's position lives in the drive.

    Parameters
    ----------
    name : str
    target : int
        First register of the commanded position.
    type : {"int16", "uint16", "int32", "float32"}
    scale : float
        Counts per unit of the robot file (e.g. per deg or per mm), > 0.
    word_order, byte_order : {"big", "little"}
        Order of the two registers of a 32-bit value (big: high word first), and of the two
        bytes within a register (big: high byte first, the Modbus default).
    actual : int or None
        First register of the measured position, same encoding; None if the drive has none.
    """

    name: str
    target: int
    type: str
    scale: float
    word_order: str = "big"
    byte_order: str = "big"
    actual: int | None = None

    @property
    def count(self) -> int:
        """Registers one value takes: 1 or 2."""
        return 2 if self.type in ("int32", "float32") else 1

    @property
    def counts_range(self) -> tuple[float, float]:
        """Smallest and largest number the data type holds."""
        if self.type == "float32":
            return -FLOAT32_MAX, FLOAT32_MAX
        info = np.iinfo(DTYPES[self.type])
        return float(info.min), float(info.max)

    def counts(self, value: ArrayLike) -> NDArray:
        """File-unit values (...) to the numbers the registers hold (rounded for integers)."""
        raw = np.asarray(value, dtype=float) * self.scale
        # asarray again: NumPy turns 0-d results into scalars, whose astype ignores byte order.
        return np.asarray(raw if self.type == "float32" else np.rint(raw))

    def words(self, value: ArrayLike) -> NDArray:
        """File-unit values (...) to registers (..., count), uint16.

        Raises
        ------
        InputError
            If a value does not fit the data type at this scale.
        """
        counts = self.counts(value)
        lo, hi = self.counts_range
        if not np.all((counts >= lo) & (counts <= hi)):
            raise InputError(f"joint {self.name}: expected values within {lo:g}..{hi:g} "
                             f"counts for {self.type}, found {counts.min():g}..{counts.max():g}")
        raw = counts.astype(DTYPES[self.type]).reshape(counts.shape + (1,))
        octets = raw.view(np.uint8)                                # (..., 2 * count)
        if self.byte_order == "little":
            octets = octets.reshape(counts.shape + (self.count, 2))[..., ::-1]
            octets = octets.reshape(counts.shape + (2 * self.count,))
        words = (octets[..., 0::2].astype(np.uint16) << 8) | octets[..., 1::2]
        return words[..., ::-1] if self.word_order == "little" else words

    def value(self, words: ArrayLike) -> NDArray:
        """Registers (..., count) to file-unit values (...); the inverse of `words`."""
        words = np.asarray(words, dtype=np.uint16)
        if self.word_order == "little":
            words = words[..., ::-1]
        octets = np.stack([words >> 8, words & 0xFF], axis=-1).astype(np.uint8)
        if self.byte_order == "little":
            octets = octets[..., ::-1]
        raw = np.ascontiguousarray(octets.reshape(words.shape[:-1] + (2 * self.count,)))
        counts = raw.view(DTYPES[self.type])[..., 0]
        return counts.astype(float) / self.scale


@dataclass(frozen=True, eq=False)
class RegisterMap:
    """A drive's register map for one robot; build it with `load_register_map`.

    Parameters
    ----------
    robot : Robot
        The robot whose joints the map drives; its limits and file units apply.
    joints : tuple of JointRegister
        One per moving joint, in the robot's order.
    device_id : int
        Modbus unit id.
    waypoint, enable : int or None
        Command registers: the waypoint index (written with the targets), the enable flag.
    accepted, state, fault : int or None
        Status registers: index of the last waypoint taken, state bits, fault code.
    fault_bit : int
        Bit of `state` that means a fault.
    readback : bool
        Read the targets back after each write and compare them register for register.
    source : str
        Where the map came from, for messages.

    Attributes
    ----------
    block_start, block_count : int
        The registers one waypoint write covers: every target and the waypoint index.
    ack_reads : tuple of (int, int)
        (address, count) of the reads that acknowledge a waypoint: the block when `readback`,
        and the status registers, grouped into contiguous runs.
    """

    robot: Robot
    joints: tuple[JointRegister, ...]
    device_id: int = 1
    waypoint: int | None = None
    enable: int | None = None
    accepted: int | None = None
    state: int | None = None
    fault: int | None = None
    fault_bit: int = 15
    readback: bool = True
    source: str = "<register map>"
    block_start: int = field(init=False)
    block_count: int = field(init=False)
    ack_reads: tuple[tuple[int, int], ...] = field(init=False)

    def __post_init__(self):
        block = [a for j in self.joints for a in range(j.target, j.target + j.count)]
        if self.waypoint is not None:
            block.append(self.waypoint)
        start = min(block)
        needed = set(block) if self.readback else set()
        needed |= {a for a in (self.accepted, self.state, self.fault) if a is not None}
        object.__setattr__(self, "block_start", start)
        object.__setattr__(self, "block_count", max(block) - start + 1)
        object.__setattr__(self, "ack_reads", runs(needed, MAX_READ))

    @property
    def n(self) -> int:
        return len(self.joints)

    def encode(self, q: ArrayLike) -> NDArray:
        """Joint positions (..., n), SI, to waypoint blocks (..., block_count), uint16.

        The waypoint index register, if any, is left 0: the client fills it per write.

        Raises
        ------
        InputError
            If q has the wrong last axis, or a value does not fit its data type.
        """
        q_file = self.robot.q_from_si(joint_array(self.robot, q))
        out = np.zeros(q_file.shape[:-1] + (self.block_count,), dtype=np.uint16)
        for i, joint in enumerate(self.joints):
            at = joint.target - self.block_start
            out[..., at:at + joint.count] = joint.words(q_file[..., i])
        return out

    def decode(self, block: ArrayLike) -> NDArray:
        """Waypoint blocks (..., block_count) to joint positions (..., n), SI."""
        block = np.asarray(block, dtype=np.uint16)
        q_file = np.stack([j.value(block[..., j.target - self.block_start:
                                         j.target - self.block_start + j.count])
                           for j in self.joints], axis=-1)
        return self.robot.q_to_si(q_file)

    def joint_at(self, address: int) -> str:
        """What register `address` of the block holds, for messages: ``joint q3``."""
        for joint in self.joints:
            if joint.target <= address < joint.target + joint.count:
                return f"joint {joint.name}"
        return "the waypoint index" if address == self.waypoint else "no field"


def runs(addresses, longest: int) -> tuple[tuple[int, int], ...]:
    """Sorted addresses as (start, count) runs of consecutive registers, each <= longest."""
    out: list[list[int]] = []
    for a in sorted(addresses):
        if out and a == out[-1][0] + out[-1][1] and out[-1][1] < longest:
            out[-1][1] += 1
        else:
            out.append([a, 1])
    return tuple((a, n) for a, n in out)


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
    return parse_register_map(read_yaml(path), str(path), robot)


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
    try:
        spec = RegisterMapFile.model_validate(document)
    except ValidationError as err:
        raise validation_error(path, err, RegisterMapFile) from None
    model = _robot(spec, path, robot)
    joints = _joints(spec, path, model)
    _check_acknowledgement(spec, path)
    _check_addresses(spec, joints, path)
    return RegisterMap(model, joints, spec.device_id, spec.command.waypoint,
                       spec.command.enable, spec.status.accepted, spec.status.state,
                       spec.status.fault, spec.status.fault_bit, spec.readback, path)


def _robot(spec: RegisterMapFile, path: str, given) -> Robot:
    if given is not None:
        return load_robot_by_name(given)
    if spec.robot is None:
        raise ModelFileError(path, "robot", "the robot the map drives (a built-in name or a "
                             "robot file)", "nothing")
    relative = Path(path).parent / spec.robot
    try:
        return load_robot_by_name(relative if relative.is_file() else spec.robot)
    except ModelFileError:
        raise
    except ArmkitError as err:
        raise ModelFileError(path, "robot", "a built-in robot name or a robot file",
                             repr(spec.robot)) from err


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
            raise ModelFileError(path, f"{where}.name",
                                 f"{name!r} (joint {i + 1} of {robot.name})", repr(j.name))
        if any(with_actual) and not with_actual[i]:
            raise ModelFileError(path, f"{where}.actual", "an actual-position register, as the "
                                 "other joints have", "none")
        joint = JointRegister(name, j.target, j.type, j.scale, j.word_order or spec.word_order,
                              j.byte_order or spec.byte_order, j.actual)
        lo, hi = joint.counts([lower[i], upper[i]])
        low, high = joint.counts_range
        if lo < low or hi > high:
            unit = robot.units.angle if robot.chain.revolute[i] else robot.units.length
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
