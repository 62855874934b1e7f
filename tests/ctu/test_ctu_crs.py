"""CTU Prague's own client, ctu-crs (from the package registry), drives the simulated MARS 8.

ctu-crs and ctu-mars-control-unit drove CTU's two A465-type arms on real MARS 8 units for
years; `trol sim --mars` must satisfy them byte for byte (docs/mars.md). Each test starts
`trol sim --mars` on a pty (a variant for each point the public sources leave open that the
client does not settle), and runs the client's own code against it: initialize with hard
and soft home, move_to_q, wait_for_motion_stop, get_q, in_motion and the gripper.

Only the camera import is stubbed (tests/ctu/stub/pypylon): there is no camera here. And the
client's serial port keeps the line's time (`LineTimedSerial`): the client's code is unchanged.
One test makes the line late on purpose (`LateLine`), as a loaded machine can.
"""

import os
import queue
import random
import select
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "stub"))

import ctu_mars_control_unit.mars_control_unit as mars_control_unit  # noqa: E402
import serial  # noqa: E402
from ctu_crs import CRS93  # noqa: E402


class LineTimedSerial(serial.Serial):
    """The client's serial port, with a query's answer started inside the client's read window.

    The client reads for 10 ms at a time and its gripper wait parses one read as one answer
    (`AP<axis>?`; ctu_crs/gripper.py): a read that got nothing makes it ask again, and the
    next read holds both answers, which it cannot parse ("could not convert string to float:
    '103\\nAPG=103'"). The client was written for the real line, where the question
    takes 2.6 ms at 19200 baud and the answer follows inside the window. Here the answer
    passes three scheduled tasks (the simulated unit, the kernel's pty worker, this process),
    and a loaded 2-core machine has held them past 10 ms (CI of 375cc23, the homing-silent
    variant). So after a query, a read first waits, up to 2 s, for the answer's first byte;
    then the client's own read window runs as written. Nothing is added to, dropped from or
    reordered in the bytes.
    """

    QUERY_WAIT_S = 2.0

    def __init__(self, *args, **kwargs):
        self._asked = False
        super().__init__(*args, **kwargs)

    def write(self, data):
        data = bytes(data)
        if b"?" in data:
            self._asked = True
        return self._send(data)

    def _send(self, data):
        return super().write(data)

    def read(self, size=1):
        if self._asked:
            self._asked = False
            select.select([self.fd], [], [], self.QUERY_WAIT_S)
        return super().read(size)


class LateLine(LineTimedSerial):
    """A loaded machine made to order: each write reaches the unit up to 30 ms late, in the
    order written (a seeded random delay per write; one thread sends them)."""

    MAX_DELAY_S = 0.03

    def __init__(self, *args, **kwargs):
        self._pending = queue.Queue()
        self._due = 0.0
        self._random = random.Random(465)
        self._pump = None
        super().__init__(*args, **kwargs)
        self._pump = threading.Thread(target=self._send_late, daemon=True)
        self._pump.start()

    def _send_late(self):
        while (item := self._pending.get()) is not None:
            due, data = item
            time.sleep(max(0.0, due - time.monotonic()))
            serial.Serial.write(self, data)

    def _send(self, data):
        self._due = max(self._due, time.monotonic() + self._random.uniform(0, self.MAX_DELAY_S))
        self._pending.put((self._due, data))
        return len(data)

    def close(self):
        if self._pump is not None:
            self._pending.put(None)
            self._pump.join()
            self._pump = None
        super().close()


@pytest.fixture(autouse=True)
def line_timed_serial(monkeypatch):
    monkeypatch.setattr(mars_control_unit, "Serial", LineTimedSerial)


TROL = os.environ.get("TROL_BIN", "target/debug/trol")
VARIANTS = ["default", "echo", "noise", "moving-lag", "refusal-line",
            "refusal-error-bit", "stop-latches", "lf-only", "r-blocks", "gripper-moving",
            "stop-ignored", "homing-silent", "unstoppable"]


@pytest.fixture
def unit(request):
    proc = subprocess.Popen(
        [TROL, "sim", "--mars", "--time-scale", "20", "--variant", request.param],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    first = proc.stdout.readline()
    assert first.startswith("trol sim: serving on "), first
    # Keep reading its log: a full pipe would stop the simulated unit mid-answer, and CTU's
    # client, which asks again every 10 ms when no answer came, then parses the answers that
    # arrive together as one (its gripper wait failed so on a loaded machine).
    threading.Thread(target=proc.stdout.read, daemon=True).start()
    yield first.split()[-1]
    proc.kill()
    proc.wait()


@pytest.mark.timeout(120)
@pytest.mark.parametrize("unit", VARIANTS, indirect=True)
def test_ctu_crs_drives_the_simulated_mars8(unit, capsys):
    drive(unit, capsys)


@pytest.mark.timeout(120)
@pytest.mark.parametrize("unit", ["default"], indirect=True)
def test_ctu_crs_drives_it_through_a_line_up_to_30_ms_late(unit, capsys, monkeypatch):
    """The test above, on a line made as slow as a loaded machine can make the pty. Without
    LineTimedSerial's wait the client's gripper wait fails so (tried: 13 of 13 variants)."""
    monkeypatch.setattr(mars_control_unit, "Serial", LateLine)
    drive(unit, capsys)


def drive(unit, capsys):
    """CTU's client through its own steps: homes, moves, 25 moves queued, the gripper."""
    robot = CRS93(tty_dev=unit)
    assert "Firmware version : TROL simulated MARS 8" in capsys.readouterr().out
    robot.initialize(home=True)
    # After the hard home the soft home: CTU's q_home.
    assert np.allclose(robot.get_q(), robot.q_home, atol=np.deg2rad(0.05))
    assert not robot.in_motion()

    q = np.deg2rad([10, 20, -30, 5, -40, 15])
    assert robot.in_limits(q)
    robot.move_to_q(q)
    robot.wait_for_motion_stop()
    assert np.allclose(robot.get_q(), q, atol=np.deg2rad(0.05)), np.rad2deg(robot.get_q())

    # 25 moves in a row: the client checks the queue-full bit every 20 (throttle_coordmv).
    last = None
    for k in range(25):
        last = np.deg2rad([k, -k / 2, -20 + k, 0, -30, k * 2])
        robot.move_to_q(last)
    robot.wait_for_motion_stop()
    assert np.allclose(robot.get_q(), last, atol=np.deg2rad(0.05))

    # The gripper: closing waits for the fingers (R<axis>: then AP<axis>? polls).
    robot.gripper.control_position_relative(1.0)
    assert robot._mars.query("APG") == str(robot.gripper.bounds[1])
    robot.gripper.control_position_relative(0.0)
    robot.gripper.wait_for_motion_stop()
    assert robot._mars.query("APG") == str(robot.gripper.bounds[0])
    robot.close()
