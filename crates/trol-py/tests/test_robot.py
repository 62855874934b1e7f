"""TROL for Python against the embedded simulator and `trol sim` over a pty: every method,
every exception class with its code, threads, Ctrl-C, numpy and list inputs."""

from __future__ import annotations

import array
import math
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import trol

from conftest import trol_binary

ROOT = Path(__file__).resolve().parents[3]
HALF_PI = math.pi / 2


def test_every_method(robot: trol.Robot) -> None:
    with pytest.raises(trol.RefusedError):
        robot.ready()  # not homed yet
    robot.home()
    assert not robot.is_moving()  # Home returns when homing is done
    robot.speed(100)
    robot.ready()
    robot.finish()
    # A named location of the controller's table, and the approach to it.
    robot.appro("test_001", [-150.0])
    robot.appro("test_001", [-90.0], straight=True)
    robot.move("test_001", straight=True)
    robot.finish()
    pose = robot.pose()
    assert isinstance(pose, trol.Pose)
    assert (pose.x, pose.y, pose.z) == pytest.approx((400.0, 0.0, 150.0), abs=1e-2)
    robot.depart([-90.0], straight=True)
    robot.finish()
    assert robot.pose().z == pytest.approx(240.0, abs=1e-2)
    # Given locations: a Pose (any sequence of up to 6 values) or a Precision.
    robot.move(trol.Pose(420.0, 50.0, 250.0, 0.0, HALF_PI, 0.0))
    robot.appro([420.0, 50.0, 250.0, 0.0, HALF_PI, 0.0], [-30.0])
    robot.finish()
    robot.jog([0.0, 0.0, 10.0], straight=True)
    robot.joint(1, 0.1)
    robot.mi([0.0, 0.05])
    robot.finish()
    robot.ma([0.1, 0.5, 1.0, 0.0, 0.5, 0.0])
    robot.finish()
    joints = robot.joints()
    assert isinstance(joints, trol.Joints)
    assert list(joints) == pytest.approx([0.1, 0.5, 1.0, 0.0, 0.5, 0.0], abs=1e-6)
    actual = robot.joints(actual=True)
    assert actual.j2 == pytest.approx(0.5, abs=1e-3)
    counts = robot.precision()
    assert isinstance(counts, trol.Precision) and all(isinstance(c, int) for c in counts)
    robot.move(trol.Precision(*counts))
    robot.finish()
    assert robot.precision() == counts
    robot.grip(20)
    robot.open_gripper(60)
    robot.close_gripper(40)
    robot.finish()
    robot.set_tool([0.0, 0.0, 100.0])
    robot.set_tool([0.0] * 6)
    robot.halt()
    assert robot.status() == (True, 0)
    # TransSR: GetStatus's bytes (called, last, transaction, epoch).
    raw = robot.transact(bytes([193]))
    assert len(raw) == 8 and raw[:4] == bytes([1, 0, 0, 0])
    assert robot.call("getstatus") == (True, 0)
    assert robot.call("TROLSpeed", 50) == 0


def test_poses_and_joints_are_immutable_sequences_numpy_reads(sim_robot: trol.Robot) -> None:
    sim_robot.home()
    pose = sim_robot.pose()
    assert len(pose) == 6 and pose[2] == pose.z
    assert np.asarray(pose).shape == (6,)
    with pytest.raises(AttributeError):
        pose.x = 1.0  # type: ignore[misc]


def test_poses_and_joints_print_to_the_arms_precision() -> None:
    """Issue 44: a pose reads as a person reads it (0.001 mm, 1e-6 rad, no exponent, no
    -0); its fields keep the full value."""
    pose = trol.Pose(400.0, 3.040798136292461e-14, 240.0, 1.6407142272685713e-24, 1.570796251296997, -0.0)
    assert repr(pose) == "Pose(x=400, y=0, z=240, yaw=0, pitch=1.570796, roll=0)"
    assert str(pose) == repr(pose)
    assert pose.y == 3.040798136292461e-14
    joints = trol.Joints(-1e-12, 0.5, -0.25, 0.0, 1.2345678, -3.0)
    assert repr(joints) == "Joints(j1=0, j2=0.5, j3=-0.25, j4=0, j5=1.234568, j6=-3)"


