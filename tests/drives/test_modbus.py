"""The client against the simulated drive on loopback: sequences read back exactly, limits
caught before anything leaves, and every fault reported with the right last accepted waypoint
and never a partly written waypoint."""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

from armkit.drives import DriveClient, SimDrive, check_waypoints, send_waypoints
from armkit.errors import DriveError, InputError
from armkit.io.register_maps import load_register_map
from tests.drives.conftest import (INSPECTION, TIMEOUT, assert_report_true, drive_took,
                                   locked_map, waypoints)


def assert_whole_waypoints(sim: SimDrive, register_map, blocks, flipped: bool = False) -> None:
    """Every write that touched the block covered all of it, and the drive holds one whole
    waypoint of `blocks` or its start (the index register aside; `flipped`: the first register
    with its lowest bit flipped, as the corrupt fault stores it)."""
    m = register_map
    for address, count in sim.writes:
        if address < m.block_start + m.block_count and address + count > m.block_start:
            assert (address, count) == (m.block_start, m.block_count)
    held = np.array(sim.registers(m.block_start, m.block_count))
    held[m.waypoint - m.block_start] = 0
    held[0] ^= flipped
    robot = m.robot
    home = robot.q_to_si(np.clip(0.0, robot.q_from_si(robot.lower), robot.q_from_si(robot.upper)))
    candidates = np.vstack([m.encode(home), blocks])
    assert (candidates == held).all(axis=1).any(), held


def test_ten_waypoints_arrive_exactly(any_map):
    q = waypoints(any_map, 10)
    with SimDrive(any_map) as sim:
        result = send_waypoints(any_map, q, port=sim.port, timeout=TIMEOUT)
        taken = np.array(sim.taken)
        writes = sim.writes
        held = sim.registers(any_map.block_start, any_map.block_count)
    assert (result.waypoints, result.last_accepted) == (10, 9)
    assert result.indices == tuple(range(1, 11))
    block_writes = [w for w in writes if w[0] == any_map.block_start]
    assert block_writes == [(any_map.block_start, any_map.block_count)] * 10
    expected = any_map.encode(q)
    expected[:, any_map.waypoint - any_map.block_start] = np.arange(1, 11)
    assert taken.tolist() == expected.tolist()                    # register for register
    assert held == expected[-1].tolist()
    q_file = any_map.robot.q_from_si(q)
    back = any_map.robot.q_from_si(any_map.decode(taken))
    for i, joint in enumerate(any_map.joints):
        sent, got = q_file[:, i] * joint.scale, back[:, i] * joint.scale
        if joint.type == "float32":                               # bit-exact
            assert np.float32(got).tobytes() == np.float32(sent).tobytes()
        else:                                                     # within one count
            assert np.abs(got - sent).max() <= 0.5 + 1e-9


def test_the_drive_moves_to_the_last_waypoint(inspection_map, sim):
    target = np.deg2rad([1.0, -2.0, 0.5, 3.0, -1.0, 2.0])       # a few deg: < 0.05 s at 90 deg/s
    with DriveClient(inspection_map, port=sim.port, timeout=TIMEOUT) as drive:
        assert drive.write_waypoint(target) == 1
        first = drive.status()
        deadline = time.monotonic() + 60.0      # a hang, not a speed: it takes < 0.05 s
        status = first
        while not np.allclose(status.q, target, atol=1e-9) and time.monotonic() < deadline:
            time.sleep(0.01)
            status = drive.status()
    assert first.state & 0b11 == 0b11                             # enabled and moving
    np.testing.assert_allclose(status.q, target, atol=1e-9)       # 1/1000 deg, exactly
    assert status.state & 0b11 == 0b01 and not status.faulted and status.accepted == 1


def test_index_continues_from_the_drive(inspection_map, sim):
    q = waypoints(inspection_map, 3)
    assert send_waypoints(inspection_map, q, port=sim.port).indices == (1, 2, 3)
    assert send_waypoints(inspection_map, q, port=sim.port).indices == (4, 5, 6)


def test_limit_violation_is_caught_before_anything_leaves(inspection_map, sim):
    q = waypoints(inspection_map, 10)
    q[6, 2] = np.deg2rad(181.0)
    with pytest.raises(InputError, match=r"waypoint 6, joint q3: 181 deg outside the limits "
                                         r"-180..180 deg"):
        send_waypoints(inspection_map, q, port=sim.port)
    with DriveClient(inspection_map, port=sim.port) as drive:
        with pytest.raises(InputError, match="waypoint 0, joint q3"):
            drive.write_waypoint(q[6])
    assert list(sim.requests) == []                               # no write, not even a read


