"""The anchor of `trol bench mars`: CTU Prague's own MARS 8 client (ctu-crs, from the package
registry) moves joint 1 back and forth on the unit at argv[1] and waits for each motion to
stop, as CTU's programs do (move_to_q, then wait_for_motion_stop: COORDMV, then R:).

Prints `call` right before each move_to_q and `returned` right after wait_for_motion_stop
returns (flushed), so that the benchmark, which watches the simulated unit's arm, times from
the call to the arm's start and from its stand to the return.

Run: python ctu_crs_moves.py DEVICE MOVES RADIANS
"""

import sys
import types

# ctu-crs imports Basler's camera package at load time; there is no camera here.
sys.modules.setdefault("pypylon", types.ModuleType("pypylon"))
sys.modules["pypylon"].pylon = None
sys.modules["pypylon"].genicam = None

from ctu_crs import CRS93  # noqa: E402


def main():
    device, moves, step = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    robot = CRS93(tty_dev=device)
    # The unit is homed already: no hard home, as a program that ran before would find it.
    robot.initialize(home=False)
    q = robot.get_q()
    for k in range(moves):
        target = q.copy()
        target[0] += step if k % 2 == 0 else 0.0
        print("call", flush=True)
        robot.move_to_q(target)
        robot.wait_for_motion_stop()
        print("returned", flush=True)
    robot.close()


if __name__ == "__main__":
    main()
