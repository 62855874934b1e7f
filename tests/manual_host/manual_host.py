#!/usr/bin/env python3
"""A TROL host written from the 1998 manual alone, byte by byte (no TROL code).

It speaks what the manual's chapter "Kommunikation" describes, with the values
docs/protocol.md fixes where the manual left them to protoc.h: the bare activation line
`PCP TROL`, layer 2 with the LRC (the sum of the block's bytes but the control codes), the
PCI left at 0 ("wird ... nicht benötigt"), requests never numbered and never marked
REPEAT, and the manual's records. It runs a 1998 program's calls, back-to-back motions
without Finish between them included, and says what each returned.

    manual_host.py PORT

PORT is a pty (or serial device) path. Exit 0 when every call returned 0 and the arm ended
where the calls put it (where it stood after Home, plus the relative motions); 1
otherwise, with the call that failed.
"""

import argparse
import os
import select
import struct
import sys
import time
import tty

SOH, STX, ETX, ETB, EOT, ENQ, ACK, NAK = 0x1E, 0x2D, 0x4B, 0x78, 0x87, 0x99, 0xB4, 0xD2
FRAME_SIZE = 256


class LineError(Exception):
    pass


class ManualHost:
    def __init__(self, path, timeout=5.0):
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        self.timeout = timeout

    # Layer 1: SendByte, GetByte, FlushBuffer.
    def send(self, data):
        os.write(self.fd, bytes(data))

    def get(self, n, timeout=None):
        deadline = time.monotonic() + (timeout or self.timeout)
        out = b""
        while len(out) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise LineError(f"timeout: {len(out)} of {n} bytes ({out.hex()})")
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                out += os.read(self.fd, n - len(out))
        return out

    def flush(self, quiet=0.2):
        while select.select([self.fd], [], [], quiet)[0]:
            os.read(self.fd, 4096)

    # Activation (inittrol): Ctrl-C, CR, the bare line; wait for the answer.
    def activate(self):
        self.send(b"\x03\r")
        time.sleep(0.2)
        self.flush()
        self.send(b"PCP TROL\r")
        seen = b""
        deadline = time.monotonic() + 10
        while b"PCP TROL ACTIVE" not in seen:
            if time.monotonic() > deadline:
                raise LineError(f"no PCP TROL ACTIVE: {seen!r}")
            if select.select([self.fd], [], [], 0.5)[0]:
                seen += os.read(self.fd, 256)
        self.flush()

    @staticmethod
    def lrc(block):
        s = sum(block) & 0xFFFF
        return struct.pack("<H", s)

    def expect_ack(self, what):
        b = self.get(1)[0]
        if b != ACK:
            extra = self.get(1).hex() if b == NAK else ""
            raise LineError(f"{what}: {b:#04x} {extra} instead of ACK")

    # Layer 2: SendData.
    def send_data(self, msg, pci=0):
        self.send([ENQ])
        self.expect_ack("ENQ")
        first = (msg[:2] + b"\0\0")[:2]
        fields = struct.pack("<HH", len(msg), pci) + first
        self.send(bytes([SOH]) + fields + self.lrc(fields) + bytes([ETX]))
        self.expect_ack("header")
        rest = msg[2:]
        chunks = [rest[i : i + FRAME_SIZE] for i in range(0, len(rest), FRAME_SIZE)]
        for fid, chunk in enumerate(chunks):
            body = chunk + struct.pack("<H", fid)
            end = ETX if fid == len(chunks) - 1 else ETB
            self.send(bytes([STX]) + body + self.lrc(body) + bytes([end]))
            self.expect_ack(f"frame {fid}")
        self.send([EOT])

    # Layer 2: ReceiveData.
    def receive_data(self, timeout):
        if self.get(1, timeout)[0] != ENQ:
            raise LineError("ENQ expected")
        self.send([ACK])
        h = self.get(10)
        if h[0] != SOH or h[9] != ETX or h[7:9] != self.lrc(h[1:7]):
            raise LineError(f"bad header {h.hex()}")
        n, _pci = struct.unpack("<HH", h[1:5])
        msg = h[5:7][: min(n, 2)]
        self.send([ACK])
        left = n - len(msg)
        fid = 0
        while left > 0:
            k = min(left, FRAME_SIZE)
            f = self.get(k + 6)
            body = f[1 : 1 + k + 2]
            if f[0] != STX or f[-3:-1] != self.lrc(body) or body[-2:] != struct.pack("<H", fid):
                raise LineError(f"bad frame {f.hex()}")
            msg += body[:-2]
            left -= k
            fid += 1
            self.send([ACK])
        if self.get(1)[0] != EOT:
            raise LineError("EOT expected")
        return msg

    # Layer 3: TransSR.
    def trans_sr(self, req, timeout=15.0):
        self.send_data(req)
        return self.receive_data(timeout)

    # Layer 4: the manual's CAT1 records; the reply is one 16-bit integer.
    def cat1(self, req, timeout=15.0):
        r = self.trans_sr(bytes(req), timeout)
        if len(r) != 2:
            raise LineError(f"CAT1 reply of {len(r)} bytes")
        return struct.unpack("<h", r)[0]


