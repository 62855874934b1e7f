"""TROLTrajectory from Python (docs/protocol.md "Trajectory"): timed on the simulated A465,
arguments checked before anything is sent, and a trajectory faster than the arm refused by
the controller with nothing moved."""

from __future__ import annotations

import pytest

import trol


def test_a_trajectory_runs_timed_and_ends_at_its_last_waypoint(sim_robot: trol.Robot) -> None:
    sim_robot.home()
    start = list(sim_robot.joints())
    end = [0.5, 0.3, 0.8, 0.1, 0.3, 0.2]
    timing = sim_robot.trajectory([(0.0, start), (1.0, (0.3, 0.2, 0.5, 0, 0.2, 0)), (2.0, end)])
    assert timing == "timed"
    sim_robot.finish()
    assert list(sim_robot.joints()) == pytest.approx(end, abs=1e-6)


@pytest.mark.parametrize(
    "points",
    [
        [],
        [(2.0, [0.1] * 6), (1.0, [0.2] * 6)],
        [(1.0, [0.1] * 5)],
        [(1.0, [0.1] * 7)],
        [(True, [0.1] * 6)],
        [(1.0, "abcdef")],
        "w(1, 0, 0, 0, 0, 0, 0)",
        [(float("nan"), [0.1] * 6)],
        [1.0],
    ],
)
def test_bad_trajectories_raise_argument_error_and_move_nothing(
    sim_robot: trol.Robot, points: object
) -> None:
    sim_robot.home()
    before = list(sim_robot.joints())
    with pytest.raises(trol.ArgumentError) as e:
        sim_robot.trajectory(points)  # type: ignore[arg-type]
    assert e.value.code == -32003
    sim_robot.finish()
    assert list(sim_robot.joints()) == pytest.approx(before, abs=1e-9)


def test_a_trajectory_faster_than_the_arm_is_refused_and_nothing_moves(sim_robot: trol.Robot) -> None:
    sim_robot.home()
    before = list(sim_robot.joints())
    with pytest.raises(trol.RefusedError) as e:
        sim_robot.trajectory([(0.05, [-1.0, 0, 0, 0, 0, 0])])
    assert (e.value.code, e.value.name, e.value.command) == (-30, "BIOS_TOO_FAST", "TROLTrajectory")
    sim_robot.finish()
    assert list(sim_robot.joints()) == pytest.approx(before, abs=1e-9)
