"""Sample the arm's pose during a move and plot joints and TCP over time.

Needs matplotlib (an optional dependency: pip install matplotlib, or pip install
"./crates/trol-py[plot]"). Writes motion.png, or shows the plot with --show.

    python examples/plot_motion.py
"""

import sys
import time

import matplotlib

if "--show" not in sys.argv:
    matplotlib.use("Agg")
import matplotlib.pyplot as plt

import trol

samples: list[tuple[float, trol.Joints, trol.Pose]] = []
with trol.Robot.open("sim", time_scale=1) as robot:
    robot.home()
    robot.speed(50)
    robot.ready()
    robot.finish()
    robot.move([420.0, 150.0, 250.0, 0.0, 1.5707963, 0.0])
    t0 = time.monotonic()
    while True:
        moving = robot.is_moving()
        samples.append((time.monotonic() - t0, robot.joints(actual=True), robot.pose(actual=True)))
        if not moving:
            break
        time.sleep(0.02)

t = [s[0] for s in samples]
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
for i in range(6):
    top.plot(t, [s[1][i] for s in samples], label=f"J{i + 1}")
top.set_ylabel("joint (rad)")
top.legend(ncol=6, fontsize="small")
for name in ("x", "y", "z"):
    bottom.plot(t, [getattr(s[2], name) for s in samples], label=name)
bottom.set_ylabel("TCP (mm)")
bottom.set_xlabel("time (s)")
bottom.legend()
fig.suptitle(f"MoveII from READY, {len(samples)} samples")
if "--show" in sys.argv:
    plt.show()
else:
    fig.savefig("motion.png", dpi=100)
    print("plot_motion: wrote motion.png from", len(samples), "samples")
