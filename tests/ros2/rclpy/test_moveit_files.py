"""`trol ros2 --write-config DIR`: MoveIt's files for the node, read as MoveIt reads them
(YAML, the URDF and SRDF as XML, the launch file as Python) and checked against each other and
against the URDF: no ROS 2 machine needed (MoveIt does not install from PyPI)."""

import os
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[3]


def write_config(tmp: Path, *args: str) -> subprocess.CompletedProcess:
    binary = Path(os.environ.get("TROL_ROS2_BIN", ROOT / "target" / "debug" / "trol-ros2"))
    return subprocess.run([str(binary), "--write-config", str(tmp), *args], capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("prefix", ["", "arm1_"])
def test_the_files_agree_with_the_urdf_and_with_each_other(tmp_path: Path, prefix: str) -> None:
    done = write_config(tmp_path, "--namespace", "cell", "--prefix", prefix)
    assert done.returncode == 0, done.stderr
    urdf = ET.parse(tmp_path / "crs_a465.urdf").getroot()
    links = {l.get("name") for l in urdf.findall("link")}
    joints = {j.get("name"): j for j in urdf.findall("joint")}
    arm = [f"{prefix}joint_{i}" for i in range(1, 7)]
    assert all(joints[j].get("type") == "revolute" for j in arm)
    # The gripper: one prismatic joint whose value is the gap, as GripperCommand's position.
    grip = joints[f"{prefix}gripper_joint"]
    assert grip.get("type") == "prismatic"
    assert (float(grip.find("limit").get("lower")), float(grip.find("limit").get("upper"))) == (0.0, 0.05)
    assert all(l.startswith(prefix) for l in links)
    for j in joints.values():
        assert j.find("parent").get("link") in links and j.find("child").get("link") in links
    # Every link has a collision shape: MoveIt plans around the whole arm and the fingers.
    for link in urdf.findall("link"):
        assert link.find("collision") is not None, link.get("name")
    # The fingers: one on a mimic joint (at minus half the gap), one on gripper_joint.
    mimic = joints[f"{prefix}finger_right_joint"].find("mimic")
    assert (mimic.get("joint"), float(mimic.get("multiplier"))) == (f"{prefix}gripper_joint", -0.5)

    srdf = ET.parse(tmp_path / "crs_a465.srdf").getroot()
    chain = srdf.find("group[@name='arm']/chain")
    assert chain.get("base_link") == f"{prefix}base_link" and chain.get("tip_link") == f"{prefix}tool0"
    for d in srdf.findall("disable_collisions"):
        assert d.get("link1") in links and d.get("link2") in links
    assert [j.get("name") for j in srdf.findall("group_state[@name='ready']/joint")] == arm

    limits = yaml.safe_load((tmp_path / "joint_limits.yaml").read_text())["joint_limits"]
    assert sorted(limits) == sorted(arm)
    for j in arm:
        v = limits[j]["max_velocity"]
        assert limits[j]["has_velocity_limits"] and limits[j]["has_acceleration_limits"]
        assert 0 < v <= float(joints[j].find("limit").get("velocity")) + 1e-9
        assert limits[j]["max_acceleration"] > 0

    # move_group runs in the node's namespace; each controller is named after the node's
    # action there (an empty action_ns: the action is at the controller's name).
    controllers = yaml.safe_load((tmp_path / "moveit_controllers.yaml").read_text())
    manager = controllers["moveit_simple_controller_manager"]
    assert manager["controller_names"] == ["follow_joint_trajectory", "gripper_cmd"]
    arm_controller, gripper = manager["follow_joint_trajectory"], manager["gripper_cmd"]
    assert (arm_controller["type"], arm_controller["action_ns"], arm_controller["joints"]) == \
        ("FollowJointTrajectory", "", arm)
    assert (gripper["type"], gripper["action_ns"], gripper["joints"]) == \
        ("GripperCommand", "", [f"{prefix}gripper_joint"])
    group = {l.get("name") for l in srdf.findall("group[@name='gripper']/link")}
    assert group == {f"{prefix}finger_left", f"{prefix}finger_right"}
    assert srdf.find("end_effector").get("parent_link") == f"{prefix}tool0"

    kinematics = yaml.safe_load((tmp_path / "kinematics.yaml").read_text())
    assert "kinematics_solver" in kinematics["arm"]
    source = (tmp_path / "move_group.launch.py").read_text()
    compile(source, "move_group.launch.py", "exec")
    assert 'namespace="cell"' in source and "generate_launch_description" in source


def test_a_node_in_a_deeper_namespace_or_none_gets_its_move_group_there(tmp_path: Path) -> None:
    for ns, want in [("cell/arm2", 'namespace="cell/arm2"'), ("/", 'namespace=""')]:
        done = write_config(tmp_path / ns.strip("/").replace("/", "_"), "--namespace", ns)
        assert done.returncode == 0, done.stderr
        source = (tmp_path / ns.strip("/").replace("/", "_") / "move_group.launch.py").read_text()
        assert want in source, source
