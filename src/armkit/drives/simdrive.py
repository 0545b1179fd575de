"""A simulated motor drive: a real Modbus TCP server holding one register map.

Each joint moves toward its target register at the robot's velocity limit, in real time (the
position is brought up to date whenever a request arrives), and the status registers report
it. A waypoint write (the whole block in one FC16 request) is taken by copying its index into
``status.accepted``. State bits: 0 enabled, the map's moving bit and its fault bit.

It answers as a Modbus TCP device does (Modbus Application Protocol V1.1b3 and the Messaging
on TCP/IP Implementation Guide V1.0b):

- functions 3 (read holding registers), 6 (write single register) and 16 (write multiple
  registers); any other function is answered with exception 1 (illegal function), the function
  code with its high bit set (``0x81``, ``0xC1`` ...);
- a quantity outside 1..125 (read) or 1..123 (write), a byte count that disagrees with it, or a
  request of the wrong length: exception 3 (illegal data value); a register it does not hold,
  or a write to a register that is not a command (status, actual positions): exception 2;
- unit ids: its own (the map's ``device_id``), 0 and 255 (the id of a device addressed by its
  IP address alone); any other, exception 11 (gateway target device failed to respond), as
  a gateway answers for a unit that is not behind it;
- several requests in one TCP segment (pipelined) are each answered, in order; a frame with a
  length field outside 2..254 closes the connection, one with another protocol id is dropped;
- a waypoint outside the joint limits, or NaN or inf in a float32 target, is refused as the
  map says (``out_of_limits``): exception 3 and nothing held, or the registers held, nothing
  taken and a fault with the map's code. The joints never move outside their limits;
- the lock register, if the map has one, gives one connection exclusive access: writing a
  non-zero token takes it when free, writing 0 frees it, and so does the owner's disconnect;
  while it is held, a write from any other connection is answered with exception 6 (server
  device busy). A non-zero write to the reset register clears a fault.

Faults can be injected for tests; ``at`` counts waypoint writes from 0 since the drive started:

==========  =====================================================================================
refuse      stop listening: new connections are refused (until `clear`)
drop        at waypoint write ``at``: close every connection without answering; with
            ``apply=True`` the drive takes the waypoint first
silence     at waypoint write ``at``: stop answering anything, keeping connections open
exception   at waypoint write ``at``: answer with Modbus exception ``code`` (default 4, device
            failure); the write is not executed
fault       at waypoint write ``at``: hold the registers but do not take the waypoint; raise the
            fault bit with fault code ``code`` (default 0x2310) and stop moving
ignore      at waypoint write ``at``: hold the registers but never take the waypoint (its index
            is not acknowledged), with no fault
corrupt     at waypoint write ``at``: store the first register of the block with its lowest bit
            flipped, and take it so (a read-back mismatch)
==========  =====================================================================================

>>> from importlib import resources
>>> from armkit.drives import send_waypoints
>>> from armkit.io.register_maps import load_register_map
>>> drive_map = load_register_map(resources.files("armkit.drives") / "inspection_6dof.map.yaml")
>>> with SimDrive(drive_map) as sim:                               # port 0: a free port
...     send_waypoints(sim.map, np.zeros((1, 6)), port=sim.port).waypoints
1
"""

from __future__ import annotations

import asyncio
import struct
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.drives.modbus import port_number
from armkit.drives.registers import MAX_READ, MAX_WRITE, RegisterMap
from armkit.errors import DriveError, InputError
from armkit.model.robot import joint_array

FAULTS = ("refuse", "drop", "silence", "exception", "fault", "ignore", "corrupt")
ENABLED_BIT = 0
WRITES = (6, 16)   # function codes that write holding registers: single, multiple
KEPT_REQUESTS = 100_000
# Exception codes (Modbus Application Protocol V1.1b3, section 7).
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE = 0x01, 0x02, 0x03
DEVICE_FAILURE, DEVICE_BUSY, GATEWAY_NO_RESPONSE = 0x04, 0x06, 0x0B
MBAP = struct.Struct(">HHHB")     # transaction id, protocol id, length, unit id
NO_ANSWER = -1                    # a write the drive does not answer (dropped, silent)