@pytest.mark.parametrize(
    "joints",
    [
        [0.2, 0.4, 0.8],
        (0.2, 0.4, 0.8),
        np.array([0.2, 0.4, 0.8]),
        np.array([0.2, 0.4, 0.8], dtype=np.float32),
        [np.float64(0.2), np.float32(0.4), 0.8],
    ],
)
def test_lists_tuples_and_numpy_arrays_are_accepted(sim_robot: trol.Robot, joints: object) -> None:
    sim_robot.home()
    sim_robot.ma(joints)  # type: ignore[arg-type]
    sim_robot.finish()
    # Missing values are 0, as numDims allows.
    assert list(sim_robot.joints()) == pytest.approx([0.2, 0.4, 0.8, 0, 0, 0], abs=1e-6)


@pytest.mark.parametrize(
    "joints",
    [
        b"abcdef",  # a sequence of small ints to Python: an MI of 97..102 rad
        bytearray(b"ab"),
        "0.1",
        [True, False, True],
        [0.1, 1j],
        np.array([0.1, 0.2], dtype=np.complex128),
        np.array([0.1, 0.2], dtype=object),
        np.array([True, False]),
        [0.1, "0.2"],
        [0.1, None],
        memoryview(b"abcdef"),
        memoryview(bytearray(b"abcdef")),
        array.array("b", [1, 2, 3]),
    ],
)
def test_values_that_are_not_real_numbers_are_refused_and_nothing_moves(
    sim_robot: trol.Robot, joints: object
) -> None:
    sim_robot.home()
    sim_robot.finish()
    before = list(sim_robot.joints())
    for call in (sim_robot.mi, sim_robot.ma):
        with pytest.raises(trol.ArgumentError):
            call(joints)  # type: ignore[arg-type]
    sim_robot.finish()
    assert list(sim_robot.joints()) == pytest.approx(before, abs=1e-9)


@pytest.mark.parametrize(
    "joints",
    [
        {2: 0.1},  # a dict gives its keys: joint 1 turned by 2 rad
        {0.1, 0.2},
        frozenset([0.1]),
        (x for x in [0.1, 0.2]),
        iter([0.1, 0.2]),
        range(3),
        {0.1: 0.2}.values(),
    ],
)
def test_what_is_no_ordered_sequence_is_a_type_error_and_nothing_moves(
    sim_robot: trol.Robot, joints: object
) -> None:
    sim_robot.home()
    sim_robot.finish()
    before = list(sim_robot.joints())
    for call in (sim_robot.mi, sim_robot.ma):
        with pytest.raises(TypeError) as e:
            call(joints)  # type: ignore[arg-type]
        assert isinstance(e.value, trol.ArgumentError)
        assert "ordered sequence" in str(e.value)
    with pytest.raises(trol.ArgumentTypeError):
        sim_robot.move({400: 0.0})  # type: ignore[arg-type]
    sim_robot.finish()
    assert list(sim_robot.joints()) == pytest.approx(before, abs=1e-9)


def test_refused_calls_raise_refused_error_with_the_code_and_its_name(robot: trol.Robot) -> None:
    with pytest.raises(trol.RefusedError) as e:
        robot.joint(1, 0.1)
    assert (e.value.code, e.value.name, e.value.command) == (-1, "BIOS_NOT_HOMED", "TROLJoint")
    assert isinstance(e.value, trol.TrolError)
    robot.home()
    with pytest.raises(trol.RefusedError) as e:
        robot.move("nowhere")
    assert (e.value.code, e.value.name) == (-32102, "TROL_ERR_LOCATION")
    with pytest.raises(trol.RefusedError) as e:
        robot.ma([0, 0, 0, 0, 0, 9.0])
    assert (e.value.code, e.value.name) == (-3, "BIOS_JOINT_LIMIT")
    assert robot.status() == (True, -3)


