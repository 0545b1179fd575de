"""Waypoints to motor drives over Modbus TCP: checked before anything leaves, each written whole
in one request and acknowledged before the next.

A sequence goes out as follows:

1. Every waypoint is checked against the joint limits and, given waypoint times, the velocity
   limits, and encoded; a violation raises `InputError` before a connection is opened.
2. Connect (time-out `timeout`), read the status registers: a drive in fault takes nothing.
   The enable register, if the map has one, is set to 1.
   With a lock register in the map, the client first takes the drive's lock (its owner token,
   1..65535): while it holds it the drive refuses every other client's writes.
3. Per waypoint: one FC16 write of the whole block (every target and the waypoint index), then
   acknowledgement: the status read shows the drive's waypoint index at this waypoint's and no
   fault bit, and (``readback``) the block reads back register for register as written.
4. The first failure ends the sequence with a `DriveError`: which waypoint, why, the last
   waypoint the drive acknowledged, and whether the failed write's outcome is unknown.

What the report says the drive took comes only from what the drive reports, read back: its
waypoint index and the registers it holds. Anything unexpected is read again, and acted upon
only when two consecutive reads agree (a response corrupted on the way is not the drive's
word). Then:

- index at this waypoint's and the block as written: taken;
- index still at the previous waypoint's and the block as written: not yet taken (polled until
  ``ack_timeout``, then the outcome is unknown);
- the block not as written (a read-back mismatch): a failure of this waypoint, never a
  qualified success;
- the index elsewhere: another client is writing to the drive (or the index was changed on the
  way; when the drive holds this waypoint's targets under that index, it took them);
- the lock, if the map has one, not holding this client's token: another client has the drive.

Without the lock another client may write between this client's write and its read, so an
unexpected read leaves the failed waypoint's outcome unknown; with the lock held the drive's
report is definitive.

The waypoint index is a counter that continues from the drive's own (1..65535, wrapping), so a
stale index left from an earlier sequence never passes for an acknowledgement.

pymodbus 3.16 facts this relies on: error responses are returned (``isError()``), not raised;
``retries`` applies to response time-outs only, so a silent drive fails after
``timeout x (retries + 1)``; a retried FC16 write re-sends the same registers, which is harmless.
After a lost connection or a time-out nobody knows whether the last write was executed; the
report says so, and the client never reconnects on its own in the middle of a sequence.
"""

from __future__ import annotations

import secrets
import socket
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pymodbus.client import ModbusTcpClient
from pymodbus.constants import ExcCodes
from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

from armkit.drives.registers import MAX_READ, RegisterMap, runs
from armkit.errors import DriveError, InputError
from armkit.model import joint_array

# How often the acknowledgement read is repeated while a drive has not yet taken a waypoint.
ACK_POLL = 0.001   # s
# Consecutive reads that must agree before the client acts on an unexpected acknowledgement.
CONFIRM_READS = 2
DEVICE_BUSY = 6    # the exception a drive answers to a write while another client holds its lock
ILLEGAL_VALUE = 3  # the exception a drive answers to a waypoint it refuses (outside its limits)


def port_number(port: int) -> int:
    """A TCP port, 0..65535 (0: any free port, for a server).

    Raises
    ------
    InputError
        Otherwise: the operating system would take a larger number modulo 65536.
    """
    if not (isinstance(port, (int, np.integer)) and 0 <= port <= 65535):
        raise InputError(f"port: expected 0..65535, found {port!r}")
    return int(port)


@dataclass(frozen=True)
class SendResult:
    """A sequence the drive took whole.

    Attributes
    ----------
    waypoints : int
        Number of waypoints sent and acknowledged.
    last_accepted : int
        Index (from 0) of the last one: ``waypoints - 1``.
    indices : tuple of int
        The drive's waypoint index written with each waypoint (empty without an index register).
    seconds : float
        From the first write to the last acknowledgement, s.
    """

    waypoints: int
    last_accepted: int
    indices: tuple[int, ...]
    seconds: float


