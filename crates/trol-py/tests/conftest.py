"""Fixtures: robots against the embedded simulator and against `trol sim` over a pty, and a
scripted controller on TCP for the failures a simulator does not make."""

from __future__ import annotations

import binascii
import os
import socket
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

import trol

ROOT = Path(__file__).resolve().parents[3]
LOCATIONS = ROOT / "examples" / "locations.txt"


def trol_binary() -> Path:
    """The `trol` binary: $TROL_BIN, else target/debug/trol (built if missing)."""
    given = os.environ.get("TROL_BIN")
    if given:
        return Path(given)
    path = ROOT / "target" / "debug" / "trol"
    if not path.exists():
        subprocess.run(["cargo", "build", "-p", "trol-cli"], cwd=ROOT, check=True)
    return path


@pytest.fixture
def sim_robot(tmp_path: Path) -> Iterator[trol.Robot]:
    """The embedded simulator, with the example locations, 50 times real time."""
    cfg = tmp_path / "trol.cfg"
    cfg.write_text(f"9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nlocations = {LOCATIONS}\n")
    with trol.Robot.from_config(cfg) as robot:
        yield robot


@pytest.fixture
def pty_robot() -> Iterator[trol.Robot]:
    """`trol sim` as its own process, serving on a pty, 50 times real time."""
    proc = subprocess.Popen(
        [str(trol_binary()), "sim", "--server", "--time-scale", "50", "--locations", str(LOCATIONS)],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "serving on " in line, line
        port = line.split("serving on ", 1)[1].split()[0]
        # Keep reading its log so that it never blocks on a full pipe.
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        with trol.Robot.open(port, baud=38400) as robot:
            yield robot
    finally:
        proc.kill()
        proc.wait()


@pytest.fixture(params=["embedded", "pty"])
def robot(request: pytest.FixtureRequest) -> trol.Robot:
    """Each test that takes `robot` runs against both controllers."""
    name = "sim_robot" if request.param == "embedded" else "pty_robot"
    return request.getfixturevalue(name)


# The link, just enough of it to answer one request with bytes of our choosing
# (docs/protocol.md, "Layer 2").
SOH, STX, ETX, EOT, ENQ, ACK = 0x1E, 0x2D, 0x4B, 0x87, 0x99, 0xB4


def _read(conn: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("the host went away")
        data += chunk
    return data


def _bcc(block: bytes) -> bytes:
    """The block check TROL uses by default: CRC-16/CCITT (poly 0x1021, init 0xFFFF)."""
    return binascii.crc_hqx(block, 0xFFFF).to_bytes(2, "little")


def _crc7(data: bytes) -> int:
    """CRC-7/MMC (poly 0x09, init 0): CRC-16 mode's check of a whole message."""
    crc = 0
    for byte in data:
        for i in range(7, -1, -1):
            top = (crc >> 6) & 1
            crc = (crc << 1) & 0x7F
            if top ^ ((byte >> i) & 1):
                crc ^= 0x09
    return crc


def _crc_arc(data: bytes) -> int:
    """CRC-16/ARC (poly 0x8005 reflected, init 0): CRC-16 mode's second check of a frame."""
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def _line_pci(message: bytes, pci: int) -> int:
    """The PCI on the line in CRC-16 mode: layer 3's bits 0..8, the message check in 9..15."""
    own = pci & 0x1FF
    check = _crc7(len(message).to_bytes(2, "little") + own.to_bytes(2, "little") + message)
    return own | (check << 9)


def _receive(conn: socket.socket) -> tuple[int, bytes]:
    """ReceiveData of a message of at most 2 bytes (header only)."""
    while _read(conn, 1)[0] != ENQ:
        pass
    conn.sendall(bytes([ACK]))
    header = _read(conn, 10)
    conn.sendall(bytes([ACK]))
    n = int.from_bytes(header[1:3], "little")
    pci = int.from_bytes(header[3:5], "little")
    assert n <= 2, "the scripted controller takes only short requests"
    assert _line_pci(header[5 : 5 + n], pci) == pci, "the message check"
    assert _read(conn, 1)[0] == EOT
    return pci & 0x1FF, header[5 : 5 + n]


def _send(conn: socket.socket, message: bytes, pci: int) -> None:
    """SendData of a message of up to 2 + 256 bytes (one frame)."""
    conn.sendall(bytes([ENQ]))
    assert _read(conn, 1)[0] == ACK
    first = (message[:2] + b"\0\0")[:2]
    line_pci = _line_pci(message, pci)
    fields = len(message).to_bytes(2, "little") + line_pci.to_bytes(2, "little") + first
    conn.sendall(bytes([SOH]) + fields + _bcc(fields) + bytes([ETX]))
    assert _read(conn, 1)[0] == ACK
    if len(message) > 2:
        # Frame 0's ID field: the index XOR CRC-16/ARC of the data.
        data = message[2:] + (0 ^ _crc_arc(message[2:])).to_bytes(2, "little")
        conn.sendall(bytes([STX]) + data + _bcc(data) + bytes([ETX]))
        assert _read(conn, 1)[0] == ACK
    conn.sendall(bytes([EOT]))


@pytest.fixture
def scripted() -> Iterator[tuple[str, list[bytes]]]:
    """A controller on TCP that answers each request with the next of the replies the test
    puts in the list (an empty list: it never answers). Yields (port name, replies)."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    replies: list[bytes] = []

    def serve() -> None:
        try:
            conn, _ = listener.accept()
        except OSError:
            return
        with conn:
            try:
                while True:
                    if not replies:
                        conn.recv(1024)
                        continue
                    pci, _ = _receive(conn)
                    _send(conn, replies.pop(0), pci & 0xFF)
            except (ConnectionError, OSError, AssertionError):
                return

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"socket://127.0.0.1:{listener.getsockname()[1]}", replies
    listener.close()