@pytest.mark.parametrize(
    "call",
    [
        lambda r: r.close_gripper(0),
        lambda r: r.open_gripper(101),
        lambda r: r.speed(151),
        lambda r: r.home(7),
        lambda r: r.joint(7, 0.1),
        lambda r: r.joint(True, 0.1),
        lambda r: r.joint(1, True),
        lambda r: r.speed(True),
        lambda r: r.call("TROLJoint", True, 0.1),
        lambda r: r.ma([0.0] * 7),
        lambda r: r.ma([]),
        lambda r: r.ma("abc"),
        lambda r: r.ma([float("nan")]),
        lambda r: r.jog([1.0, 2.0, 3.0, 4.0]),
        lambda r: r.move("not a name"),
        lambda r: r.move("ab\0cd"),
        lambda r: r.call("TROLSpeed", 0),
        lambda r: r.call("fly"),
    ],
)
def test_bad_arguments_raise_argument_error_and_send_nothing(sim_robot: trol.Robot, call: object) -> None:
    sim_robot.home()
    before = sim_robot.status()
    with pytest.raises(trol.ArgumentError) as e:
        call(sim_robot)  # type: ignore[operator]
    assert e.value.code == -32003
    assert isinstance(e.value, ValueError)
    # Nothing reached the controller: its status is still that of Home.
    assert sim_robot.status() == before


def test_a_silent_controller_raises_link_error(scripted: tuple[str, list[bytes]]) -> None:
    port, _ = scripted
    robot = trol.Robot.open(port, check=False)
    with pytest.raises(trol.LinkError) as e:
        robot.halt()
    assert e.value.code == -32001
    assert e.value.last_comm == 0x0003  # ERR_TIMEOUT_ENQ


def test_a_reply_of_the_wrong_size_raises_bad_reply_error(scripted: tuple[str, list[bytes]]) -> None:
    port, replies = scripted
    replies.append(bytes([1, 0, 0, 0, 0]))  # GetStatus answered with 5 bytes, not 8
    robot = trol.Robot.open(port, check=False)
    with pytest.raises(trol.BadReplyError) as e:
        robot.status()
    assert e.value.code == -32002


def test_open_checks_the_servers_protocol_version(scripted: tuple[str, list[bytes]]) -> None:
    """As InitTROL(1): a controller that speaks another protocol version is refused at open,
    with both versions and what to do."""
    port, replies = scripted
    status = bytes([1, 0, 0, 0, 0, 0, 7, 0])  # called, last 0, transaction 0, epoch 7
    version = bytes([0, 0, 2, 0]) + b"an older TROL"  # protocol 2
    replies.extend([status, version])
    with pytest.raises(trol.IncompatibleError) as e:
        trol.Robot.open(port)
    assert isinstance(e.value, trol.SetupError)
    assert (e.value.ours, e.value.theirs) == (4, 2)  # docs/protocol.md, "Version and kind"
    text = str(e.value)
    assert "version 2" in text and "same TROL release" in text, text


def test_open_refuses_a_silent_server_unless_told_not_to_check(scripted: tuple[str, list[bytes]]) -> None:
    port, _ = scripted
    with pytest.raises(trol.SetupError) as e:
        trol.Robot.open(port)
    assert "does not answer" in str(e.value) and "trol init" in str(e.value), str(e.value)


def test_setup_errors(tmp_path: Path, sim_robot: trol.Robot) -> None:
    with pytest.raises(trol.SetupError):
        trol.Robot.open("/dev/no-such-port")
    with pytest.raises(trol.SetupError):
        trol.Robot.from_config(tmp_path / "missing.cfg")
    (tmp_path / "bad.cfg").write_text("9600\nsim\n1 2 3\n")
    with pytest.raises(trol.SetupError) as e:
        trol.Robot.from_config(tmp_path / "bad.cfg")
    assert "bad.cfg:3" in str(e.value)
    with pytest.raises(trol.ArgumentError):
        trol.Robot.open("sim", time_scale=0)
    sim_robot.close()
    with pytest.raises(trol.SetupError):
        sim_robot.home()