@dataclass(frozen=True)
class _Armed:
    kind: str
    at: int
    code: int
    apply: bool


class _Connection(asyncio.Protocol):
    """One client's TCP connection: splits the byte stream into Modbus TCP frames, in order."""

    def __init__(self, drive: SimDrive):
        self.drive, self.buffer, self.transport = drive, bytearray(), None

    def connection_made(self, transport) -> None:
        self.transport = transport
        self.drive.connections.add(self)

    def data_received(self, data: bytes) -> None:
        self.buffer += data
        while len(self.buffer) >= MBAP.size and not self.transport.is_closing():
            length = int.from_bytes(self.buffer[4:6], "big")
            if not 2 <= length <= 254:           # no room for a function code, or > 260 bytes
                self.buffer.clear()
                self.transport.close()
                return
            if len(self.buffer) < 6 + length:
                return
            frame = bytes(self.buffer[:6 + length])
            del self.buffer[:6 + length]
            reply = self.drive.answer(self, frame)
            if reply is not None and not self.transport.is_closing():
                self.transport.write(reply)

    def connection_lost(self, exc) -> None:
        self.drive.disconnected(self)


class SimDrive:
    """A simulated drive behind a Modbus TCP server, run on its own thread or in the foreground.

    Parameters
    ----------
    register_map : RegisterMap
        The registers it holds, the robot whose limits and speeds it follows.
    host : str
        Address to listen on; loopback by default.
    port : int
        0 picks a free port; `port` holds the real one once started.
    position : array_like (n,), optional
        Where the joints start (rad, m); zero, or the nearest limit, by default.

    Attributes
    ----------
    requests : deque of (int, int, int)
        (function code, address, count) of the last 100,000 valid requests received, in order.
    waypoint_writes : int
        Number of whole-block writes received (those refused for another's lock aside).
    taken : deque of list of int
        The blocks of the last 100,000 waypoints the drive took, as written (index included).
    refused : deque of list of int
        The blocks of the last 100,000 waypoints refused as outside the limits or not finite.
    """

    def __init__(self, register_map: RegisterMap, host: str = "127.0.0.1", port: int = 0, *,
                 position: ArrayLike | None = None):
        self.map, self.host, self.port = register_map, host, port_number(port)
        m, robot = register_map, register_map.robot
        addresses = [a for j in m.joints for a in (j.target, j.actual) if a is not None]
        addresses += [j.actual + j.count - 1 for j in m.joints if j.actual is not None]
        addresses += [a for a in (m.waypoint, m.enable, m.accepted, m.state, m.fault, m.lock,
                                  m.reset) if a is not None]
        self._first = min(addresses + [m.block_start])
        self._last = max(addresses + [m.block_start + m.block_count - 1])
        self._writable = set(range(m.block_start, m.block_start + m.block_count))
        self._writable |= {a for a in (m.enable, m.lock, m.reset) if a is not None}
        self._units = {m.device_id, 0, 255}
        self._speed = robot.q_from_si(robot.chain.velocity_limits)       # file units / s
        self._lower, self._upper = robot.q_from_si(robot.lower), robot.q_from_si(robot.upper)
        # A waypoint within the limits may round past them by up to half a count (integers) or
        # float32's relative precision: the drive allows that much, and no more.
        scale = np.array([j.scale for j in m.joints])
        is_float = np.array([j.type == "float32" for j in m.joints])
        extent = np.maximum(np.abs(self._lower), np.abs(self._upper))
        self._slack = np.where(is_float, extent * 2.0 ** -23, 0.5 / scale * (1 + 1e-9))
        home = np.clip(0.0 if position is None else robot.q_from_si(
            joint_array(robot, position, "position")), self._lower, self._upper)
        self._position = home.astype(float)
        self._target = home.astype(float)
        self.requests: deque[tuple[int, int, int]] = deque(maxlen=KEPT_REQUESTS)
        self.waypoint_writes = 0
        self.taken: deque[list[int]] = deque(maxlen=KEPT_REQUESTS)
        self.refused: deque[list[int]] = deque(maxlen=KEPT_REQUESTS)
        self.connections: set[_Connection] = set()
        self._armed: _Armed | None = None
        self._fault_code = 0
        self._silent = self._refusing = False
        self._owner: _Connection | None = None
        self._registers: list[int] | None = None
        self._moved_at = time.monotonic()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._server: asyncio.base_events.Server | None = None

    # --- the registers ---

    def _initial_registers(self) -> list[int]:
        m = self.map
        regs = [0] * (self._last - self._first + 1)
        regs[self._slice(m.block_start, m.block_count)] = m.encode_file(self._position).tolist()
        self._write_actual(regs)
        self._write_state(regs)
        return regs

    def _slice(self, address: int, count: int) -> slice:
        return slice(address - self._first, address - self._first + count)

    def registers(self, address: int, count: int = 1) -> list[int]:
        """A copy of `count` holding registers from `address` (read without a request)."""
        if self._registers is None:
            raise DriveError("simulated drive: not started")
        return self._registers[self._slice(address, count)]

    def targets(self) -> NDArray:
        """The target registers decoded, (n,), rad and m."""
        block = self.registers(self.map.block_start, self.map.block_count)
        return self.map.decode(block)

    @property
    def goal(self) -> NDArray:
        """The waypoint the joints move to, (n,), rad and m: the last one taken."""
        return self.map.robot.q_to_si(self._target)

    @property
    def position(self) -> NDArray:
        """Where the joints are, (n,), rad and m, as of the last request."""
        return self.map.robot.q_to_si(self._position)

    @property
    def writes(self) -> list[tuple[int, int]]:
        """(address, count) of every write request received."""
        return [(a, n) for fc, a, n in list(self.requests) if fc in WRITES]

    # --- Modbus TCP ---

    def answer(self, connection: _Connection, frame: bytes) -> bytes | None:
        """The response to one Modbus TCP frame (MBAP header and PDU), or None for none."""
        transaction, protocol, _, unit = MBAP.unpack_from(frame)
        if protocol != 0:                        # not Modbus (implementation guide 3.1.3)
            return None
        pdu = frame[MBAP.size:]
        function = pdu[0]

        def reply(body: bytes) -> bytes:
            return MBAP.pack(transaction, 0, len(body) + 1, unit) + body

        if unit not in self._units:
            return reply(bytes([function | 0x80, GATEWAY_NO_RESPONSE]))
        request = self._parse(function, pdu)
        if isinstance(request, int):
            return reply(bytes([function | 0x80, request]))
        address, count, values = request
        self.requests.append((function, address, count))
        regs = self._registers
        self._advance(regs)
        if self._silent:
            return None
        if values is None:
            held = regs[self._slice(address, count)]
            return reply(struct.pack(f">BB{count}H", function, 2 * count, *held))
        code = self._write(connection, regs, address, values)
        if code == NO_ANSWER:
            return None
        if code:
            return reply(bytes([function | 0x80, code]))
        return reply(pdu[:5])           # FC6 echoes address and value; FC16 address and count

    def _parse(self, function: int, pdu: bytes) -> tuple[int, int, list[int] | None] | int:
        """(address, count, values or None for a read), or the exception code to answer."""
        if function == 3:
            if len(pdu) != 5:
                return ILLEGAL_VALUE
            address, count = struct.unpack_from(">HH", pdu, 1)
            if not 1 <= count <= MAX_READ:
                return ILLEGAL_VALUE
            if address < self._first or address + count - 1 > self._last:
                return ILLEGAL_ADDRESS
            return address, count, None
        if function == 6:
            if len(pdu) != 5:
                return ILLEGAL_VALUE
            address, value = struct.unpack_from(">HH", pdu, 1)
            return (address, 1, [value]) if address in self._writable else ILLEGAL_ADDRESS
        if function == 16:
            if len(pdu) < 6:
                return ILLEGAL_VALUE
            address, count, size = struct.unpack_from(">HHB", pdu, 1)
            if not 1 <= count <= MAX_WRITE or size != 2 * count or len(pdu) != 6 + size:
                return ILLEGAL_VALUE
            if not all(a in self._writable for a in range(address, address + count)):
                return ILLEGAL_ADDRESS
            return address, count, list(struct.unpack_from(f">{count}H", pdu, 6))
        return ILLEGAL_FUNCTION

    def _write(self, connection: _Connection, regs: list[int], address: int,
               values: list[int]) -> int:
        """Execute a write: 0, an exception code, or NO_ANSWER."""
        m = self.map
        if self._owner is not None and self._owner is not connection:
            return DEVICE_BUSY                    # another connection holds the lock
        if (address, len(values)) == (m.block_start, m.block_count):
            return self._waypoint(regs, values)
        for a, value in zip(range(address, address + len(values)), values):
            if a == m.lock:
                self._owner = connection if value else None
            elif a == m.reset:
                if value:
                    self._fault_code = 0
                value = 0                          # a trigger: it reads 0
            regs[a - self._first] = value
        self._write_state(regs)
        return 0

    # --- behaviour ---

    def _advance(self, regs: list[int]) -> None:
        """Bring the joints up to now: each toward its target at its speed limit."""
        now = time.monotonic()
        dt, self._moved_at = now - self._moved_at, now
        if self._enabled(regs) and not self._fault_code:
            gap = self._target - self._position
            if gap.any():
                step = np.where(np.isfinite(self._speed), self._speed * dt, np.inf)
                self._position = self._position + np.clip(gap, -step, step)
                self._write_actual(regs)
        self._write_state(regs)

    def _write_actual(self, regs: list[int]) -> None:
        block = self.map.encode_file(self._position).tolist()
        for joint in self.map.joints:
            if joint.actual is not None:
                at = joint.target - self.map.block_start
                regs[self._slice(joint.actual, joint.count)] = block[at:at + joint.count]

    def _enabled(self, regs: list[int]) -> bool:
        return self.map.enable is None or regs[self.map.enable - self._first] != 0

    def _write_state(self, regs: list[int]) -> None:
        m = self.map
        if m.state is not None:
            enabled = self._enabled(regs)
            moving = enabled and not self._fault_code and (self._target != self._position).any()
            state = enabled << ENABLED_BIT | bool(self._fault_code) << m.fault_bit
            if m.moving_bit is not None:
                state |= bool(moving) << m.moving_bit
            regs[m.state - self._first] = state
        if m.fault is not None:
            regs[m.fault - self._first] = self._fault_code

    def _outside(self, values: list[int]) -> bool:
        """Whether a block holds a target outside the joint limits (beyond rounding) or one
        that is not finite."""
        q = self.map.decode_file(values)
        with np.errstate(invalid="ignore"):
            inside = (q >= self._lower - self._slack) & (q <= self._upper + self._slack)
        return not inside.all()             # NaN compares False: outside

    def _take(self, regs: list[int], values: list[int]) -> None:
        """Take a waypoint block: it becomes the target the joints move to."""
        m = self.map
        self.taken.append(list(values))
        self._target = np.clip(m.decode_file(values), self._lower, self._upper)
        if m.waypoint is not None:
            regs[m.accepted - self._first] = values[m.waypoint - m.block_start]
        self._write_state(regs)

    def _waypoint(self, regs: list[int], values: list[int]) -> int:
        m = self.map
        at, self.waypoint_writes = self.waypoint_writes, self.waypoint_writes + 1
        armed = self._armed if self._armed is not None and self._armed.at == at else None
        kind = armed.kind if armed else None
        if kind == "exception":
            return armed.code
        if kind == "silence":
            self._silent = True
            return NO_ANSWER
        if kind == "corrupt":
            values = [values[0] ^ 1] + values[1:]
        outside = self._outside(values)
        if outside and m.limit_response == "exception":
            self.refused.append(list(values))
            return ILLEGAL_VALUE
        if kind == "drop":
            if armed.apply and not outside and not self._fault_code:
                regs[self._slice(m.block_start, m.block_count)] = values
                self._take(regs, values)
            for connection in list(self.connections):
                connection.transport.close()
            return NO_ANSWER
        regs[self._slice(m.block_start, m.block_count)] = values   # the registers hold it
        if kind == "fault":
            self._fault_code = armed.code
        elif outside:
            self.refused.append(list(values))
            self._fault_code = m.limit_fault_code
        elif kind != "ignore" and not self._fault_code:
            self._take(regs, values)
        self._write_state(regs)
        return 0

    def disconnected(self, connection: _Connection) -> None:
        """A connection closed: its lock, if it held it, is free."""
        self.connections.discard(connection)
        if self._owner is connection:
            self._owner = None
            self._registers[self.map.lock - self._first] = 0

    # --- faults ---

    def inject(self, kind: str, at: int = 0, *, code: int | None = None,
               apply: bool = False) -> None:
        """Arm a fault (see the module's table); one at a time, replacing any armed one.

        Raises
        ------
        InputError
            An unknown kind, a negative `at`, or a code outside 1..255 (an exception) or
            1..65535 (a fault).
        """
        if kind not in FAULTS:
            raise InputError(f"fault: expected one of {', '.join(FAULTS)}, found {kind!r}")
        if at < 0:
            raise InputError(f"fault at: expected a waypoint write >= 0, found {at}")
        largest = 65535 if kind == "fault" else 255
        if code is not None and not 1 <= code <= largest:
            raise InputError(f"fault code: expected 1..{largest}, found {code}")
        if kind == "refuse":
            self._call(self._refuse())
            return
        default = 0x2310 if kind == "fault" else DEVICE_FAILURE
        self._armed = _Armed(kind, int(at), default if code is None else int(code), apply)

    def clear(self) -> None:
        """Remove every fault: listen again, answer again, fault bit and code cleared."""
        self._armed = None
        self._fault_code = 0
        self._silent = False
        self._call(self._recover())

    async def _refuse(self) -> None:
        if not self._refusing:
            self._refusing = True
            self._server.close()

    async def _recover(self) -> None:
        if self._registers is not None:
            self._write_state(self._registers)
        if self._refusing:
            self._server = await self._listen()
            self._refusing = False

    async def _listen(self):
        return await self._loop.create_server(lambda: _Connection(self), self.host, self.port,
                                              reuse_address=True)

    def _call(self, coroutine, timeout: float = 5.0) -> None:
        """Run a coroutine on the drive's event loop from another thread, and wait for it."""
        if self._loop is None:
            coroutine.close()
            raise DriveError("simulated drive: not started")
        asyncio.run_coroutine_threadsafe(coroutine, self._loop).result(timeout)

    # --- running ---

    async def _serve(self, ready: Callable[[], None]) -> None:
        self._loop = asyncio.get_running_loop()
        self._stopping = asyncio.Event()
        self._registers = self._initial_registers()
        try:
            self._server = await self._listen()
        except OSError as err:
            raise DriveError(f"simulated drive: cannot listen on {self.host}:{self.port} "
                             f"({err.strerror or err})") from None
        self.port = self._server.sockets[0].getsockname()[1]
        ready()
        try:
            await self._stopping.wait()
        finally:
            self._server.close()
            for connection in list(self.connections):
                connection.transport.abort()
            await asyncio.sleep(0)                # let the connections see their end

    def start(self, timeout: float = 5.0) -> SimDrive:
        """Serve on a background thread; returns once it listens.

        Raises
        ------
        DriveError
            It could not listen, or did not start within `timeout` s.
        """
        started, failure = threading.Event(), []

        def run():
            try:
                asyncio.run(self._serve(started.set))
            except Exception as err:          # handed to the starting thread
                failure.append(err)
                started.set()

        self._thread = threading.Thread(target=run, name=f"armkit-simdrive-{id(self):x}",
                                        daemon=True)
        self._thread.start()
        if not started.wait(timeout):
            raise DriveError(f"simulated drive: not listening after {timeout:g} s")
        if failure:
            raise failure[0]
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Stop serving and wait (at most `timeout` s) for the thread to end."""
        if self._loop is not None and self._thread is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stopping.set)
            self._thread.join(timeout)

    def serve_forever(self, ready: Callable[[], None] | None = None) -> None:
        """Serve in the foreground until interrupted; `ready` is called once it listens."""
        asyncio.run(self._serve(ready or (lambda: None)))

    def __enter__(self) -> SimDrive:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