def test_velocity_violation_with_times(inspection_map, sim):
    q = np.zeros((3, 6))
    q[2, 4] = np.deg2rad(100.0)                                   # 100 deg in 1 s: q5 allows 120
    check_waypoints(inspection_map, q, [0.0, 1.0, 2.0])
    with pytest.raises(InputError, match=r"waypoints 1 -> 2, joint q5: 200 deg/s over the "
                                         r"velocity limit 120 deg/s"):
        send_waypoints(inspection_map, q, [0.0, 1.0, 1.5], port=sim.port)
    with pytest.raises(InputError, match="strictly increasing"):
        check_waypoints(inspection_map, q, [0.0, 1.0, 1.0])
    with pytest.raises(InputError, match=r"expected 3 values \(one per waypoint\), found shape"):
        check_waypoints(inspection_map, q, [0.0, 1.0])
    with pytest.raises(InputError, match="expected finite values, found nan at waypoint 1"):
        check_waypoints(inspection_map, q, [0.0, np.nan, 2.0])
    with pytest.raises(InputError, match=r"waypoints: expected last axis 6"):
        check_waypoints(inspection_map, np.zeros((3, 5)))
    assert list(sim.requests) == []


# (fault, injected at waypoint write 3, keywords, cause, last accepted, outcome unknown without
# and with the drive's lock)
FAULTS = [
    ("exception", {"code": 4}, "Modbus exception 4 (device failure)", 2, False, False),
    ("exception", {"code": 6}, "Modbus exception 6 (device busy)", 2, False, False),
    ("fault", {}, "drive fault (state 0x8001, fault code 0x2310)", 2, False, False),
    ("ignore", {}, "not acknowledged within 0.2 s: the drive's waypoint index stayed at 3", 2,
     True, True),
    # The drive took a corrupt block under waypoint 3's index: not waypoint 3. Without the lock
    # another client could have written after it, so whether 3 was taken is unknown.
    ("corrupt", {}, "read-back mismatch at register 0 (joint q1)", 2, True, False),
    ("drop", {}, "connection lost", 2, True, True),
    ("drop", {"apply": True}, "connection lost", 2, True, True),
    ("silence", {}, f"no response within {TIMEOUT:g} s x 1 attempt", 2, True, True),
]


@pytest.mark.parametrize("locked", [False, True], ids=["plain", "locked"])
@pytest.mark.parametrize("kind, keywords, cause, last, unknown, unknown_locked", FAULTS)
def test_each_fault_reports_the_last_accepted_waypoint(kind, keywords, cause, last, unknown,
                                                       unknown_locked, locked):
    register_map = locked_map() if locked else load_register_map(INSPECTION)
    q = waypoints(register_map, 10)
    blocks = register_map.encode(q)
    with SimDrive(register_map) as sim:
        sim.inject(kind, at=3, **keywords)
        with pytest.raises(DriveError) as err:
            send_waypoints(register_map, q, port=sim.port, timeout=TIMEOUT, ack_timeout=0.2)
        sim.clear()
        assert_whole_waypoints(sim, register_map, blocks[:4], flipped=kind == "corrupt")
        taken = [block[:-1] for block in sim.taken]       # the index register aside
        took = drive_took(sim, register_map, q)
    e = err.value
    expected_unknown = unknown_locked if locked else unknown
    assert (e.waypoint, e.last_accepted, e.outcome_unknown) == (3, last, expected_unknown)
    assert e.cause.startswith(cause), e.cause
    assert_report_true(e, took)
    if kind == "corrupt":
        assert e.cause.endswith("under this waypoint's index 4" + (
            "" if locked else "; another client may have written after it")), e.cause
    assert f"(last accepted waypoint: {last}" in str(e)
    # The drive took waypoints 0..2 whole; after a drop it may also have taken 3, which the
    # client cannot know (outcome unknown); a corrupt write is taken with its wrong register.
    took_fourth = kind == "corrupt" or keywords.get("apply", False)
    assert len(taken) == 3 + took_fourth
    assert taken[:3] == blocks[:3, :-1].tolist()
    assert took == (3 if keywords.get("apply") else 2)


def test_single_writes_count_from_the_connection(inspection_map):
    q = waypoints(inspection_map, 5)
    with SimDrive(inspection_map) as sim:
        sim.inject("fault", at=3)
        with DriveClient(inspection_map, port=sim.port, timeout=TIMEOUT) as drive:
            for k in range(3):
                drive.write_waypoint(q[k])
            with pytest.raises(DriveError) as err:
                drive.write_waypoint(q[3])
    assert (err.value.waypoint, err.value.last_accepted) == (3, 2)


def test_a_drive_moves_only_to_waypoints_it_took(inspection_map):
    q = waypoints(inspection_map, 3)
    with SimDrive(inspection_map) as sim:
        sim.inject("ignore", at=1)
        with pytest.raises(DriveError):
            send_waypoints(inspection_map, q, port=sim.port, timeout=TIMEOUT, ack_timeout=0.2)
        np.testing.assert_allclose(sim.targets(), q[1], atol=1e-3)   # written, not taken
        assert len(sim.taken) == 1
        np.testing.assert_allclose(sim.goal, q[0], atol=1e-3)


