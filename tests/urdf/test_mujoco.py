"""`trol urdf` in another simulator: MuJoCo (from the package registry) loads the A465's
URDF (every moving link has mass, inertia and a collision shape) and its kinematics agree with TROL's: at several joint sets, the
wrist centre MuJoCo computes is where TROL's simulated arm puts it. Dropped under gravity
with contacts on, the arm folds as with contacts off (issue 42: the shapes of links joined
by a joint touched at every pose, and held the forearm horizontal)."""

import math
import os
import subprocess

import mujoco
import numpy as np
import pytest

import trol

TROL = os.environ.get("TROL_BIN", "target/debug/trol")

POSES = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.3, -0.4, 0.9, 1.2, -0.7, 2.0],
    [-1.1, 0.6, 0.4, -2.0, 1.3, -0.5],
]


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> mujoco.MjModel:
    path = tmp_path_factory.mktemp("urdf") / "a465.urdf"
    path.write_text(subprocess.run([TROL, "urdf"], check=True, capture_output=True,
                                   text=True).stdout)
    return mujoco.MjModel.from_xml_path(str(path))


def test_mujoco_loads_it_with_mass_and_collision_shapes(model: mujoco.MjModel) -> None:
    assert model.nq == 6
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, i) for i in range(model.nbody)]
    for i in range(1, 7):
        assert f"link_{i}" in names, names
    # Every moving body has mass (MuJoCo refuses a URDF without) and a collision shape (the
    # flange and the tool are fused into link_6, fixed to it).
    assert all(m > 0 for m in model.body_mass[1:]), model.body_mass
    bodies = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(b)) for b in model.geom_bodyid}
    assert {f"link_{i}" for i in range(1, 7)} <= bodies, bodies


@pytest.mark.timeout(120)
def test_its_kinematics_are_trols(model: mujoco.MjModel) -> None:
    data = mujoco.MjData(model)
    link_5 = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "link_5")
    with trol.Robot.open("sim", time_scale=50) as robot:
        robot.home()
        for q in POSES:
            robot.ma(q)
            robot.finish()
            x, y, z, yaw, pitch, roll = robot.pose()
            # The tool frame's x axis leaves the flange; the wrist centre (joint 5's origin)
            # lies 76.2 mm back along it.
            rot = (np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]])
                   @ np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0], [-math.sin(pitch), 0, math.cos(pitch)]])
                   @ np.array([[1, 0, 0], [0, math.cos(roll), -math.sin(roll)], [0, math.sin(roll), math.cos(roll)]]))
            wrist = np.array([x, y, z]) - 76.2 * rot[:, 0]
            data.qpos[:] = q
            mujoco.mj_forward(model, data)
            assert np.allclose(data.xpos[link_5] * 1000.0, wrist, atol=0.1), (q, data.xpos[link_5], wrist)


# Links joined by a joint, and those either side of the elbow's and the wrist's spheres:
# their shapes must never touch.
JOINED = {("world", "link_1"), ("link_1", "link_2"), ("link_2", "link_3"), ("link_3", "link_4"),
          ("link_2", "link_4"), ("link_4", "link_5"), ("link_5", "link_6"), ("link_4", "link_6")}


def drop(model_path: str, contacts: bool) -> tuple[np.ndarray, set[tuple[str, str]]]:
    """3 s of the arm falling under gravity, no motors, from J3 at 0.3 rad: its joints at
    the end (degrees) and the pairs of bodies that touched on the way."""
    m = mujoco.MjModel.from_xml_path(model_path)
    if not contacts:
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    d = mujoco.MjData(m)
    d.qpos[:6] = [0.0, 0.0, 0.3, 0.0, 0.0, 0.0]
    touched = set()
    for _ in range(int(3.0 / m.opt.timestep)):
        mujoco.mj_step(m, d)
        for c in d.contact[: d.ncon]:
            a = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom1]))
            b = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom2]))
            touched.add(tuple(sorted((a, b))))
    return np.degrees(d.qpos[:6]), touched


@pytest.mark.timeout(120)
def test_dropped_with_contacts_it_folds_as_without(tmp_path) -> None:
    path = tmp_path / "a465.urdf"
    path.write_text(subprocess.run([TROL, "urdf"], check=True, capture_output=True,
                                   text=True).stdout)
    on, touched = drop(str(path), True)
    off, _ = drop(str(path), False)
    joined = {tuple(sorted(p)) for p in JOINED}
    assert not (touched & joined), touched
    # The forearm folds down (it was held horizontal), as without contacts.
    assert off[2] > 60.0, off
    assert np.abs(on - off).max() < 1.0, (on, off)
