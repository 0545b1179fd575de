"""A simulated multi-axis drive: a real Modbus TCP server (pymodbus) holding one register map.

Each joint moves toward its target register at the robot's velocity limit, in real time (the
position is brought up to date whenever a request arrives), and the status registers report
it. A waypoint write (the whole block in one FC16 request) is taken by copying its index into
``status.accepted``. State bits: 0 enabled, 1 moving, and the map's fault bit.

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
            flipped (a read-back mismatch)
==========  =====================================================================================

>>> from importlib import resources
>>> from armkit.drives import load_register_map, send_waypoints
>>> drive_map = load_register_map(resources.files("armkit.drives") / "inspection_6dof.map.yaml")
>>> with SimDrive(drive_map) as sim:                               # port 0: a free port
...     send_waypoints(sim.map, np.zeros((1, 6)), port=sim.port).waypoints
1
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from pymodbus.constants import ExcCodes
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from armkit.drives.modbus import port_number
from armkit.drives.registers import RegisterMap
from armkit.errors import DriveError, InputError

FAULTS = ("refuse", "drop", "silence", "exception", "fault", "ignore", "corrupt")
ENABLED_BIT, MOVING_BIT = 0, 1
WRITES = (6, 16)   # function codes that write holding registers: single, multiple
KEPT_REQUESTS = 100_000


@dataclass(frozen=True)
class _Armed:
    kind: str
    at: int
    code: int
    apply: bool


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

    Attributes
    ----------
    requests : deque of (int, int, int)
        (function code, address, count) of the last 100,000 requests received, in order.
    waypoint_writes : int
        Number of whole-block writes received.
    taken : deque of list of int
        The blocks of the last 100,000 waypoints the drive took, as written (index included).
    """

    def __init__(self, register_map: RegisterMap, host: str = "127.0.0.1", port: int = 0):
        self.map, self.host, self.port = register_map, host, port_number(port)
        m, robot = register_map, register_map.robot
        addresses = [a for j in m.joints for a in (j.target, j.actual) if a is not None]
        addresses += [j.actual + j.count - 1 for j in m.joints if j.actual is not None]
        addresses += [a for a in (m.waypoint, m.enable, m.accepted, m.state, m.fault)
                      if a is not None]
        self._first = min(addresses + [m.block_start])
        self._last = max(addresses + [m.block_start + m.block_count - 1])
        self._speed = robot.q_from_si(robot.chain.velocity_limits)       # file units / s
        home = np.clip(0.0, robot.q_from_si(robot.lower), robot.q_from_si(robot.upper))
        self._position = home.astype(float)
        self._target = home.astype(float)
        self.requests: deque[tuple[int, int, int]] = deque(maxlen=KEPT_REQUESTS)
        self.waypoint_writes = 0
        self.taken: deque[list[int]] = deque(maxlen=KEPT_REQUESTS)
        self._armed: _Armed | None = None
        self._fault_code = 0
        self._silent = self._refusing = False
        self._registers: list[int] | None = None
        self._moved_at = time.monotonic()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._server: ModbusTcpServer | None = None

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
    def writes(self) -> list[tuple[int, int]]:
        """(address, count) of every write request received."""
        return [(a, n) for fc, a, n in self.requests if fc in WRITES]

    # --- behaviour ---

    def _advance(self, regs: list[int]) -> None:
        """Bring the joints up to now: each toward its target at its speed limit."""
        m = self.map
        now = time.monotonic()
        dt, self._moved_at = now - self._moved_at, now
        if self._enabled(regs) and not self._fault_code:
            gap = self._target - self._position
            if gap.any():
                step = self._speed * dt
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
            state = (enabled << ENABLED_BIT | bool(moving) << MOVING_BIT
                     | bool(self._fault_code) << m.fault_bit)
            regs[m.state - self._first] = state
        if m.fault is not None:
            regs[m.fault - self._first] = self._fault_code

    def _take(self, regs: list[int], values: list[int]) -> None:
        """Take a waypoint block: it becomes the target the joints move to."""
        m = self.map
        self.taken.append(list(values))
        self._target = m.decode_file(values)
        if m.waypoint is not None:
            regs[m.accepted - self._first] = values[m.waypoint - m.block_start]

    async def _action(self, function_code: int, start: int, address: int, count: int,
                      regs: list[int], values: list[int] | None) -> ExcCodes | None:
        """Called by pymodbus before it answers a request (or applies a write)."""
        if self._registers is None:             # the start-up read that hands us the list
            self._registers = regs
            return None
        if not (function_code == 6 and values is None):    # FC6 reads back what it wrote
            self.requests.append((function_code, address, count))
        self._advance(regs)
        if self._silent:
            return await self._hold()
        if values is None:
            return None
        if (address, count) != (self.map.block_start, self.map.block_count):
            return None
        return await self._waypoint(regs, values)

    async def _waypoint(self, regs: list[int], values: list[int]) -> ExcCodes | None:
        at, self.waypoint_writes = self.waypoint_writes, self.waypoint_writes + 1
        armed = self._armed if self._armed is not None and self._armed.at == at else None
        kind = armed.kind if armed else None
        if kind == "exception":
            return ExcCodes(armed.code)
        if kind == "drop":
            if armed.apply:
                regs[self._slice(self.map.block_start, self.map.block_count)] = values
                self._take(regs, values)
            for connection in list(self._server.active_connections.values()):
                connection.close()
            return ExcCodes.DEVICE_FAILURE          # nobody hears it; keeps pymodbus from writing
        if kind == "silence":
            self._silent = True
            return await self._hold()
        if kind == "fault":
            self._fault_code = armed.code
            self._write_state(regs)
            return None
        if kind == "corrupt":
            values[0] ^= 1
        if kind != "ignore" and not self._fault_code:
            self._take(regs, values)
        return None

    async def _hold(self) -> ExcCodes:
        """Answer nothing until the fault is cleared or the drive stops."""
        await self._wake.wait()
        return ExcCodes.DEVICE_BUSY

    # --- faults ---

    def inject(self, kind: str, at: int = 0, *, code: int | None = None,
               apply: bool = False) -> None:
        """Arm a fault (see the module's table); one at a time, replacing any armed one.

        Raises
        ------
        InputError
            An unknown kind, or a negative `at`.
        """
        if kind not in FAULTS:
            raise InputError(f"fault: expected one of {', '.join(FAULTS)}, found {kind!r}")
        if at < 0:
            raise InputError(f"fault at: expected a waypoint write >= 0, found {at}")
        if kind == "refuse":
            self._call(self._refuse())
            return
        default = 0x2310 if kind == "fault" else int(ExcCodes.DEVICE_FAILURE)
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
            self._server.transport.close()

    async def _recover(self) -> None:
        self._wake.set()
        self._wake = asyncio.Event()
        if self._refusing:
            self._server.transport = await self._loop.create_server(
                self._server.handle_new_connection, self.host, self.port, reuse_address=True)
            self._refusing = False

    def _call(self, coroutine, timeout: float = 5.0) -> None:
        """Run a coroutine on the drive's event loop from another thread, and wait for it."""
        if self._loop is None:
            coroutine.close()
            raise DriveError("simulated drive: not started")
        asyncio.run_coroutine_threadsafe(coroutine, self._loop).result(timeout)

    # --- running ---

    async def _serve(self, ready: Callable[[], None]) -> None:
        self._loop = asyncio.get_running_loop()
        self._wake, self._stopping = asyncio.Event(), asyncio.Event()
        block = SimData(address=self._first, values=self._initial_registers(),
                        datatype=DataType.REGISTERS)
        device = SimDevice(id=self.map.device_id, simdata=[block], action=self._action)
        self._server = ModbusTcpServer(device, address=(self.host, self.port))
        try:
            await self._server.serve_forever(background=True)
        except RuntimeError:
            raise DriveError(f"simulated drive: cannot listen on {self.host}:{self.port} "
                             f"(in use, or not an address of this machine)") from None
        self.port = self._server.transport.sockets[0].getsockname()[1]
        await self._server.async_getValues(self.map.device_id, 3, self._first, 1)
        ready()
        try:
            await self._stopping.wait()
        finally:
            self._wake.set()
            await self._server.shutdown()

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