def joint_req(n, rad):
    return bytes([9, n]) + struct.pack("<f", rad)


def joints(host):
    """TROLGetPosition(POS_JOINT, POS_ACT): the joint angles (rad)."""
    pos = host.trans_sr(bytes([128, 1, 1]))
    code, tag, dims = struct.unpack("<hBB", pos[:4])
    if code != 0 or tag != 1:
        raise LineError(f"GetPosition answered {code}, tag {tag}")
    return struct.unpack(f"<{dims}f", pos[4 : 4 + 4 * dims])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port")
    ap.add_argument("--tolerance", type=float, default=0.01)
    args = ap.parse_args()
    host = ManualHost(args.port)
    host.activate()
    start = [
        ("TROLHome(0)", bytes([7, 0]), 120.0),
        ("TROLFinish(FINISH_WAIT)", bytes([4, 1]), 120.0),
        ("TROLSpeed(50)", bytes([17, 50]), 15.0),
    ]
    # A 1998 program's back-to-back motions: no Finish between them.
    moves = [(2, 0.3), (3, 0.6), (5, 0.5), (1, -0.2)]
    calls = start + [
        (f"TROLJoint({n}, {rad})", joint_req(n, rad), 15.0) for n, rad in moves
    ] + [("TROLFinish(FINISH_WAIT)", bytes([4, 1]), 120.0)]
    failed = 0
    home = None
    for i, (name, req, timeout) in enumerate(calls):
        rc = host.cat1(req, timeout)
        print(f"{name} -> {rc}", flush=True)
        failed += rc != 0
        if i == len(start) - 1:
            home = joints(host)
            print("TROLGetPosition -> " + ", ".join(f"{v:.4f}" for v in home), flush=True)
    st = host.trans_sr(bytes([193]))
    called, last = struct.unpack("<hh", st[:4])
    print(f"TROLGetStatus -> BIOSCalled {called}, lastErrorCode {last} ({len(st)} bytes)")
    if (called, last) != (1, 0):
        failed += 1
    q = joints(host)
    print("TROLGetPosition -> " + ", ".join(f"{v:.4f}" for v in q), flush=True)
    want = list(home)
    for n, rad in moves:
        want[n - 1] += rad
    off = max(abs(a - b) for a, b in zip(q, want))
    if off > args.tolerance:
        print(f"the arm is {off:.4f} rad from where the calls put it", flush=True)
        failed += 1
    print(f"manual host: {len(calls) + 2 - failed} passed, {failed} failed", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except LineError as e:
        print(f"manual host: line error: {e}", flush=True)
        sys.exit(1)
