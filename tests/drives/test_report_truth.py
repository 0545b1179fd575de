"""The report is always true: after any fault, `last_accepted` is the last waypoint the drive
took (its own record, `SimDrive.taken`), or, when the report says the failed waypoint's outcome
is unknown, that waypoint may have been taken too; never the other way round.

Faults come from a proxy on loopback that corrupts the waypoint index and the target registers
on their way to the drive or back, and drops responses; and from second clients writing to the
same drive, with and without the drive's lock.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
from pyModbusTCP.client import ModbusClient

from armkit.drives import DriveClient, SimDrive, send_waypoints
from armkit.io.register_maps import load_register_map
from armkit.errors import DriveError
from tests.drives.conftest import INSPECTION, assert_report_true, drive_took, locked_map, waypoints
from tests.drives.proxy import FaultProxy, get_register, registers, set_register

TIMEOUT, ACK_TIMEOUT = 0.3, 0.3   # s
AT = 3                            # the waypoint write the fault hits (from 0)


class Faults:
    """Proxy hooks for one case: count the waypoint writes, act at write AT."""

    def __init__(self, register_map, case: str, drive_port: int):
        self.map, self.case, self.drive_port = register_map, case, drive_port
        self.writes = 0                # waypoint writes seen
        self.reads_after = 0           # acknowledgement reads answered after write AT
        self.rng = np.random.default_rng(7)
        self.second: list[int | None] = []    # the second writer's exception codes (0: none)

    def is_block_write(self, frame: bytes) -> bool:
        found = registers(frame)
        return (found is not None and found[0] == 16
                and found[1:3] == (self.map.block_start, self.map.block_count))

    def on_request(self, frame: bytes) -> bytes | None:
        m = self.map
        if not self.is_block_write(frame):
            return frame
        self.writes += 1
        if self.writes - 1 != AT:
            return frame
        index_at = m.waypoint - m.block_start
        if self.case == "index corrupted in the write":
            return set_register(frame, 13, index_at, get_register(frame, 13, index_at) + 1000)
        if self.case == "target corrupted in the write":           # q1 + 65.5 deg
            value = (get_register(frame, 13, 0) << 16 | get_register(frame, 13, 1)) + 65500
            value = (value + 2**31) % 2**32 - 2**31
            value = value - 360000 if value > 180000 else value
            frame = set_register(frame, 13, 0, (value & 0xFFFFFFFF) >> 16)
            return set_register(frame, 13, 1, value & 0xFFFF)
        if self.case == "target corrupted out of the limits":      # q1 = 500 deg
            frame = set_register(frame, 13, 0, 500000 >> 16)
            return set_register(frame, 13, 1, 500000 & 0xFFFF)
        return frame

    def on_response(self, request: bytes, response: bytes) -> bytes | None:
        m = self.map
        if self.is_block_write(request) and self.writes - 1 == AT:
            if self.case == "response to the write dropped":
                return None
            if self.case.startswith("second writer"):
                self.write_as_second_client(same_index="same index" in self.case)
            return response
        found = registers(request)
        if (self.writes - 1 < AT or found is None or found[0] != 3 or response[7] != 3
                or not found[1] <= m.accepted < found[1] + found[2]):
            return response                         # only reads of the status from write AT on
        self.reads_after += 1
        first = self.reads_after == 1
        start = found[1]
        accepted_at, offset = m.accepted - start, 9               # the values after the byte count
        if self.case == "response to the acknowledgement dropped" and first:
            return None
        if self.case == "index corrupted in one acknowledgement" and first:
            return set_register(response, offset, accepted_at, 0x5A5A)
        if self.case == "index corrupted in every acknowledgement":
            return set_register(response, offset, accepted_at, int(self.rng.integers(1, 65535)))
        if self.case == "index corrupted alike in every acknowledgement":
            return set_register(response, offset, accepted_at,
                                get_register(response, offset, accepted_at) ^ 0x0100)
        if self.case == "target corrupted in one read-back" and first:
            return set_register(response, offset, 1, get_register(response, offset, 1) ^ 0x0040)
        return response

    def write_as_second_client(self, same_index: bool) -> None:
        """Another client writes a waypoint of its own straight to the drive."""
        m = self.map
        other = ModbusClient("127.0.0.1", self.drive_port, unit_id=m.device_id, timeout=2.0)
        try:
            accepted = other.read_holding_registers(m.accepted, 1)[0]
            block = m.encode(np.deg2rad([5.0, 6, 7, 8, 9, 10])).tolist()
            block[m.waypoint - m.block_start] = accepted if same_index else accepted % 65535 + 1
            ok = other.write_multiple_registers(m.block_start, block)
            self.second.append(0 if ok else other.last_except)
        finally:
            other.close()


# case: (plain map, locked map) outcome: "ok", or (last accepted, outcome unknown, cause part)
CASES = {
    "index corrupted in the write": ((AT, False, "under waypoint index"),) * 2,
    "index corrupted in one acknowledgement": ("ok", "ok"),
    "index corrupted in every acknowledgement": ((AT - 1, True, "disagree"),) * 2,
    "index corrupted alike in every acknowledgement": (
        (AT - 1, True, "another client is writing"), (AT - 1, True, "changed on the way")),
    "target corrupted in the write": ((AT - 1, True, "read-back mismatch"),
                                      (AT - 1, False, "read-back mismatch")),
    "target corrupted out of the limits": ((AT - 1, False, "Modbus exception 3"),) * 2,
    "target corrupted in one read-back": ("ok", "ok"),
    "response to the write dropped": ((AT - 1, True, "no response"),) * 2,
    "response to the acknowledgement dropped": ((AT - 1, True, "acknowledgement read"),) * 2,
    "second writer, its own index": ((AT - 1, True, "another client is writing"), "ok"),
    "second writer, same index": ((AT - 1, True, "another client may have written"), "ok"),
}


@pytest.mark.parametrize("locked", [False, True], ids=["plain", "locked"])
@pytest.mark.parametrize("case", list(CASES))
def test_the_report_is_what_the_drive_took(case, locked):
    register_map = locked_map() if locked else load_register_map(INSPECTION)
    q = waypoints(register_map, 10, seed=11)
    expected = CASES[case][locked]
    with SimDrive(register_map) as sim:
        faults = Faults(register_map, case, sim.port)
        with FaultProxy(sim.port, faults.on_request, faults.on_response) as proxy:
            try:
                result = send_waypoints(register_map, q, port=proxy.port, timeout=TIMEOUT,
                                        ack_timeout=ACK_TIMEOUT)
                err = None
            except DriveError as caught:
                err, result = caught, None
        took = drive_took(sim, register_map, q)
    if expected == "ok":
        assert err is None, str(err)
        assert result.last_accepted == took == 9
    else:
        assert err is not None, "not reported"
        last, unknown, words = expected
        assert (err.waypoint, err.last_accepted, err.outcome_unknown) == (AT, last, unknown), \
            str(err)
        assert words in err.cause, err.cause
        assert_report_true(err, took)
    if case.startswith("second writer"):
        assert faults.second == [6 if locked else 0]          # the lock kept it out


def run_clients(register_map, port: int, count: int) -> list:
    """`count` clients send 10 waypoints each to one drive at once; their results or errors."""
    start = threading.Barrier(count, timeout=10)
    outcomes: list = [None] * count

    def send(c: int) -> None:
        q = waypoints(register_map, 10, seed=100 + c)
        start.wait()
        try:
            outcomes[c] = send_waypoints(register_map, q, port=port, timeout=1.0,
                                         ack_timeout=1.0)
        except DriveError as err:
            outcomes[c] = err

    threads = [threading.Thread(target=send, args=(c,)) for c in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert not any(t.is_alive() for t in threads)
    return outcomes


@pytest.mark.parametrize("attempt", range(3))      # each run interleaves the clients anew
def test_four_clients_at_once_each_report_what_the_drive_took(attempt):
    register_map = load_register_map(INSPECTION)
    with SimDrive(register_map) as sim:
        outcomes = run_clients(register_map, sim.port, 4)
        for c, outcome in enumerate(outcomes):
            took = drive_took(sim, register_map, waypoints(register_map, 10, seed=100 + c))
            if isinstance(outcome, DriveError):
                assert "another client" in outcome.cause, outcome.cause
                assert_report_true(outcome, took)
            else:
                assert outcome.last_accepted == took == 9


def test_with_the_lock_one_client_at_a_time_has_the_drive():
    register_map = locked_map()
    with SimDrive(register_map) as sim:
        outcomes = run_clients(register_map, sim.port, 4)
        taken = [tuple(block[:-1]) for block in sim.taken]
    sequences = {c: [tuple(b[:-1]) for b in register_map.encode(
        waypoints(register_map, 10, seed=100 + c)).tolist()] for c in range(4)}
    done = [c for c, outcome in enumerate(outcomes) if not isinstance(outcome, DriveError)]
    assert done
    for c, outcome in enumerate(outcomes):
        if isinstance(outcome, DriveError):
            assert (outcome.waypoint, outcome.last_accepted, outcome.outcome_unknown) == (
                0, None, False)
            assert "another client holds the drive's lock" in outcome.cause, outcome.cause
    # The drive took whole sequences, one after another, never interleaved.
    expected_runs = sorted(tuple(sequences[c]) for c in done)
    runs = sorted(tuple(taken[i:i + 10]) for i in range(0, len(taken), 10))
    assert len(taken) == 10 * len(done) and runs == expected_runs


def test_a_client_that_keeps_the_connection_keeps_the_lock():
    register_map = locked_map()
    q = waypoints(register_map, 3)
    with SimDrive(register_map) as sim:
        with DriveClient(register_map, port=sim.port, timeout=TIMEOUT) as first:
            first.send(q)
            with pytest.raises(DriveError, match="another client holds the drive's lock") as e:
                send_waypoints(register_map, q, port=sim.port, timeout=TIMEOUT)
            assert e.value.last_accepted is None and not e.value.outcome_unknown
            assert first.status().lock not in (None, 0)
            first.send(q)
        assert send_waypoints(register_map, q, port=sim.port).last_accepted == 2
        assert sim.registers(register_map.lock)[0] == 0       # freed on close
