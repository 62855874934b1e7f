"""TROL for Python driving an A465 on a MARS 8: `trol sim --mars` over a pty, through
`mars:` in trol.cfg with the arm's profile (docs/mars.md)."""

from __future__ import annotations

import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

import trol

from conftest import trol_binary


@pytest.fixture
def mars_robot(tmp_path: Path) -> Iterator[trol.Robot]:
    """`trol sim --mars` as its own process, 20 times real time, driven through `mars:`."""
    profile = subprocess.run(
        [str(trol_binary()), "sim", "--mars", "--print-profile"],
        check=True, capture_output=True, text=True,
    ).stdout
    (tmp_path / "arm.toml").write_text(profile)
    proc = subprocess.Popen(
        [str(trol_binary()), "sim", "--mars", "--time-scale", "20"],
        stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "serving on " in line, line
        port = line.split("serving on ", 1)[1].split()[0]
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        cfg = tmp_path / "trol.cfg"
        cfg.write_text(f"9600\nmars:{port}\n0 0 0 0 0 0\nmars-profile = arm.toml\n")
        with trol.Robot.from_config(cfg) as robot:
            yield robot
    finally:
        proc.kill()
        proc.wait()


@pytest.mark.timeout(120)
def test_a_python_script_drives_the_arm_on_a_mars8(mars_robot: trol.Robot) -> None:
    assert mars_robot.version()[1] == "MARS 8"
    # Nothing moves before Home: the unit's counters mean nothing until then.
    with pytest.raises(trol.RefusedError) as e:
        mars_robot.ma([0.2, 0.1, 0.8, 0.0, 0.6, 0.0])
    assert (e.value.code, e.value.name) == (-1, "BIOS_NOT_HOMED")
    mars_robot.home()
    mars_robot.ma([0.2, 0.1, 0.8, 0.0, 0.6, 0.0])
    mars_robot.finish()
    assert list(mars_robot.joints(actual=True)) == pytest.approx([0.2, 0.1, 0.8, 0.0, 0.6, 0.0], abs=1e-3)
    # Outside CRS93's range (joint 2 ends at 89.69 degrees): refused, with the backend's name.
    with pytest.raises(trol.RefusedError) as e:
        mars_robot.ma([0.0, 1.5690, 0.5, 0.0, 0.5, 0.0])
    assert (e.value.code, e.value.name) == (-3, "BIOS_JOINT_LIMIT")
    mars_robot.close_gripper(50)
    mars_robot.finish()
    # A trajectory keeps its times on a MARS 8 (coordinated segments) and ends at its last
    # waypoint, as seen on the unit's encoders.
    # The unit's own speeds (CRS93's REGMS) are a few times below the A465's published ones:
    # seconds per tenth of a radian; faster is BIOS_TOO_FAST, refused before anything moves.
    end = [0.25, 0.15, 0.7, 0.1, 0.5, 0.0]
    with pytest.raises(trol.RefusedError) as e:
        mars_robot.trajectory([(0.1, end)])
    assert (e.value.code, e.value.name) == (-30, "BIOS_TOO_FAST")
    assert mars_robot.trajectory([(8.0, [0.2, 0.2, 0.7, 0.0, 0.6, 0.0]), (16.0, end)]) == "timed"
    mars_robot.finish()
    assert list(mars_robot.joints(actual=True)) == pytest.approx(end, abs=1e-3)


@pytest.mark.timeout(120)
def test_a_python_script_drives_the_mars8_through_trol_gateway(tmp_path: Path) -> None:
    profile = subprocess.run(
        [str(trol_binary()), "sim", "--mars", "--print-profile"],
        check=True, capture_output=True, text=True,
    ).stdout
    (tmp_path / "arm.toml").write_text(profile)
    procs = []
    try:
        def start(args: list[str]) -> str:
            proc = subprocess.Popen([str(trol_binary()), *args], stdout=subprocess.PIPE,
                                    stdin=subprocess.DEVNULL, text=True)
            procs.append(proc)
            assert proc.stdout is not None
            line = proc.stdout.readline()
            assert "serving on " in line, line
            threading.Thread(target=proc.stdout.read, daemon=True).start()
            return line.split("serving on ", 1)[1].split()[0]

        unit = start(["sim", "--mars", "--time-scale", "20"])
        gateway = start(["gateway", "--controller", f"mars:{unit}", "--profile",
                         str(tmp_path / "arm.toml"), "--server"])
        with trol.Robot.open(gateway) as robot:
            assert robot.version()[1] == "MARS 8"
            # The unit's codes came with the version check (TROLGetCodes), not from a table
            # this end picked by the kind's words.
            assert robot.codes()[-21][0] == "BIOS_MOTION_STOP"
            assert robot.describe(-21).startswith("-21 (BIOS_MOTION_STOP): ")
            assert trol.describe(-21) == "-21 (BIOS code)"
            robot.home()
            robot.ma([0.2, 0.1, 0.8, 0.0, 0.6, 0.0])
            robot.finish()
            assert list(robot.joints(actual=True)) == pytest.approx(
                [0.2, 0.1, 0.8, 0.0, 0.6, 0.0], abs=1e-3)
    finally:
        for p in procs:
            p.kill()
            p.wait()
