"""The simulated drive as a Modbus TCP device, driven by clients that are not armkit's: pyModbusTCP
and raw sockets, against `armkit sim-drive` running as its own process.

What a device owes its clients (Modbus Application Protocol V1.1b3, Messaging on TCP/IP
Implementation Guide V1.0b): the standard exception codes with the function code's high bit
set, its unit ids, every pipelined request answered in order; and what a drive owes its
joints: no target outside the limits, no state it cannot leave.
"""

from __future__ import annotations

import os
import re
import select
import socket
import struct
import subprocess
import sys

import numpy as np
import pytest
import yaml
from pyModbusTCP.client import ModbusClient

from armkit.drives import SimDrive
from armkit.io.register_maps import load_register_map
from tests.drives.conftest import INSPECTION, WATER, locked_map

TIMEOUT = 2.0   # s, every socket read in these tests


def start_sim_drive(map_path) -> tuple[subprocess.Popen, int]:
    """`armkit sim-drive --port 0 --map FILE` as its own process; its port, read within 60 s."""
    server = subprocess.Popen([sys.executable, "-m", "armkit", "sim-drive", "--port", "0",
                               "--map", str(map_path)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True,
                              env={**os.environ, "COLUMNS": "200"})
    ready, _, _ = select.select([server.stdout], [], [], 60)     # bounded: never hangs
    line = server.stdout.readline() if ready else ""
    found = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
    if not found:
        server.kill()
        server.wait(timeout=10)
        pytest.fail(f"sim-drive did not start: {line!r}")
    return server, int(found.group(1))


@pytest.fixture(scope="module")
def drive_process(tmp_path_factory):
    """One sim-drive process for the module: the inspection map with a lock (29) and a fault
    reset (30); (port, map)."""
    doc = yaml.safe_load(INSPECTION.read_text())
    doc["command"].update(lock=29, reset=30)
    path = tmp_path_factory.mktemp("maps") / "locked.map.yaml"
    path.write_text(yaml.safe_dump(doc))
    server, port = start_sim_drive(path)
    try:
        yield port, load_register_map(path)
    finally:
        server.terminate()
        server.wait(timeout=10)


def client(port: int, unit: int = 1) -> ModbusClient:
    return ModbusClient("127.0.0.1", port, unit_id=unit, timeout=TIMEOUT, auto_open=True)


def frame(transaction: int, unit: int, pdu: bytes) -> bytes:
    return struct.pack(">HHHB", transaction, 0, len(pdu) + 1, unit) + pdu


def receive(sock: socket.socket) -> tuple[int, int, bytes] | None:
    """One Modbus TCP response: (transaction id, unit id, PDU); None once the drive closed."""
    header = b""
    while len(header) < 7:
        chunk = sock.recv(7 - len(header))
        if not chunk:
            return None
        header += chunk
    transaction, protocol, length, unit = struct.unpack(">HHHB", header)
    assert protocol == 0 and 2 <= length <= 254
    pdu = b""
    while len(pdu) < length - 1:
        chunk = sock.recv(length - 1 - len(pdu))
        assert chunk, "connection closed within a frame"
        pdu += chunk
    return transaction, unit, pdu


def ask(port: int, pdu: bytes, unit: int = 1) -> bytes:
    """One raw request, its response PDU."""
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as sock:
        sock.sendall(frame(7, unit, pdu))
        answer = receive(sock)
    assert answer is not None and answer[:2] == (7, unit)
    return answer[2]


def read(address: int, count: int) -> bytes:
    return struct.pack(">BHH", 3, address, count)


def write(address: int, values) -> bytes:
    values = [int(v) for v in values]
    return struct.pack(f">BHHB{len(values)}H", 16, address, len(values), 2 * len(values),
                       *values)


# --- the protocol -------------------------------------------------------------------------------

@pytest.mark.parametrize("pdu, expected", [
    (bytes([0x01, 0, 0, 0, 1]), bytes([0x81, 0x01])),          # read coils: not a drive's
    (bytes([0x41]), bytes([0xC1, 0x01])),                        # an unknown function
    (bytes([0x2B, 0x0E, 0x01, 0x00]), bytes([0xAB, 0x01])),      # device identification
    (read(0, 0), bytes([0x83, 0x03])),                            # quantity 0
    (read(0, 126), bytes([0x83, 0x03])),                          # quantity over 125
    (read(0, 1) + b"\x00", bytes([0x83, 0x03])),                  # a byte too many
    (read(60000, 2), bytes([0x83, 0x02])),                        # no such register
    (read(25, 10), bytes([0x83, 0x02])),                          # runs past the last one
    (struct.pack(">BHH", 6, 14, 1), bytes([0x86, 0x02])),         # the state: read only
    (struct.pack(">BHH", 6, 60000, 1), bytes([0x86, 0x02])),
    (write(13, [1]), bytes([0x90, 0x02])),                        # status.accepted: read only
    (struct.pack(">BHHB2H", 16, 0, 124, 248, 0, 0), bytes([0x90, 0x03])),   # quantity > 123
    (struct.pack(">BHHB2H", 16, 0, 2, 3, 0, 0), bytes([0x90, 0x03])),   # byte count wrong
    (struct.pack(">BHHB1H", 16, 0, 2, 4, 0), bytes([0x90, 0x03])),      # values missing
])
def test_standard_exception_responses(drive_process, pdu, expected):
    port, _ = drive_process
    assert ask(port, pdu) == expected


def test_pymodbustcp_reads_writes_and_sees_exception_codes(drive_process):
    port, m = drive_process
    c = client(port)
    try:
        regs = c.read_holding_registers(m.accepted, 3)
        assert regs is not None and len(regs) == 3
        assert c.write_single_register(m.enable, 1)
        assert c.read_holding_registers(m.enable, 1) == [1]
        assert c.read_holding_registers(60000, 1) is None and c.last_except == 2
        assert c.custom_request(read(0, 126)) is None and c.last_except == 3
        assert not c.write_single_register(m.state, 0) and c.last_except == 2
        assert c.custom_request(bytes([0x41])) is None and c.last_except == 1
    finally:
        c.close()


@pytest.mark.parametrize("unit", [1, 0, 255])
def test_the_unit_ids_a_tcp_device_answers(drive_process, unit):
    port, m = drive_process
    pdu = ask(port, read(m.accepted, 1), unit)
    assert pdu[:2] == bytes([3, 2])


@pytest.mark.parametrize("unit", [2, 9, 254])
def test_another_unit_id_is_a_gateway_exception(drive_process, unit):
    port, m = drive_process
    assert ask(port, read(m.accepted, 1), unit) == bytes([0x83, 0x0B])
    c = client(port, unit)
    try:
        assert c.read_holding_registers(m.accepted, 1) is None and c.last_except == 0x0B
    finally:
        c.close()


def test_pipelined_requests_are_each_answered_in_order(drive_process):
    port, m = drive_process
    requests = [(1, 1, read(0, 16)), (2, 1, bytes([0x41])), (3, 9, read(0, 1)),
                (4, 0, read(m.accepted, 2)), (5, 1, read(60000, 1)),
                (6, 255, struct.pack(">BHH", 6, m.enable, 1))]
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.sendall(b"".join(frame(t, u, pdu) for t, u, pdu in requests))   # one segment
        answers = [receive(sock) for _ in requests]
    assert [(a[0], a[1]) for a in answers] == [(t, u) for t, u, _ in requests]
    assert answers[0][2][:2] == bytes([3, 32]) and len(answers[0][2]) == 34
    assert [a[2] for a in answers[1:]] == [bytes([0xC1, 1]), bytes([0x83, 0x0B]),
                                           answers[3][2], bytes([0x83, 2]),
                                           struct.pack(">BHH", 6, m.enable, 1)]
    assert answers[3][2][:2] == bytes([3, 4])


def test_a_request_split_over_segments_is_answered_once(drive_process):
    port, m = drive_process
    data = frame(11, 1, read(m.accepted, 1)) + frame(12, 1, read(m.accepted, 1))
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        for cut in (3, 9, len(data)):
            sock.sendall(data[:cut])
            data = data[cut:]
        assert [receive(sock)[0] for _ in range(2)] == [11, 12]


@pytest.mark.parametrize("garbage", [
    struct.pack(">HHHB", 1, 0, 0, 1),              # length 0: no room for the unit id
    struct.pack(">HHHB", 1, 0, 1000, 1),           # length over 254
    b"GET / HTTP/1.1\r\nHost: x\r\n\r\n",           # not Modbus at all
])
def test_a_broken_frame_closes_that_connection_only(drive_process, garbage):
    port, m = drive_process
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as sock:
        sock.sendall(garbage)
        assert receive(sock) is None                  # closed, nothing answered
    assert ask(port, read(m.accepted, 1))[:2] == bytes([3, 2])   # the drive serves on


def test_another_protocol_id_is_dropped_and_the_next_frame_answered(drive_process):
    port, m = drive_process
    other = struct.pack(">HHHB", 5, 1, 6, 1) + read(0, 1)
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as sock:
        sock.sendall(other + frame(6, 1, read(m.accepted, 1)))
        assert receive(sock)[0] == 6


# --- the drive --------------------------------------------------------------------------------

def block_for(m, q_file, index: int) -> list[int]:
    """A raw waypoint block: targets (robot file units) encoded as the map says."""
    block = m.encode_file(q_file).tolist()
    block[m.waypoint - m.block_start] = index
    return block


@pytest.mark.parametrize("joint, value", [(0, 500.0), (1, -1000.0), (2, 180.5), (5, -181.0)])
def test_targets_outside_the_limits_are_refused(drive_process, joint, value):
    port, m = drive_process
    c = client(port)
    try:
        before = c.read_holding_registers(0, 14)                 # block and accepted
        q = np.zeros(6)
        q[joint] = value
        assert not c.write_multiple_registers(0, block_for(m, q, 60000))
        assert c.last_except == 3                                 # illegal data value
        assert c.read_holding_registers(0, 14) == before          # nothing held, nothing taken
        raw = block_for(m, np.zeros(6), 60001)
        raw[2 * joint:2 * joint + 2] = [0x7FFF, 0xFFFF]           # int32 max
        assert not c.write_multiple_registers(0, raw) and c.last_except == 3
        ok = block_for(m, np.full(6, 180.0), 60002)               # on the limits: taken
        assert c.write_multiple_registers(0, ok)
        assert c.read_holding_registers(m.accepted, 1) == [60002]
    finally:
        c.close()


def test_a_partial_block_write_is_held_not_taken(drive_process):
    port, m = drive_process
    c = client(port)
    try:
        accepted = c.read_holding_registers(m.accepted, 1)
        assert c.write_multiple_registers(0, [0, 5000])           # q1 only: 5 deg
        assert c.read_holding_registers(0, 2) == [0, 5000]
        assert c.read_holding_registers(m.accepted, 1) == accepted
    finally:
        c.close()


def test_the_lock_gives_one_connection_the_drive(drive_process):
    port, m = drive_process
    a, b = client(port), client(port)
    try:
        assert a.write_single_register(m.lock, 0x1234)
        assert b.read_holding_registers(m.lock, 1) == [0x1234]     # anyone may read
        assert not b.write_single_register(m.enable, 1) and b.last_except == 6
        assert not b.write_multiple_registers(0, block_for(m, np.zeros(6), 5)) \
            and b.last_except == 6
        assert not b.write_single_register(m.lock, 0) and b.last_except == 6
        assert a.write_multiple_registers(0, block_for(m, np.zeros(6), 7))
        a.close()                                                   # the owner leaves
        for _ in range(200):                                        # bounded: <= 2 s
            if b.read_holding_registers(m.lock, 1) == [0]:
                break
            select.select([], [], [], 0.01)
        assert b.read_holding_registers(m.lock, 1) == [0]
        assert b.write_single_register(m.lock, 0x4321)
        assert b.write_single_register(m.lock, 0)                   # and frees it
        assert b.read_holding_registers(m.lock, 1) == [0]
    finally:
        a.close()
        b.close()


# In-process drives from here on: their state is read without a request.

def float_map(**out_of_limits):
    doc = yaml.safe_load(INSPECTION.read_text())
    for joint in doc["joints"]:
        joint.update(type="float32", scale=1.0)
    doc["command"]["reset"] = 30
    if out_of_limits:
        doc["out_of_limits"] = out_of_limits
    from armkit.io.register_maps import parse_register_map
    return parse_register_map(doc, "float32 map")


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_and_inf_targets_are_refused_and_the_drive_goes_on(bad):
    m = float_map()
    with SimDrive(m) as sim:
        c = client(sim.port)
        try:
            q = np.zeros(6)
            q[3] = bad
            raw = m.encode_file(np.zeros(6)).tolist()
            raw[6:8] = np.array([bad], dtype=">f4").view(">u2").tolist()
            raw[m.waypoint - m.block_start] = 1
            assert not c.write_multiple_registers(0, raw) and c.last_except == 3
            assert len(sim.refused) == 1 and len(sim.taken) == 0
            good = block_for(m, np.full(6, 1.5), 2)
            assert c.write_multiple_registers(0, good)              # every later request works
            assert c.read_holding_registers(m.accepted, 1) == [2]
            assert np.isfinite(sim.position).all() and np.isfinite(sim.goal).all()
        finally:
            c.close()


def test_a_map_may_say_the_drive_faults_instead():
    m = float_map(response="fault", fault_code=0x5555)
    with SimDrive(m) as sim:
        c = client(sim.port)
        try:
            raw = block_for(m, np.array([0, 0, 0, 0, 0, 720.0]), 1)
            assert c.write_multiple_registers(0, raw)               # held, not taken
            state, fault = c.read_holding_registers(m.state, 2)
            assert state >> 15 & 1 and fault == 0x5555
            assert c.read_holding_registers(m.accepted, 1) == [0] and len(sim.taken) == 0
            assert np.all(np.abs(np.rad2deg(sim.goal)) <= 180)
            assert c.write_single_register(m.reset, 1)              # the way out
            state, fault = c.read_holding_registers(m.state, 2)
            assert not state >> 15 & 1 and fault == 0
            assert c.write_multiple_registers(0, block_for(m, np.full(6, 2.0), 2))
            assert c.read_holding_registers(m.accepted, 1) == [2]
        finally:
            c.close()


@pytest.mark.parametrize("lift", [-5000.0, 600.5, 1e30])
def test_the_water_supply_lift_stays_within_its_travel(lift):
    m = load_register_map(WATER)
    with SimDrive(m) as sim:
        c = client(sim.port, m.device_id)
        try:
            raw = block_for(m, np.array([lift, 0, 0, 0]), 1)
            assert not c.write_multiple_registers(m.block_start, raw) and c.last_except == 3
            assert c.write_multiple_registers(m.block_start, block_for(m, [600, 0, 0, 0], 2))
            assert c.read_holding_registers(m.accepted, 1) == [2]
        finally:
            c.close()


def test_the_joints_never_leave_their_limits():
    """Random blocks, most of them outside the limits, at a drive moving at full speed: the
    positions it reports stay within the limits, whatever it was sent."""
    m = locked_map()
    rng = np.random.default_rng(3)
    lower, upper = np.rad2deg(m.robot.lower), np.rad2deg(m.robot.upper)
    with SimDrive(m) as sim:
        c = client(sim.port)
        try:
            c.write_single_register(m.enable, 1)
            for i in range(60):
                raw = rng.integers(0, 65536, m.block_count).tolist()
                raw[m.waypoint - m.block_start] = i + 1
                c.write_multiple_registers(0, raw)
                actual = c.read_holding_registers(16, 12)
                q = np.array([m.joints[0].value(actual[2 * j:2 * j + 2]) for j in range(6)])
                assert np.all(q >= lower - 1e-3) and np.all(q <= upper + 1e-3)
        finally:
            c.close()
        assert len(sim.refused) + len(sim.taken) == 60 and len(sim.refused) > 30


def test_random_requests_pipelined_each_get_one_well_formed_answer():
    """300 random requests (seeded) in one burst on one connection: each answered once, in
    order, with its function code or an exception of the standard codes; afterwards the joints
    are within their limits and the drive answers as before."""
    m = locked_map()
    rng = np.random.default_rng(5)
    requests = []
    for t in range(300):
        function = int(rng.choice([3, 6, 16, 16, int(rng.integers(1, 128))]))
        if function == 3:
            pdu = read(int(rng.integers(0, 40)), int(rng.integers(0, 130)))
        elif function == 6:
            pdu = struct.pack(">BHH", 6, int(rng.integers(0, 40)), int(rng.integers(0, 65536)))
        elif function == 16:
            count = int(rng.choice([13, int(rng.integers(1, 20))]))
            address = 0 if count == 13 else int(rng.integers(0, 40))
            pdu = write(address, rng.integers(0, 65536, count))
        else:
            pdu = bytes([function]) + rng.bytes(int(rng.integers(0, 10)))
        requests.append((t, int(rng.choice([1, 1, 1, 0, 255, 7])), pdu))
    lower, upper = np.rad2deg(m.robot.lower), np.rad2deg(m.robot.upper)
    with SimDrive(m) as sim:
        with socket.create_connection(("127.0.0.1", sim.port), timeout=TIMEOUT) as sock:
            sock.sendall(struct.pack(">HHHB", 9999, 0, 6, 1) + struct.pack(">BHH", 6, 28, 1))
            assert receive(sock)[0] == 9999                          # enabled: it moves
            sock.sendall(b"".join(frame(t, u, pdu) for t, u, pdu in requests))
            answers = [receive(sock) for _ in requests]
        for (t, unit, pdu), answer in zip(requests, answers):
            assert answer is not None and answer[:2] == (t, unit)
            reply = answer[2]
            if reply[0] & 0x80:
                assert reply[0] == pdu[0] | 0x80 and len(reply) == 2
                assert reply[1] in (1, 2, 3, 6, 11)
            else:
                assert reply[0] == pdu[0] in (3, 6, 16)
        assert np.all(np.rad2deg(sim.position) >= lower - 1e-9)
        assert np.all(np.rad2deg(sim.position) <= upper + 1e-9)
        assert np.isfinite(sim.goal).all()
        assert ask(sim.port, read(m.accepted, 1))[:2] == bytes([3, 2])
