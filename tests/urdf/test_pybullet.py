"""`trol urdf` in pybullet (from the package registry), self-collision on: with every joint
held at its position by its motor the arm stands still, no two of its links touch, and the
flange frame has the small mass the URDF gives it (issue 42: J1 turned 79 deg by itself, the
shapes of the foot plate and the column overlapping, and pybullet gave the massless flange
1 kg and 1 kg m^2)."""

import math
import os
import subprocess

import pybullet
import pytest

TROL = os.environ.get("TROL_BIN", "target/debug/trol")


@pytest.mark.timeout(120)
def test_held_with_self_collision_on_it_stands_still(tmp_path) -> None:
    path = tmp_path / "a465.urdf"
    path.write_text(subprocess.run([TROL, "urdf"], check=True, capture_output=True,
                                   text=True).stdout)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.setGravity(0, 0, -9.81, physicsClientId=client)
        robot = pybullet.loadURDF(str(path), useFixedBase=True,
                                  flags=pybullet.URDF_USE_SELF_COLLISION,
                                  physicsClientId=client)
        joints = range(pybullet.getNumJoints(robot, physicsClientId=client))
        revolute = [j for j in joints
                    if pybullet.getJointInfo(robot, j, physicsClientId=client)[2]
                    == pybullet.JOINT_REVOLUTE]
        assert len(revolute) == 6
        for start in ([0.0] * 6, [0.4, 0.5, 1.0, -0.8, 0.6, 1.2]):
            for j, q in zip(revolute, start):
                pybullet.resetJointState(robot, j, q, physicsClientId=client)
                pybullet.setJointMotorControl2(robot, j, pybullet.POSITION_CONTROL,
                                               targetPosition=q, force=500,
                                               physicsClientId=client)
            for _ in range(240 * 3):
                pybullet.stepSimulation(physicsClientId=client)
            now = [pybullet.getJointState(robot, j, physicsClientId=client)[0] for j in revolute]
            moved = max(abs(a - b) for a, b in zip(now, start))
            assert math.degrees(moved) < 0.1, (start, now)
            assert not pybullet.getContactPoints(robot, robot, physicsClientId=client)
        names = {pybullet.getJointInfo(robot, j, physicsClientId=client)[12].decode(): j
                 for j in joints}
        flange_mass = pybullet.getDynamicsInfo(robot, names["flange"], physicsClientId=client)[0]
        assert flange_mass < 0.01, flange_mass
    finally:
        pybullet.disconnect(client)