@pytest.mark.parametrize("port", [-1, 65536, 70000])
def test_ports_outside_the_tcp_range_are_refused(inspection_map, port):
    with pytest.raises(InputError, match=f"port: expected 0..65535, found {port}"):
        DriveClient(inspection_map, port=port)
    with pytest.raises(InputError, match="port: expected 0..65535"):
        SimDrive(inspection_map, port=port)


def test_retries_resend_the_same_write(inspection_map):
    q = waypoints(inspection_map, 5)
    with SimDrive(inspection_map) as sim:
        sim.inject("silence", at=1)
        with pytest.raises(DriveError, match=r"no response within 0.1 s x 2 attempts"):
            send_waypoints(inspection_map, q, port=sim.port, timeout=0.1, retries=1)
        writes = sim.writes
    assert writes[-2:] == [(0, 13), (0, 13)]      # the same whole block twice


def test_a_drive_in_fault_takes_nothing(inspection_map):
    q = waypoints(inspection_map, 3)
    with SimDrive(inspection_map) as sim:
        sim.inject("fault", at=0)
        with pytest.raises(DriveError):
            send_waypoints(inspection_map, q[:1], port=sim.port, timeout=TIMEOUT)
        writes_before = len(sim.writes)
        with pytest.raises(DriveError, match=r"waypoint 0: drive in fault before the first "
                                             r"waypoint \(state 0x8001, fault code 0x2310\) "
                                             r"\(last accepted waypoint: none\)"):
            send_waypoints(inspection_map, q, port=sim.port, timeout=TIMEOUT)
        assert len(sim.writes) == writes_before
        sim.clear()
        assert send_waypoints(inspection_map, q, port=sim.port).waypoints == 3


def test_refused_and_absent_connections(inspection_map):
    q = waypoints(inspection_map, 3)
    with SimDrive(inspection_map) as sim:
        sim.inject("refuse")
        with pytest.raises(DriveError, match=rf"cannot connect to 127.0.0.1:{sim.port}: "
                                             r".*refused \(last accepted waypoint: none\)"):
            send_waypoints(inspection_map, q, port=sim.port, timeout=TIMEOUT)
        assert sim.writes == []
        sim.clear()
        assert send_waypoints(inspection_map, q, port=sim.port).waypoints == 3
    with socket.socket() as s:                     # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(DriveError, match="cannot connect") as err:
        send_waypoints(inspection_map, q, port=port, timeout=TIMEOUT)
    assert err.value.last_accepted is None and not err.value.outcome_unknown


def test_wrong_device_id_is_an_exception_response(inspection_map, sim):
    from dataclasses import replace
    other = replace(inspection_map, device_id=9)
    with pytest.raises(DriveError, match=r"waypoint 0: Modbus exception 11 \(gateway no response\)"):
        send_waypoints(other, waypoints(other, 2), port=sim.port, timeout=TIMEOUT)


def test_no_reconnect_after_a_lost_connection(inspection_map):
    with SimDrive(inspection_map) as sim:
        sim.inject("drop", at=1)
        drive = DriveClient(inspection_map, port=sim.port, timeout=TIMEOUT).connect()
        drive.write_waypoint(np.zeros(6))
        with pytest.raises(DriveError, match="connection lost"):
            drive.write_waypoint(np.zeros(6))
        drive.close()
        assert sim.waypoint_writes == 2


def test_bad_client_settings(inspection_map):
    with pytest.raises(InputError, match="timeout > 0"):
        DriveClient(inspection_map, timeout=0)


def test_drive_error_keeps_the_old_signature():
    err = DriveError("no connection", 4)
    assert str(err) == "no connection (last accepted waypoint: 4)"
    assert err.waypoint is None and not err.outcome_unknown


def test_the_readme_example_runs(monkeypatch):
    import armkit
    from tests.drives.conftest import ROOT
    text = (ROOT / "README.md").read_text().split("## Motor drives over Modbus TCP", 1)[1]
    code = text.split("```python", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(ROOT)
    scope = {"np": np, "armkit": armkit}
    exec(code, scope)                                             # noqa: S102 (our README)
    assert scope["result"].last_accepted == 2


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_waypoints_are_named_before_anything_leaves(inspection_map, sim, bad):
    q = waypoints(inspection_map, 4)
    q[2, 4] = bad
    with pytest.raises(InputError, match=rf"waypoint 2, joint q5: expected a finite value, "
                                         rf"found {bad}"):
        send_waypoints(inspection_map, q, port=sim.port)
    assert list(sim.requests) == []