@dataclass(frozen=True)
class DriveStatus:
    """What the drive's status registers say.

    Attributes
    ----------
    q : ndarray, shape (n,)
        Actual joint positions (rad, m); NaN without actual-position registers.
    state : int or None
        The state bits, if the map has a state register.
    fault_code : int or None
        The fault code register, if any (0: no fault).
    accepted : int or None
        The drive's index of the last waypoint it took, if any.
    faulted : bool
        The state's fault bit is set, or the fault code is non-zero.
    lock : int or None
        The lock register (the owner's token, 0 when free), if the map has one.
    moving : bool or None
        The state's moving bit (`RegisterMap.moving_bit`); None without one.
    """

    q: NDArray
    state: int | None
    fault_code: int | None
    accepted: int | None
    faulted: bool
    lock: int | None = None
    moving: bool | None = None


def check_waypoints(register_map: RegisterMap, q: ArrayLike,
                    t: ArrayLike | None = None) -> NDArray:
    """Check a sequence of waypoints against the robot's joint and velocity limits.

    Parameters
    ----------
    register_map : RegisterMap
    q : array_like, shape (N, n) or (n,)
        Waypoints; rad for revolute, m for prismatic joints.
    t : array_like, shape (N,), optional
        Waypoint times, s, strictly increasing; then the joint speed between consecutive
        waypoints is checked against the velocity limits.

    Returns
    -------
    q : ndarray, shape (N, n)

    Raises
    ------
    InputError
        Naming the waypoint (from 0), the joint and the value in the robot file's units:
        ``waypoint 3, joint q2: 190 deg outside the limits -180..180 deg``.
    """
    robot = register_map.robot
    try:
        q = joint_array(robot, q, "waypoints")
    except InputError:
        _name_non_finite(robot, q)            # which waypoint and joint, if that was it
        raise
    if q.ndim == 1:
        q = q[None]
    if q.ndim != 2 or len(q) == 0:
        raise InputError(f"waypoints: expected shape (N, {robot.n}) with N >= 1, "
                         f"found {q.shape}")
    outside = (q < robot.lower) | (q > robot.upper)
    if outside.any():
        k, i = np.argwhere(outside)[0]
        value, lo, hi = robot.q_from_si([q[k], robot.lower, robot.upper])[:, i]
        raise InputError(f"waypoint {k}, joint {robot.joint_names[i]}: {value:.6g} "
                         f"{register_map.robot.joint_units[i]} outside the limits {lo:.6g}..{hi:.6g} "
                         f"{register_map.robot.joint_units[i]}")
    if t is None:
        return q
    t = np.asarray(t, dtype=float)
    if t.shape != (len(q),):
        raise InputError(f"waypoint times: expected {len(q)} values (one per waypoint), found "
                         f"shape {t.shape}")
    if not np.isfinite(t).all():
        raise InputError(f"waypoint times: expected finite values, found "
                         f"{t[~np.isfinite(t)][0]} at waypoint {int(np.argmax(~np.isfinite(t)))}")
    dt = np.diff(t)
    if (dt <= 0).any():
        k = int(np.argmax(dt <= 0))
        raise InputError(f"waypoint times: expected strictly increasing, found {t[k]:g} s then "
                         f"{t[k + 1]:g} s at waypoints {k} and {k + 1}")
    with np.errstate(over="ignore"):          # a step over a denormal dt: inf, too fast
        speed = np.abs(np.diff(q, axis=0)) / dt[:, None]
    too_fast = speed > robot.chain.velocity_limits
    if too_fast.any():
        k, i = np.argwhere(too_fast)[0]
        v, limit = robot.q_from_si([speed[k], robot.chain.velocity_limits])[:, i]
        raise InputError(f"waypoints {k} -> {k + 1}, joint {robot.joint_names[i]}: {v:.6g} "
                         f"{register_map.robot.joint_units[i]}/s over the velocity limit {limit:.6g} "
                         f"{register_map.robot.joint_units[i]}/s")
    return q


