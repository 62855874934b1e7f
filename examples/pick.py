"""The manual's pick example (TROLAppro), in Python: approach test_001 along the tool's x
axis, move onto it, close the gripper, and depart. Run it against the embedded simulator:

    python examples/pick.py          # reads examples/trol.cfg (port sim, the example locations)
"""

from pathlib import Path

import trol

CONFIG = Path(__file__).with_name("trol.cfg")

with trol.Robot.from_config(CONFIG) as robot:
    robot.home()
    robot.appro("test_001", [-150.0])                # clear of the table first
    robot.appro("test_001", [-90.0], straight=True)  # along the tool's x axis, to 9 cm
    robot.move("test_001", straight=True)            # straight onto the object
    robot.finish()                                   # wait until the motion is done
    robot.close_gripper(60)                          # grip it
    robot.finish()
    robot.depart([-90.0], straight=True)             # 9 cm back along the tool's x axis
    robot.finish()
    print("pick: done, the tool at", robot.pose())
