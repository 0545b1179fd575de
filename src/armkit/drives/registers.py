"""Register maps: where a drive keeps each joint's target, how the value is encoded, and which
registers command and report; waypoints to registers and back.

The file format (YAML) and its checks live in `armkit.io.register_maps`; this module holds what
a loaded map is (`RegisterMap`, `JointRegister`) and the encoding of values into registers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model import Robot, joint_array

MAX_WRITE = 123   # registers in one FC16 request (Modbus application protocol, 6.12)
MAX_READ = 125    # registers in one FC3 request (6.3)

# Big-endian NumPy types: the bytes come out in Modbus order, high byte first.
DTYPES = {"int16": ">i2", "uint16": ">u2", "int32": ">i4", "float32": ">f4"}
COUNTS = {"int16": 1, "uint16": 1, "int32": 2, "float32": 2}
FLOAT32_MAX = float(np.finfo(np.float32).max)
RANGES = {kind: ((-FLOAT32_MAX, FLOAT32_MAX) if kind == "float32" else
                 (float(np.iinfo(t).min), float(np.iinfo(t).max))) for kind, t in DTYPES.items()}


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
    """A drive's register map for one robot; build it with `load_register_map`
    (`armkit.io.register_maps`).

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
    lock : int or None
        The exclusive-access register: a client writes its owner token (1..65535) there and
        the drive then refuses writes from any other connection (Modbus exception 6) until the
        owner writes 0 or disconnects. It reads 0 when free, else the owner's token.
    reset : int or None
        Writing a non-zero value here clears the drive's fault.
    limit_response : {"exception", "fault"}
        What the drive does with a waypoint outside its joint limits, or not finite: answer
        Modbus exception 3 (illegal data value) and hold nothing, or hold the registers, take
        nothing, and fault with `limit_fault_code`.
    limit_fault_code : int
        The fault code of that fault, 1..65535.
    moving_bit : int or None
        Bit of `state` that the drive sets while it moves toward its target; None if it has
        none (arrival is then told by the positions alone).

    Attributes
    ----------
    block_start, block_count : int
        The registers one waypoint write covers: every target and the waypoint index.
    ack_reads : tuple of (int, int)
        (address, count) of the reads that acknowledge a waypoint: the block when `readback`,
        the status registers and the lock, grouped into contiguous runs.
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
    lock: int | None = None
    reset: int | None = None
    limit_response: str = "exception"
    limit_fault_code: int = 0x8612
    moving_bit: int | None = None
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
        needed |= {a for a in (self.accepted, self.state, self.fault, self.lock)
                   if a is not None}
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

    def half_count(self, q: ArrayLike) -> NDArray:
        """Half of one count of each joint's register near q (n,), rad or m: how far a value
        moves when the drive stores it (integers: 1 / scale; float32: its relative precision
        2^-23 of the value, at least of 1 file unit)."""
        q_file = np.abs(self.robot.q_from_si(joint_array(self.robot, q)))
        count = np.array([max(v, 1.0) * 2.0 ** -23 if j.type == "float32" else 1.0 / j.scale
                          for j, v in zip(self.joints, q_file)])
        return 0.5 * self.robot.q_to_si(count)

    def joint_at(self, address: int) -> str:
        """What register `address` of the block holds, for messages: ``joint q3``."""
        for joint in self.joints:
            if joint.target <= address < joint.target + joint.count:
                return f"joint {joint.name}"
        return "the waypoint index" if address == self.waypoint else "no field"


def default_register_map(robot: Robot) -> RegisterMap:
    """A register map for any robot, what the simulated drive holds when a task names none:
    float32 targets from register 0 and the waypoint index after them (one write), actual
    positions from register 200, then the accepted index, the state (bit 1: moving, bit 15:
    fault) and the fault code."""
    n = robot.n
    joints = tuple(JointRegister(name, 2 * i, "float32", 1.0, actual=200 + 2 * i)
                   for i, name in enumerate(robot.joint_names))
    return RegisterMap(robot, joints, waypoint=2 * n, accepted=2 * n + 1, state=2 * n + 2,
                       fault=2 * n + 3, source=f"<default register map of {robot.name}>",
                       moving_bit=1)


def runs(addresses, longest: int) -> tuple[tuple[int, int], ...]:
    """Sorted addresses as (start, count) runs of consecutive registers, each <= longest."""
    out: list[list[int]] = []
    for a in sorted(addresses):
        if out and a == out[-1][0] + out[-1][1] and out[-1][1] < longest:
            out[-1][1] += 1
        else:
            out.append([a, 1])
    return tuple((a, n) for a, n in out)