def _name_non_finite(robot, q) -> None:
    """Raise an InputError naming the first non-finite waypoint value of q (N, n) or (n,)."""
    try:
        values = np.asarray(q, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return
    if values.ndim in (1, 2) and values.shape[-1] == robot.n:
        values = values.reshape(-1, robot.n)
        bad = np.argwhere(~np.isfinite(values))
        if len(bad):
            k, i = bad[0]
            raise InputError(f"waypoint {k}, joint {robot.joint_names[i]}: expected a finite "
                             f"value, found {values[k, i]}") from None


class _Failed(Exception):
    """A step failed: why, whether the waypoint's outcome is unknown, whether it was taken,
    and the Modbus exception code of an exception response (0 for none)."""

    def __init__(self, cause: str, unknown: bool, taken: bool = False, code: int = 0):
        super().__init__(cause)
        self.cause, self.unknown, self.taken, self.code = cause, unknown, taken, code


class _TcpClient(ModbusTcpClient):
    """pymodbus's sync TCP client, made to tell what happened.

    It keeps why a connect failed (pymodbus only logs it), records whether a request's bytes
    left, and connects only when asked: pymodbus would otherwise reconnect silently on the next
    request after a lost connection, in the middle of a sequence.
    """

    may_connect = True
    connect_error: OSError | None = None
    request_left = False

    def connect(self) -> bool:
        if self.socket is not None:
            return True
        if not self.may_connect:
            return False
        try:
            self.socket = socket.create_connection(
                (self.comm_params.host, self.comm_params.port),
                timeout=self.comm_params.timeout_connect,
                source_address=self.comm_params.source_address)
        except OSError as err:
            self.connect_error = err
            self.socket = None
        return self.socket is not None

    def send(self, request, addr=None):
        sent = super().send(request, addr)
        self.request_left = True
        return sent


class DriveClient:
    """A Modbus TCP connection to a drive that takes waypoints of one register map.

    Parameters
    ----------
    register_map : RegisterMap
    host : str
    port : int
    timeout : float
        Connect and response time-out, s.
    retries : int
        Re-sends after a response time-out (pymodbus ``retries``); a silent drive is reported
        after ``timeout x (retries + 1)``.
    ack_timeout : float
        How long a drive may take to show a waypoint's index in its status, s.

    Example
    -------
    >>> from importlib import resources
    >>> from armkit.drives import SimDrive
    >>> from armkit.io.register_maps import load_register_map
    >>> drive_map = load_register_map(resources.files("armkit.drives") / "inspection_6dof.map.yaml")
    >>> q = np.deg2rad([[0, 0, 0, 0, 0, 0], [5, 5, 5, 5, 5, 5]])     # (N, n) in rad/m
    >>> with SimDrive(drive_map) as sim, DriveClient(drive_map, port=sim.port) as drive:
    ...     drive.send(q, [0.0, 1.0]).last_accepted                    # t (N,) in s
    1
    """

    def __init__(self, register_map: RegisterMap, host: str = "127.0.0.1", port: int = 502, *,
                 timeout: float = 1.0, retries: int = 0, ack_timeout: float = 1.0):
        if not (timeout > 0 and ack_timeout > 0 and retries >= 0):
            raise InputError(f"drive client: expected timeout > 0, ack_timeout > 0 and "
                             f"retries >= 0, found {timeout}, {ack_timeout} and {retries}")
        self.map, self.host, self.port = register_map, host, port_number(port)
        self.timeout, self.retries, self.ack_timeout = timeout, int(retries), ack_timeout
        self._client = _TcpClient(host, port=self.port, timeout=timeout, retries=self.retries)
        self._index: int | None = None     # the drive's waypoint index last written or read
        self._taken: int | None = None     # the last waypoint of this sequence acknowledged
        self._token: int | None = None     # this client's owner token, with a lock register
        self._locked = False               # whether this connection took the drive's lock
        self._unread = np.full(register_map.n, np.nan)      # positions not read
        self._unread.setflags(write=False)

    # --- connection ---

    def connect(self) -> DriveClient:
        """Open the connection.

        Raises
        ------
        DriveError
            ``cannot connect to 127.0.0.1:5020: Connection refused``.
        """
        client = self._client
        client.may_connect = True
        if not client.connect():
            err = client.connect_error
            why = (err.strerror or str(err)) if err else "failed"
            if isinstance(err, TimeoutError | socket.timeout):
                why = f"no answer within {self.timeout:g} s"
            raise DriveError(f"cannot connect to {self.host}:{self.port}: {why}")
        client.may_connect = False
        return self

    def close(self) -> None:
        """Free the drive's lock (if this client took it and the connection is sound), then
        close the connection."""
        if self._locked and self._client.socket is not None:
            try:
                self._request("write_register", self.map.lock, 0)
            except _Failed:
                pass                        # the drive frees it when the connection ends
        self._abandon()

    def _abandon(self) -> None:
        """Close the connection without a further request (after a failure)."""
        self._client.close()
        self._index = None
        self._locked = False

    def __enter__(self) -> DriveClient:
        return self.connect()

    def __exit__(self, *exc) -> None:
        self.close()

    # --- requests ---

    def _request(self, method: str, *args, **kwargs):
        """One request; a failure of any kind is a _Failed with its cause."""
        client = self._client
        client.request_left = False
        try:
            response = getattr(client, method)(*args, device_id=self.map.device_id, **kwargs)
        except ConnectionException:
            raise _Failed("connection lost" if client.request_left else "not connected",
                          client.request_left) from None
        except ModbusIOException as err:
            attempts = self.retries + 1
            if "No response received" not in str(err):     # a response for another request
                raise _Failed(f"invalid response: {err}", True) from None
            raise _Failed(f"no response within {self.timeout:g} s x {attempts} "
                          f"attempt{'s' * (attempts > 1)}", True) from None
        except (ModbusException, OSError) as err:
            raise _Failed(f"{type(err).__name__}: {err}", client.request_left) from None
        if response.isError():
            code = getattr(response, "exception_code", 0)
            name = (ExcCodes(code).name.lower().replace("_", " ")
                    if code in set(ExcCodes) else "unknown code")
            raise _Failed(f"Modbus exception {code} ({name})", False, code=code)
        return response

    def _read(self, reads) -> dict[int, int]:
        values: dict[int, int] = {}
        for address, count in reads:
            registers = self._request("read_holding_registers", address, count=count).registers
            if len(registers) != count:
                raise _Failed(f"read of {count} registers at {address} returned "
                              f"{len(registers)}", False)
            values.update(zip(range(address, address + count), registers))
        return values

    def status(self) -> DriveStatus:
        """Read the status registers (and actual positions, if the map has them).

        Raises
        ------
        DriveError
        """
        m = self.map
        addresses = {a for a in (m.accepted, m.state, m.fault, m.lock) if a is not None}
        for joint in m.joints:
            if joint.actual is not None:
                addresses.update(range(joint.actual, joint.actual + joint.count))
        try:
            values = self._read(runs(addresses, MAX_READ))
        except _Failed as failed:
            raise DriveError(f"status read failed: {failed.cause}", self._taken) from None
        q = np.full(m.n, np.nan)
        if all(j.actual is not None for j in m.joints):
            q_file = [float(j.value([values[a] for a in range(j.actual, j.actual + j.count)]))
                      for j in m.joints]
            q = m.robot.q_to_si(q_file)
        return self._status(values, q)

    def _status(self, values: dict[int, int], q: NDArray) -> DriveStatus:
        m = self.map
        state = values.get(m.state) if m.state is not None else None
        code = values.get(m.fault) if m.fault is not None else None
        faulted = bool(state is not None and state >> m.fault_bit & 1) or bool(code)
        accepted = values.get(m.accepted) if m.accepted is not None else None
        lock = values.get(m.lock) if m.lock is not None else None
        moving = (bool(state >> m.moving_bit & 1)
                  if state is not None and m.moving_bit is not None else None)
        return DriveStatus(q, state, code, accepted, faulted, lock, moving)

    # --- waypoints ---

    def send(self, q: ArrayLike, t: ArrayLike | None = None) -> SendResult:
        """Check, then send a sequence of waypoints, each acknowledged before the next.

        Parameters
        ----------
        q : array_like, shape (N, n)
            Waypoints, rad and m.
        t : array_like, shape (N,), optional
            Waypoint times, s: the velocity limits are checked too.

        Returns
        -------
        SendResult

        Raises
        ------
        InputError
            A waypoint outside the limits, before any connection is made.
        DriveError
            The first failure: ``waypoint 4: no response within 1 s x 1 attempt (last accepted
            waypoint: 3; whether the drive took waypoint 4 is unknown)``.
        """
        blocks = self._encode(check_waypoints(self.map, q, t))
        self._start()
        started = time.perf_counter()
        indices = []
        for k, block in enumerate(blocks):
            indices.append(self._write(k, block))
        seconds = time.perf_counter() - started
        return SendResult(len(blocks), len(blocks) - 1,
                          tuple(indices) if self.map.waypoint is not None else (), seconds)

    def write_waypoint(self, q: ArrayLike) -> int:
        """Check and send one waypoint (n,), rad and m; returns the drive's index for it.

        Raises
        ------
        InputError, DriveError
            As `send`, the single waypoints counted from 0 since the connection was made.
        """
        block = self._encode(check_waypoints(self.map, q)[0])
        if self._index is None:
            self._start()
        index = self._write(self._singles, block)
        self._singles += 1
        return index

    def _encode(self, q: NDArray) -> list:
        """Checked waypoints (..., n), SI, as register lists."""
        return self.map.encode_file(self.map.robot.q_from_si(q)).tolist()

    def _start(self) -> None:
        """Before the first waypoint: connected, the lock taken, no fault, the drive's index,
        enable set."""
        m = self.map
        if self._client.socket is None:
            try:
                self.connect()
            except DriveError as err:
                raise DriveError(err.cause, None, waypoint=0) from None
        try:
            if m.lock is not None:
                self._take_lock()
            values = self._read(m.ack_reads)
            status = self._status(values, self._unread)
            if m.lock is not None and status.lock != self._token:
                raise _Failed(self._lock_text(status.lock), False)
            if status.faulted:
                raise _Failed(f"drive in fault before the first waypoint "
                              f"({self._fault_text(status)})", False)
            self._index = status.accepted or 0
            self._singles, self._taken = 0, None
            if m.enable is not None:
                self._request("write_register", m.enable, 1)
        except _Failed as failed:
            self._abandon()
            raise DriveError(failed.cause, None, waypoint=0,
                             outcome_unknown=False) from None

    def _take_lock(self) -> None:
        """Write this client's owner token to the lock register."""
        if self._token is None:
            self._token = secrets.randbelow(65535) + 1
        try:
            self._request("write_register", self.map.lock, self._token)
        except _Failed as failed:
            if failed.code != DEVICE_BUSY:
                raise
            raise _Failed(f"{failed.cause}: {self._lock_text(self._lock_holder())}",
                          False) from None
        self._locked = True

    def _lock_holder(self) -> int | None:
        """The lock register as the drive reports it; None if it cannot be read."""
        try:
            return self._read([(self.map.lock, 1)])[self.map.lock]
        except _Failed:
            return None

    def _lock_text(self, held: int | None) -> str:
        if held is None:
            return "another client may hold the drive's lock (it could not be read)"
        if held == 0:
            return "the drive's lock is free, not held by this client: another client may write"
        return (f"another client holds the drive's lock (owner token {held:#06x}, this "
                f"client's {self._token:#06x})")

    def _write(self, k: int, block: list[int]) -> int:
        """Write waypoint k whole and wait for its acknowledgement; its index on the drive."""
        m = self.map
        index = self._index % 65535 + 1
        if m.waypoint is not None:
            block[m.waypoint - m.block_start] = index
        last = k - 1 if k > 0 else None
        try:
            self._request("write_registers", m.block_start, block)
        except _Failed as failed:
            cause = failed.cause
            if failed.code == DEVICE_BUSY and m.lock is not None:
                cause = f"{cause}: {self._lock_text(self._lock_holder())}"
            elif failed.code == ILLEGAL_VALUE:
                cause = (f"{cause}: the drive refused the values it received (checked within "
                         f"the limits here, so changed on the way or the drive's limits differ)")
            self._abandon()
            raise DriveError(cause, last, waypoint=k,
                             outcome_unknown=failed.unknown) from None
        try:
            self._acknowledge(index, block)
        except _Failed as failed:
            self._abandon()
            raise DriveError(failed.cause, k if failed.taken else last,
                             waypoint=k, outcome_unknown=failed.unknown) from None
        self._index, self._taken = index, k
        return index

    def _acknowledge(self, index: int, block: list[int]) -> None:
        """Read until the drive reports waypoint `index` taken as written; else _Failed.

        An unexpected report is acted upon only when CONFIRM_READS consecutive reads agree.
        """
        m = self.map
        deadline = time.monotonic() + self.ack_timeout
        seen, agreeing = None, 0
        while True:
            try:
                values = self._read(m.ack_reads)
            except _Failed as failed:
                # The write was answered, so the drive holds the registers; whether it took
                # the waypoint was not seen.
                raise _Failed(f"acknowledgement read failed: {failed.cause}", True) from None
            verdict, failure = self._verdict(values, index, block)
            if verdict == "taken":
                return
            if verdict == "pending":
                seen, agreeing = None, 0
                if time.monotonic() > deadline:
                    raise _Failed(f"not acknowledged within {self.ack_timeout:g} s: the "
                                  f"drive's waypoint index stayed at {self._index}", True)
                time.sleep(ACK_POLL)
                continue
            report = tuple(sorted(values.items()))
            seen, agreeing = report, (agreeing + 1 if report == seen else 1)
            if agreeing >= CONFIRM_READS:
                raise failure
            if time.monotonic() > deadline:
                raise _Failed(f"the drive's reports disagree from read to read (the last: "
                              f"{failure.cause})", True)

    def _verdict(self, values: dict[int, int], index: int,
                 block: list[int]) -> tuple[str, _Failed | None]:
        """What one acknowledgement read says of the waypoint written with `index`:
        ("taken", None), ("pending", None) or ("failed", the failure to raise)."""
        m = self.map
        status = self._status(values, self._unread)
        accepted, previous = status.accepted, self._index
        lock_held = m.lock is None or status.lock == self._token
        exclusive = m.lock is not None and lock_held    # no other client can have written
        held = [values[m.block_start + i] for i in range(m.block_count)] if m.readback else None
        as_written = held is None or held == block
        if m.waypoint is not None and held is not None:
            at = m.waypoint - m.block_start
            targets_held = held[:at] + held[at + 1:] == block[:at] + block[at + 1:]
            held_index = held[at]
        else:
            targets_held, held_index = False, None
        # Whether the drive took this waypoint: True, False, or None (its reports cannot say).
        if accepted is None or accepted == index:
            taken = True if as_written else (False if exclusive else None)
        elif accepted == previous:
            taken = False if (as_written or exclusive) else None
        elif targets_held and held_index == accepted:
            taken = True                   # this waypoint's targets, under another index
        else:
            taken = None                   # an index neither this client's nor the previous

        def failed(cause: str) -> tuple[str, _Failed]:
            return "failed", _Failed(cause, taken is None, taken=bool(taken))

        if not lock_held:
            return failed(self._lock_text(status.lock))
        if status.faulted:
            return failed(f"drive fault ({self._fault_text(status)})")
        if as_written and (accepted is None or accepted == index):
            return "taken", None
        if as_written and accepted == previous:
            return "pending", None
        others = "" if exclusive else "; another client may have written after it"
        if not as_written and (accepted is None or accepted in (index, previous)):
            offset = next(i for i, (h, w) in enumerate(zip(held, block)) if h != w)
            address = m.block_start + offset
            state = (f"under this waypoint's index {index}" if accepted == index else
                     "and its index says it has taken nothing since the previous waypoint"
                     if accepted is not None else "")
            return failed(f"read-back mismatch at register {address} ({m.joint_at(address)}): "
                          f"wrote {block[offset]:#06x}, the drive holds {held[offset]:#06x}"
                          f"{' ' * bool(state)}{state}{others}")
        if taken:
            return failed(f"the drive took this waypoint's targets under waypoint index "
                          f"{accepted}, not {index}: the index was changed on the way")
        if exclusive:
            return failed(f"the drive's waypoint index reads {accepted}, neither {index} nor "
                          f"{previous}, while this client holds its lock: the index was "
                          f"changed on the way")
        return failed(f"the drive's waypoint index moved to {accepted} without this client "
                      f"(it wrote {index} after {previous}): another client is writing to "
                      f"the drive")

    @staticmethod
    def _fault_text(status: DriveStatus) -> str:
        parts = []
        if status.state is not None:
            parts.append(f"state {status.state:#06x}")
        if status.fault_code is not None:
            parts.append(f"fault code {status.fault_code:#06x}")
        return ", ".join(parts)


def send_waypoints(register_map: RegisterMap, q: ArrayLike, t: ArrayLike | None = None, *,
                   host: str = "127.0.0.1", port: int = 502, timeout: float = 1.0,
                   retries: int = 0, ack_timeout: float = 1.0) -> SendResult:
    """Check a sequence of waypoints, then send it to a drive over Modbus TCP.

    Checks, connects, sends, closes. Parameters as `DriveClient` and `DriveClient.send`.

    Raises
    ------
    InputError
        A waypoint outside the limits (nothing was sent, no connection was made).
    DriveError
        Which waypoint failed, why, the last one the drive accepted.
    """
    drive = DriveClient(register_map, host, port, timeout=timeout, retries=retries,
                        ack_timeout=ack_timeout)
    try:
        return drive.send(q, t)        # checks before it connects
    finally:
        drive.close()
