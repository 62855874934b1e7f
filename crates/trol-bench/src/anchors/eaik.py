# The anchor of `trol bench ik --eaik PYTHON`: EAIK (the `eaik` package on PyPI, an analytic
# solver in C++ with Python bindings) on the A465, timed in the same run as TROL's solver.
# The poses: forward kinematics of joints uniform within the A465's limits, as TROL's.
# Prints one JSON line.
import json
import sys
import time

import numpy as np
from eaik.IK_DH import DhRobot

n, seed = int(sys.argv[1]), int(sys.argv[2])
deg = np.radians
# The A465's standard DH table (docs/a465.md), in metres.
robot = DhRobot(
    deg(np.array([-90.0, 0.0, -90.0, 90.0, -90.0, 0.0])),
    np.array([0.0, 0.3048, 0.0, 0.0, 0.0, 0.0]),
    np.array([0.3302, 0.0, 0.0, 0.3302, 0.0, 0.0762]),
)
limits = deg(np.array([175.0, 90.0, 110.0, 180.0, 105.0, 180.0]))
joints = (np.random.default_rng(seed).random((n, 6)) * 2.0 - 1.0) * limits
poses = [robot.fwdKin(q) for q in joints]
per_call = float("inf")
for _ in range(3):
    started = time.perf_counter()
    for pose in poses:
        robot.IK(pose)
    per_call = min(per_call, time.perf_counter() - started)
batched = float("inf")
for _ in range(3):
    started = time.perf_counter()
    robot.IK_batched(poses)
    batched = min(batched, time.perf_counter() - started)
print(
    json.dumps(
        {
            "poses": n,
            "family": str(robot.getKinematicFamily()),
            "ns_per_pose_one_call_each": per_call / n * 1e9,
            "ns_per_pose_batched": batched / n * 1e9,
        }
    )
)
