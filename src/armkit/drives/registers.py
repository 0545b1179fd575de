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
from armkit.model import Robot, joint_array
from armkit.model.files import robot as load_robot_by_name
from armkit.io.documents import StrictModel, read_yaml, validation_error

MAX_WRITE = 123   # registers in one FC16 request (Modbus application protocol, 6.12)
MAX_READ = 125    # registers in one FC3 request (6.3)

DataType = Literal["int16", "uint16", "int32", "float32"]
Order = Literal["big", "little"]
# Big-endian NumPy types: the bytes come out in Modbus order, high byte first.
DTYPES = {"int16": ">i2", "uint16": ">u2", "int32": ">i4", "float32": ">f4"}
COUNTS = {"int16": 1, "uint16": 1, "int32": 2, "float32": 2}
FLOAT32_MAX = float(np.finfo(np.float32).max)
RANGES = {kind: ((-FLOAT32_MAX, FLOAT32_MAX) if kind == "float32" else
                 (float(np.iinfo(t).min), float(np.iinfo(t).max))) for kind, t in DTYPES.items()}

Address = Annotated[int, Field(ge=0, le=65535, strict=True)]


# --- the file ----------------------------------------------------------------------------------

class JointField(StrictModel):
    name: str | None = None
    target: Address
    actual: Address | None = None
    type: DataType
    scale: float = Field(1.0, gt=0, allow_inf_nan=False)
    word_order: Order | None = None
    byte_order: Order | None = None


class CommandField(StrictModel):
    waypoint: Address | None = None
    enable: Address | None = None


class StatusField(StrictModel):
    accepted: Address | None = None
    state: Address | None = None
    fault_bit: int = Field(15, ge=0, le=15, strict=True)
    fault: Address | None = None


class RegisterMapFile(StrictModel):
    robot: str | None = None
    device_id: int = Field(1, ge=0, le=255, strict=True)
    word_order: Order = "big"
    byte_order: Order = "big"
    readback: bool = True
    joints: list[JointField] = Field(min_length=1)
    command: CommandField = CommandField()
    status: StatusField = StatusField()


# --- the model ---------------------------------------------------------------------------------

def to_words(values: ArrayLike, kind: str, scale: ArrayLike = 1.0, word_order: str = "big",
             byte_order: str = "big", names: tuple[str, ...] = ("value",)) -> NDArray:
    """Values x scale as registers: shape (...) to (..., count), uint16.

    `scale` broadcasts against `values` (one per joint along the last axis, say); integer types
    round to the nearest count. `names` name the values along the last axis in messages.

    Raises
    ------
    InputError
        If a value does not fit the data type at this scale.
    """
    counts = np.asarray(values, dtype=float) * scale
    if kind != "float32":
        counts = np.rint(counts)
    lo, hi = RANGES[kind]
    if not ((counts >= lo) & (counts <= hi)).all():
        bad = ~((counts >= lo) & (counts <= hi)).reshape(-1, len(names)).all(axis=0)
        raise InputError(f"{', '.join(n for n, b in zip(names, bad) if b)}: expected values "
                         f"within {lo:g}..{hi:g} counts for {kind}, found "
                         f"{counts.min():g}..{counts.max():g}")
    # asarray first: NumPy makes 0-d results scalars, whose astype drops the byte order.
    raw = np.asarray(counts).astype(DTYPES[kind])         # big-endian, high byte first
    words = raw.reshape(raw.shape + (1,)).view(">u2")     # (..., count), high word first
    if byte_order == "little":
        words = words.byteswap()
    if word_order == "little":
        words = words[..., ::-1]
    return words.astype(np.uint16)