def test_finish_times_out_while_the_arm_keeps_moving() -> None:
    with trol.Robot.open("sim", time_scale=5) as robot:
        robot.home()
        robot.speed(5)
        robot.joint(1, 1.0)
        with pytest.raises(trol.TimeoutError) as e:
            robot.finish(timeout=0.05)
        assert isinstance(e.value, TimeoutError)
        assert robot.is_moving()
        robot.halt()  # the arm brakes within its limits, then stands
        robot.finish(timeout=5)
        assert not robot.is_moving()


def test_a_timeout_too_large_for_the_clock_is_no_limit_and_no_panic() -> None:
    with trol.Robot.open("sim", time_scale=20) as robot:
        robot.home()
        robot.joint(6, 0.1)
        robot.finish(timeout=1e300)
        assert not robot.is_moving()
        with pytest.raises(trol.ArgumentError):
            robot.finish(timeout=float("inf"))


def test_other_threads_run_while_one_waits_in_finish() -> None:
    with trol.Robot.open("sim", time_scale=5) as robot:
        robot.home()
        robot.speed(20)
        robot.joint(1, 1.0)
        ticks = 0
        stop = threading.Event()

        def count() -> None:
            nonlocal ticks
            while not stop.is_set():
                ticks += 1
                time.sleep(0.001)

        t = threading.Thread(target=count)
        t.start()
        robot.finish()
        stop.set()
        t.join()
        assert ticks > 10, "the GIL was held while finish() waited"


def test_halt_from_another_thread_stops_a_move_while_one_waits() -> None:
    with trol.Robot.open("sim", time_scale=1) as robot:
        robot.home()
        robot.speed(10)
        robot.joint(1, 2.0)  # several seconds at 10 %
        timer = threading.Timer(0.3, robot.halt)
        started = time.monotonic()
        timer.start()
        robot.finish(timeout=30)
        took = time.monotonic() - started
        timer.join()
        assert not robot.is_moving()
        assert robot.joints().j1 < 1.0, "the move ran to its end"
        assert took < 5.0


