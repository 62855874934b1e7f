"""A Halt from the browser's pendant is seen by a Python program (issue 37, item 4): `trol sim`
with its view and pendant as its own process, a long joint motion of the program's halted
through the pendant's HTTP request; the program's finish() raises RefusedError with
TROL_ERR_HALTED, once."""

from __future__ import annotations

import http.client
import subprocess
import threading
import time

import pytest

import trol

from conftest import trol_binary

TROL_ERR_HALTED = -32056


def test_a_pendant_halt_ends_the_programs_finish() -> None:
    proc = subprocess.Popen(
        [
            str(trol_binary()),
            "sim",
            "--port",
            "listen://127.0.0.1:0",
            "--server",
            "--homed",
            "--view",
            "127.0.0.1:0",
            "--control",
        ],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert proc.stdout is not None
        port = view = token = None
        deadline = time.monotonic() + 20
        while not (port and view and token):
            assert time.monotonic() < deadline, "trol sim did not say where it serves"
            line = proc.stdout.readline()
            assert line, "trol sim ended"
            if "serving on " in line:
                port = line.split("serving on ", 1)[1].split()[0]
            if "the view: " in line:
                view = line.split("the view: ", 1)[1].strip().removeprefix("http://").rstrip("/")
            if "#token=" in line:
                token = line.split("#token=", 1)[1].strip()
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        host, _, http_port = view.partition(":")

        with trol.Robot.open(port, baud=38400) as robot:
            robot.speed(10)
            robot.joint(1, 2.0)  # over 6 s at 10 %

            def halt() -> None:
                time.sleep(0.5)
                c = http.client.HTTPConnection(host, int(http_port), timeout=10)
                c.request("POST", f"/control/halt?token={token}")
                assert c.getresponse().status == 200
                c.close()

            halter = threading.Thread(target=halt)
            halter.start()
            with pytest.raises(trol.RefusedError) as e:
                robot.finish()
            halter.join()
            assert e.value.code == TROL_ERR_HALTED
            assert e.value.name == "TROL_ERR_HALTED"
            # Once: the arm stands short of the target, and the next finish succeeds.
            robot.finish()
            j1 = robot.joints()[0]
            assert 0.0 < j1 < 1.9, j1
    finally:
        proc.kill()
        proc.wait()
