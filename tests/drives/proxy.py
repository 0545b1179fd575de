"""A Modbus TCP proxy on loopback that changes or drops frames between a client and a drive.

Test-only. Each connection accepted on `port` is relayed to the drive's port; every request
frame passes `on_request(frame)` and every response `on_response(request, response)`, which
return the frame to forward (changed or not) or None to drop it. Frames are split by their
MBAP length, so pipelined and split segments are handled. Everything is bounded: the relay
thread polls every 20 ms and is joined with a time-out.
"""

from __future__ import annotations

import select
import socket
import struct
import threading
from collections import deque
from collections.abc import Callable

Hook = Callable[..., bytes | None]


def frames(buffer: bytearray) -> list[bytes]:
    """Whole Modbus TCP frames taken off the front of `buffer`."""
    out = []
    while len(buffer) >= 7:
        end = 6 + int.from_bytes(buffer[4:6], "big")
        if len(buffer) < end:
            break
        out.append(bytes(buffer[:end]))
        del buffer[:end]
    return out


def registers(frame: bytes) -> tuple[int, int, int, int] | None:
    """(function, address, count, offset of the first value) of a read request or response,
    or a write request; None for anything else (an exception, a write response)."""
    function = frame[7]
    if function == 16 and len(frame) > 13:
        address, count = struct.unpack_from(">HH", frame, 8)
        return function, address, count, 13
    if function == 3 and len(frame) == 12:                   # a read request
        address, count = struct.unpack_from(">HH", frame, 8)
        return function, address, count, -1
    return None


def set_register(frame: bytes, offset: int, index: int, value: int) -> bytes:
    """`frame` with register `index` (counted from the one at byte `offset`) set to `value`."""
    out = bytearray(frame)
    struct.pack_into(">H", out, offset + 2 * index, value & 0xFFFF)
    return bytes(out)


def get_register(frame: bytes, offset: int, index: int) -> int:
    return struct.unpack_from(">H", frame, offset + 2 * index)[0]


class FaultProxy:
    """Relay Modbus TCP from `port` (chosen free) to the drive at 127.0.0.1:`drive_port`."""

    def __init__(self, drive_port: int, on_request: Hook | None = None,
                 on_response: Hook | None = None):
        self.drive_port = drive_port
        self.on_request = on_request or (lambda frame: frame)
        self.on_response = on_response or (lambda request, response: response)
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="fault-proxy", daemon=True)
        self.errors: list[BaseException] = []

    def __enter__(self) -> FaultProxy:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5.0)
        self.listener.close()
        if self.errors:
            raise self.errors[0]

    def _run(self) -> None:
        # socket -> (its peer, its buffer, whether it is the client side, pending requests)
        links: dict[socket.socket, tuple] = {}
        try:
            while not self._stop.is_set():
                readable, _, _ = select.select([self.listener, *links], [], [], 0.02)
                for sock in readable:
                    if sock is self.listener:
                        client, _ = self.listener.accept()
                        drive = socket.create_connection(("127.0.0.1", self.drive_port), 2.0)
                        pending: deque[bytes] = deque()
                        links[client] = (drive, bytearray(), True, pending)
                        links[drive] = (client, bytearray(), False, pending)
                        continue
                    peer, buffer, from_client, pending = links[sock]
                    try:
                        data = sock.recv(65536)
                    except OSError:
                        data = b""
                    if not data:                   # one side closed: close the other
                        for s in (sock, peer):
                            links.pop(s, None)
                            s.close()
                        continue
                    buffer += data
                    for frame in frames(buffer):
                        if from_client:
                            pending.append(frame)
                            out = self.on_request(frame)
                        else:
                            request = pending.popleft() if pending else b""
                            out = self.on_response(request, frame)
                        if out is not None:
                            peer.sendall(out)
        except BaseException as err:               # handed to the test on exit
            self.errors.append(err)
        finally:
            for sock in links:
                sock.close()