def from_words(words: ArrayLike, kind: str, scale: ArrayLike = 1.0, word_order: str = "big",
               byte_order: str = "big") -> NDArray:
    """Registers (..., count) to values (...): the inverse of `to_words`."""
    words = np.asarray(words, dtype=np.uint16)
    if word_order == "little":
        words = words[..., ::-1]
    words = words.astype(">u2")
    if byte_order == "little":
        words = words.byteswap()
    counts = np.ascontiguousarray(words).view(DTYPES[kind])[..., 0]
    return counts.astype(float) / scale


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
        return COUNTS[self.type]

    @property
    def counts_range(self) -> tuple[float, float]:
        """Smallest and largest number the data type holds."""
        return RANGES[self.type]

    def counts(self, value: ArrayLike) -> NDArray:
        """File-unit values (...) to the numbers the registers hold (rounded for integers)."""
        raw = np.asarray(value, dtype=float) * self.scale
        return raw if self.type == "float32" else np.rint(raw)

    def words(self, value: ArrayLike) -> NDArray:
        """File-unit values (...) to registers (..., count), uint16 (see `to_words`)."""
        return to_words(value, self.type, self.scale, self.word_order, self.byte_order,
                        (f"joint {self.name}",))

    def value(self, words: ArrayLike) -> NDArray:
        """Registers (..., count) to file-unit values (...)."""
        return from_words(words, self.type, self.scale, self.word_order, self.byte_order)


@dataclass(frozen=True)
class _Group:
    """Joints sharing one encoding, encoded together: their indices, scales, block columns."""

    kind: str
    word_order: str
    byte_order: str
    joints: NDArray
    scales: NDArray
    columns: NDArray
    names: tuple[str, ...]


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
    _groups: tuple[_Group, ...] = field(init=False, repr=False)

    def __post_init__(self):
        block = [a for j in self.joints for a in range(j.target, j.target + j.count)]
        if self.waypoint is not None:
            block.append(self.waypoint)
        start = min(block)
        needed = set(block) if self.readback else set()
        needed |= {a for a in (self.accepted, self.state, self.fault) if a is not None}
        groups: dict[tuple[str, str, str], list[int]] = {}
        for i, j in enumerate(self.joints):
            groups.setdefault((j.type, j.word_order, j.byte_order), []).append(i)
        object.__setattr__(self, "block_start", start)
        object.__setattr__(self, "block_count", max(block) - start + 1)
        object.__setattr__(self, "ack_reads", runs(needed, MAX_READ))
        object.__setattr__(self, "_groups", tuple(
            _Group(*key, np.array(index), np.array([self.joints[i].scale for i in index]),
                   np.array([a - start for i in index for a in range(
                       self.joints[i].target, self.joints[i].target + COUNTS[key[0]])]),
                   tuple(f"joint {self.joints[i].name}" for i in index))
            for key, index in groups.items()))

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
        return self.encode_file(self.robot.q_from_si(joint_array(self.robot, q)))

    def encode_file(self, q_file: ArrayLike) -> NDArray:
        """As `encode`, from joint positions (..., n) in the robot file's units."""
        q_file = np.asarray(q_file, dtype=float)
        lead = q_file.shape[:-1]
        out = np.zeros(lead + (self.block_count,), dtype=np.uint16)
        for g in self._groups:       # one group (a few NumPy calls) for a uniform map
            words = to_words(q_file[..., g.joints], g.kind, g.scales, g.word_order,
                             g.byte_order, g.names)
            out[..., g.columns] = words.reshape(lead + (len(g.columns),))
        return out

    def decode(self, block: ArrayLike) -> NDArray:
        """Waypoint blocks (..., block_count) to joint positions (..., n), SI."""
        return self.robot.q_to_si(self.decode_file(block))

    def decode_file(self, block: ArrayLike) -> NDArray:
        """As `decode`, to joint positions (..., n) in the robot file's units."""
        block = np.asarray(block, dtype=np.uint16)
        lead = block.shape[:-1]
        q_file = np.empty(lead + (self.n,))
        for g in self._groups:
            words = block[..., g.columns].reshape(lead + (len(g.joints), COUNTS[g.kind]))
            q_file[..., g.joints] = from_words(words, g.kind, g.scales, g.word_order,
                                               g.byte_order)
        return q_file

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
