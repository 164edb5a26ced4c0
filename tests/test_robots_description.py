"""RobotDescription (Pinocchio side): dimensions, actuator numbers, reference posture, errors."""

import numpy as np
import pinocchio as pin
import pytest

from robots import RobotDescription, available_robots, load_robot
from wbmpc.errors import ParameterError


@pytest.fixture(scope="module")
def bolt() -> RobotDescription:
    return load_robot("bolt")


def test_bolt_dimensions_and_names(bolt):
    assert (bolt.nq, bolt.nv, bolt.nu, bolt.nx, bolt.ndx) == (13, 12, 6, 25, 24)
    assert dict(bolt.foot_frames) == {"left": "FL_FOOT", "right": "FR_FOOT"}
    assert bolt.contact_type == "point3d"
    assert bolt.actuated_joint_names == ("FL_HAA", "FL_HFE", "FL_KFE", "FR_HAA", "FR_HFE", "FR_KFE")
    assert bolt.mass == pytest.approx(1.25387789, abs=1e-8)


def test_bolt_actuator_numbers_are_written_into_the_pinocchio_model(bolt):
    model = bolt.pinocchio_model
    np.testing.assert_allclose(bolt.torque_limit, 0.025 * 12.0 * 9.0)  # 2.7 N·m
    np.testing.assert_allclose(bolt.armature, 4.5e-6 * 81.0)  # 3.645e-4 kg·m²
    np.testing.assert_array_equal(model.effortLimit[6:], bolt.torque_limit)
    np.testing.assert_array_equal(model.armature[6:], bolt.armature)
    np.testing.assert_array_equal(model.velocityLimit[6:], bolt.velocity_limit)
    assert np.all(model.armature[:6] == 0.0)
    # The armature enters the joint-space mass matrix diagonal.
    data = model.createData()
    M = pin.crba(model, data, bolt.q_reference)
    model_no_armature = pin.Model(model)
    model_no_armature.armature = np.zeros(model.nv)
    M0 = pin.crba(model_no_armature, model_no_armature.createData(), bolt.q_reference)
    np.testing.assert_allclose(np.diag(M - M0)[6:], bolt.armature, atol=1e-15)


def test_bolt_reference_posture_touches_the_floor(bolt):
    feet = bolt.foot_positions_reference()
    for side in ("left", "right"):
        assert feet[side][2] == pytest.approx(bolt.foot_radius, abs=1e-12)
    assert feet["left"][1] > 0 > feet["right"][1]  # left foot on +y
    # SRDF "standing" pose with only the base height changed.
    q_srdf = bolt.pinocchio_model.referenceConfigurations["standing"]
    np.testing.assert_array_equal(np.delete(bolt.q_reference, 2), np.delete(q_srdf, 2))
    # The SRDF pose has its foot frames about 30 mm above the floor; 16 mm is the sphere radius.
    assert bolt.q_reference[2] == pytest.approx(q_srdf[2] - 0.030 + 0.016, abs=2e-4)
    assert 0.28 < bolt.com_height_reference < 0.31
    assert np.all(bolt.v_reference == 0.0) and bolt.v_reference.shape == (12,)


def test_reference_arrays_are_read_only_and_each_load_is_independent(bolt):
    with pytest.raises(ValueError):
        bolt.q_reference[0] = 1.0
    with pytest.raises(ValueError):
        bolt.torque_limit[0] = 100.0
    other = load_robot("bolt")
    other.pinocchio_model.armature = np.zeros(other.nv)
    assert np.all(bolt.pinocchio_model.armature[6:] > 0)
    x = bolt.x_reference
    x[0] = 5.0  # a new array, free to modify
    assert bolt.q_reference[0] == 0.0


def test_unknown_robot_lists_available_ones():
    assert "bolt" in available_robots()
    with pytest.raises(ParameterError, match=r"robot='atlas' is not known; available robots: .*bolt"):
        load_robot("atlas")


def test_bad_description_fields_are_rejected(bolt):
    base = dict(
        name="bad", pinocchio_model=pin.Model(bolt.pinocchio_model), foot_frames=dict(bolt.foot_frames),
        contact_type="point3d", foot_radius=0.016, contact_frame_height=0.016,
        q_reference=bolt.q_reference, v_reference=bolt.v_reference, torque_limit=bolt.torque_limit,
        velocity_limit=bolt.velocity_limit, armature=bolt.armature,
        actuated_joint_names=bolt.actuated_joint_names, model_path=bolt.model_path,
        package_dirs=bolt.package_dirs, mesh_dir=bolt.mesh_dir,
    )
    with pytest.raises(ParameterError, match="contact_type='line' must be one of"):
        RobotDescription(**{**base, "contact_type": "line"})
    with pytest.raises(ParameterError, match=r"foot_frames\['left'\]='NOPE' is not a frame"):
        RobotDescription(**{**base, "foot_frames": {"left": "NOPE", "right": "FR_FOOT"}})
    with pytest.raises(ParameterError, match=r"torque_limit has shape \(5,\), expected \(6,\)"):
        RobotDescription(**{**base, "torque_limit": np.ones(5)})
    with pytest.raises(ParameterError, match=r"q_reference=.* must be finite"):
        RobotDescription(**{**base, "q_reference": np.full(13, np.nan)})
    with pytest.raises(ParameterError, match=r"q has shape \(12,\), expected \(13,\)"):
        bolt.foot_positions(np.zeros(12))


def test_g1_has_flat_6d_sole_contacts_on_the_floor():
    g1 = load_robot("g1")
    assert (g1.nq, g1.nv, g1.nu) == (36, 35, 29)
    assert g1.contact_type == "flat6d" and dict(g1.foot_frames) == {"left": "left_sole", "right": "right_sole"}
    data = g1.create_pinocchio_data()
    pin.framesForwardKinematics(g1.pinocchio_model, data, g1.q_reference)
    for frame_id in g1.foot_frame_ids.values():
        placement = data.oMf[frame_id]
        assert placement.translation[2] == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(placement.rotation, np.eye(3), atol=1e-12)  # soles flat
    assert data.oMf[g1.foot_frame_ids["left"]].translation[1] > 0.05
    # URDF effort limits (Unitree ratings) and the per-motor-class armature.
    np.testing.assert_array_equal(g1.pinocchio_model.effortLimit[6:], g1.torque_limit)
    knee = g1.actuated_joint_names.index("left_knee_joint")
    assert g1.torque_limit[knee] == 139.0 and g1.armature[knee] == pytest.approx(0.025101925)
    assert np.all(g1.armature > 0) and np.all(g1.torque_limit >= 5.0)
    assert 0.6 < g1.com_height_reference < 0.75