def test_ctrl_c_during_finish_halts_the_arm_and_raises_keyboard_interrupt() -> None:
    script = textwrap.dedent(
        """
        import signal, sys, trol
        # Ctrl-C as an interactive Python has it, whatever this process inherited (a shell
        # without job control starts background jobs with SIGINT ignored).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        robot = trol.Robot.open("sim", time_scale=1)
        robot.home()
        robot.speed(5)
        robot.joint(1, 2.0)  # 13 s: a loaded machine that holds this process up a while
        print("waiting", flush=True)
        try:
            robot.finish()
            print("finished")
        except KeyboardInterrupt:
            robot.finish(timeout=5)  # Halt was sent: the arm brakes and stands
            print("interrupted; stopped at j1", round(robot.joints().j1, 3))
            sys.exit(3)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "waiting"
    time.sleep(0.3)
    os.kill(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 3, out
    # Halted well short of the 2 rad the move was going to.
    j1 = float(out.split("stopped at j1", 1)[1])
    assert 0.0 < j1 < 1.5, out


def test_describe_names_a_code() -> None:
    assert trol.describe(-1) == "-1 (BIOS_NOT_HOMED): the arm must be homed first (TROLHome)"
    assert trol.describe(-32102).startswith("-32102 (TROL_ERR_LOCATION)")
    assert trol.describe(0) == "0 (success)"


def test_a_connection_names_codes_as_its_controller_does() -> None:
    with trol.Robot.open("sim") as robot:
        codes = robot.codes()
        assert codes[-1] == ("BIOS_NOT_HOMED", "the arm must be homed first (TROLHome)")
        assert all(value != 0 and value > -32000 for value in codes)
        assert robot.describe(-1) == trol.describe(-1)
        assert robot.call("TROLGetCodes") == codes


def test_a_missed_grasp_can_be_told_from_a_held_object(tmp_path: Path) -> None:
    (tmp_path / "locs.txt").write_text("p2 420 0 400 0 1.5707963 0\n")
    (tmp_path / "objs.txt").write_text("cube 420 0 385 30\n")
    cfg = tmp_path / "trol.cfg"
    cfg.write_text("9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nhomed = yes\n"
                   "locations = locs.txt\nobjects = objs.txt\n")
    with trol.Robot.from_config(cfg) as robot:
        robot.close_gripper()
        robot.finish()
        assert robot.gripper() == trol.Gripper(0.0, None, True)
        robot.open_gripper()
        robot.move("p2")
        robot.finish()
        robot.close_gripper()
        robot.finish()
        g = robot.gripper()
        assert g.holding == "cube" and g.known
        assert g.opening_mm == pytest.approx(30.0, abs=0.5)


def test_added_commands_are_called_by_name() -> None:
    """The guide's commands (docs/extending.md) against the guide's controller program."""
    exe = ROOT / "target" / "debug" / "examples" / "extending_controller"
    if not exe.exists():
        subprocess.run(
            ["cargo", "build", "-p", "trol", "--example", "extending_controller"], cwd=ROOT, check=True
        )
    proc = subprocess.Popen([str(exe)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        port = proc.stdout.readline().split("serving on ", 1)[1].strip()
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        with trol.Robot.open(port) as robot:
            assert robot.add_commands(ROOT / "examples" / "extending.toml") == [
                "TROLJointAbs",
                "TROLForwardKin",
            ]
            pose = robot.call("forwardkin", [0.0, 0.5, 1.0])
            assert pose[0] == pytest.approx(551.51086, abs=1e-3)
            robot.home()
            assert robot.call("TROLJointAbs", 2, 0.25) == 0
            robot.finish()
            assert robot.joints().j2 == pytest.approx(0.25, abs=1e-6)
            with pytest.raises(trol.ArgumentError):
                robot.call("jointabs", 9, 0.0)
            with pytest.raises(TypeError):
                robot.call("jointabs", 2)
    finally:
        proc.kill()
        proc.wait()


def test_repeats_can_be_turned_off(sim_robot: trol.Robot) -> None:
    assert sim_robot.repeats() == 2
    sim_robot.set_repeats(0)
    assert sim_robot.repeats() == 0
    with pytest.raises(trol.ArgumentError):
        sim_robot.set_repeats(11)
    assert sim_robot.repeats() == 0


def test_version_and_watchdog(sim_robot: trol.Robot) -> None:
    protocol, kind = sim_robot.version()
    assert protocol == 4  # docs/protocol.md, "Version and kind"
    assert kind == "simulated A465"
    with pytest.raises(trol.ArgumentError):
        sim_robot.set_watchdog(30.0)
    sim_robot.set_watchdog(2.0)
    sim_robot.speed(50)
    assert not sim_robot.is_moving()
    sim_robot.set_watchdog(0)


def test_the_getstatus_method_knows_which_call_a_status_belongs_to(sim_robot: trol.Robot) -> None:
    with pytest.raises(trol.RefusedError):
        sim_robot.joint(1, 0.1)
    n = sim_robot.last_transaction()
    called, last, transaction, epoch = sim_robot.status_record()
    assert (called, last, transaction) == (True, -1, n)
    assert epoch != 0
    sim_robot.home()
    sim_robot.joint(1, 0.1)
    n = sim_robot.last_transaction()
    sim_robot.status()  # a transaction of its own: the status still belongs to the joint
    assert sim_robot.status_record()[:3] == (True, 0, n)


def test_a_1998_controller_is_driven_and_the_program_is_told_once() -> None:
    """A controller that speaks only the manual's protocol (`trol sim --manual`): after `trol
    init` falls back to the manual's activation, Python drives it with nothing configured,
    and says once (a UserWarning) what that costs: no repeats, the manual's GetStatus."""
    proc = subprocess.Popen(
        [str(trol_binary()), "sim", "--manual", "--time-scale", "50"],
        stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        port = line.split("serving on ", 1)[1].split()[0]
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        init = subprocess.run([str(trol_binary()), "init", "--port", port],
                              capture_output=True, text=True, cwd="/")
        assert init.returncode == 0, init.stderr
        assert "speaks only the manual's protocol" in init.stdout
        with pytest.warns(UserWarning, match="speaks only the manual's protocol"):
            robot = trol.Robot.open(port, baud=9600)
        with robot:
            robot.home(0)
            robot.finish()
            robot.joint(1, 0.25)
            robot.finish()
            assert abs(robot.joints()[0] - 0.25) < 1e-6
            bios_called, last, transaction, epoch = robot.status_record()
            assert (bios_called, last, transaction, epoch) == (True, 0, 0, 0)
    finally:
        proc.kill()
        proc.wait()


def _sim_with_locations(path: Path) -> subprocess.Popen[str]:
    proc = subprocess.Popen(
        [str(trol_binary()), "sim", "--server", "--time-scale", "50", "--homed", "--locations", str(path)],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    return proc


def _port_of(proc: subprocess.Popen[str]) -> str:
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert "serving on " in line, line
    threading.Thread(target=proc.stdout.read, daemon=True).start()
    return line.split("serving on ", 1)[1].split()[0]


def test_teaching_stores_lists_deletes_and_survives_a_restart(tmp_path: Path) -> None:
    """docs/teach.md from Python: here, define, locations() as a mapping, delete, move back
    to a taught location, save; a new `trol sim` on the same file has them."""
    taught = tmp_path / "taught.txt"  # does not exist yet: save creates it
    proc = _sim_with_locations(taught)
    try:
        with trol.Robot.open(_port_of(proc), baud=38400) as robot:
            assert robot.locations() == {}
            robot.move(trol.Pose(420, -50, 330, 0, math.pi / 2, 0))
            robot.finish()
            at = robot.joints()
            robot.here("p1")
            robot.here("pj", "joint")
            robot.here("#pp", "prec")
            robot.define("up", trol.Pose(300, 0, 500, 0, 1.5, 0))
            robot.define("jj", trol.Joints(0, 0.2, 0.4, 0, 0.5, 0))
            table = robot.locations()
            assert list(table) == ["#pp", "jj", "p1", "pj", "up"]
            assert isinstance(table["p1"], trol.Pose) and abs(table["p1"].x - 420) < 0.01
            assert isinstance(table["pj"], trol.Joints)
            assert isinstance(table["#pp"], trol.Precision)
            with pytest.raises(trol.ArgumentError):
                robot.here("pp", "prec")  # a precision point's name starts with '#'
            with pytest.raises(trol.ArgumentError):
                robot.here("p2", "sideways")
            robot.delete_location("up")
            with pytest.raises(trol.RefusedError) as e:
                robot.delete_location("up")
            assert e.value.name == "TROL_ERR_LOCATION"
            robot.ready()
            robot.finish()
            robot.move("pj")
            robot.finish()
            assert all(abs(a - b) < 1e-3 for a, b in zip(robot.joints(), at))
            robot.save_locations()
    finally:
        proc.kill()
        proc.wait()
    assert "pj joint" in taught.read_text()
    proc = _sim_with_locations(taught)
    try:
        with trol.Robot.open(_port_of(proc), baud=38400) as robot:
            assert list(robot.locations()) == ["#pp", "jj", "p1", "pj"]
            robot.move("#pp")
            robot.finish()
            assert all(abs(a - b) < 1e-3 for a, b in zip(robot.joints(), at))
    finally:
        proc.kill()
        proc.wait()


def test_a_refusal_says_what_to_do_next_as_the_interpreter_does(robot: trol.Robot) -> None:
    # Issue 68, item 3: a jog after home() (the arm stretched upright, at the edge of its
    # reach) said only BIOS_OUT_OF_REACH; the interpreter and the pendant say what goes.
    robot.home()
    with pytest.raises(trol.RefusedError) as refused:
        robot.jog([0.0, 0.0, 100.0], straight=True)
    assert refused.value.name == "BIOS_OUT_OF_REACH"
    assert refused.value.next_step and "robot.jog([0, 0, -100], straight=True)" in refused.value.next_step
    assert refused.value.next_step in str(refused.value)
    # The step it names works.
    robot.jog([0.0, 0.0, -100.0], straight=True)
    robot.finish()


def test_a_misspelt_port_suggests_the_name_it_is_near() -> None:
    with pytest.raises(trol.SetupError) as failed:
        trol.Robot.open("Sim")
    assert "did you mean `sim` (the embedded simulator)?" in str(failed.value), failed.value
