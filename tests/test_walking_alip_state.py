"""Measured ALIP state on the G1: the exact angular momentum about the stance contact (Pinocchio's centroidal
momentum moved to the contact) against the paper's approximation (eqs. 14-15, L ≈ (c − p) × m v)."""

import numpy as np
import pinocchio as pin
import pytest

from robots.registry import load_robot
from sequencer.alip.model import AlipModel
from sequencer.alip.planner import alip_state_about_contact
from sequencer.planner import StanceState
from wbmpc.errors import ParameterError
from wbmpc.walking.alip_state import contact_angular_momentum, measured_alip_state


@pytest.fixture(scope="module")
def g1():
    robot = load_robot("g1")
    model = robot.pinocchio_model
    return robot, model, model.createData()


def joint_velocity_index(model, name):
    return model.joints[model.getJointId(name)].idx_v


def walking_like_state(robot, model):
    """Mid-swing of the right leg at 0.4 m/s: swing hip flexing, knee extending, arms swinging in opposition,
    the base pitching and rolling a little (rad/s values of a G1 gait at 0.4 m/s, T = 0.4 s)."""
    q = robot.q_reference.copy()
    v = np.zeros(model.nv)
    v[0:3] = [0.4, 0.05, -0.02]  # base linear velocity, base frame [m/s]
    v[3:6] = [0.1, -0.15, 0.05]  # base angular velocity, base frame [rad/s]
    for name, rate in (("right_hip_pitch_joint", -3.0), ("right_knee_joint", -2.0), ("right_ankle_pitch_joint", 1.0),
                       ("left_hip_pitch_joint", 1.0), ("left_knee_joint", 0.3), ("right_hip_roll_joint", 0.4),
                       ("left_shoulder_pitch_joint", -1.5), ("right_shoulder_pitch_joint", 1.5),
                       ("left_elbow_joint", 0.8), ("right_elbow_joint", -0.8), ("waist_yaw_joint", 0.3)):
        v[joint_velocity_index(model, name)] = rate
    return q, v


def contact_point(robot, q):
    return robot.foot_positions(q)["left"]


def momentum_by_bodies(model, data, q, v, point):
    """Independent check: Σ over bodies of their spatial momenta in the world frame, angular part about ``point``."""
    pin.forwardKinematics(model, data, q, v)
    total = pin.Force.Zero()
    for i in range(1, model.njoints):
        total += data.oMi[i].act(model.inertias[i] * data.v[i])
    return total.angular - np.cross(point, total.linear)  # L_p = L_O − p × P


def test_exact_momentum_matches_the_sum_over_bodies(g1):
    robot, model, data = g1
    q, v = walking_like_state(robot, model)
    point = contact_point(robot, q)
    measured = contact_angular_momentum(model, data, q, v, point)
    np.testing.assert_allclose(measured.angular_momentum_contact, momentum_by_bodies(model, data, q, v, point),
                               atol=1e-10)
    assert measured.mass == pytest.approx(33.34, abs=0.01)


def test_pure_translation_has_no_centroidal_angular_momentum_and_the_approximation_is_exact(g1):
    robot, model, data = g1
    q = robot.q_reference.copy()
    v = np.zeros(model.nv)
    v[0:3] = [0.45, -0.1, 0.03]
    measured = contact_angular_momentum(model, data, q, v, contact_point(robot, q))
    np.testing.assert_allclose(measured.angular_momentum_com, 0.0, atol=1e-12)
    np.testing.assert_allclose(measured.angular_momentum_contact, measured.approximate_angular_momentum_contact,
                               rtol=1e-12, atol=1e-12)
    exact, approx = measured_alip_state(measured), measured_alip_state(measured, approximate=True)
    np.testing.assert_allclose(exact, approx, rtol=1e-12, atol=1e-12)
    assert exact[1] == pytest.approx(measured.mass * (measured.com[2] - measured.contact_point[2]) * 0.45
                                     - measured.mass * exact[0] * 0.03, rel=1e-12)  # eq. 14, p_z v_x − p_x v_z


def test_zero_centroidal_momentum_with_limb_motion_keeps_the_approximation_exact(g1):
    """Arms and legs moving, the base counter-rotating so that L_G = 0: eqs. 14-15 (no I ω) hold exactly."""
    robot, model, data = g1
    q, v = walking_like_state(robot, model)
    pin.ccrba(model, data, q, v)
    Ag = data.Ag.copy()
    v[3:6] = np.linalg.solve(Ag[3:6, 3:6], -(Ag[3:6] @ v - Ag[3:6, 3:6] @ v[3:6]))  # cancel L_G with the base
    measured = contact_angular_momentum(model, data, q, v, contact_point(robot, q))
    np.testing.assert_allclose(measured.angular_momentum_com, 0.0, atol=1e-12)
    np.testing.assert_allclose(measured_alip_state(measured), measured_alip_state(measured, approximate=True),
                               atol=1e-12)


def test_rigid_rotation_is_the_approximation_plus_the_locked_inertia_term(g1):
    robot, model, data = g1
    q = robot.q_reference.copy()
    v = np.zeros(model.nv)
    v[0:6] = [0.3, 0.0, 0.0, 0.2, -0.3, 0.1]
    measured = contact_angular_momentum(model, data, q, v, contact_point(robot, q))
    omega_world = pin.Quaternion(q[3:7].reshape(4, 1)).toRotationMatrix() @ v[3:6]
    np.testing.assert_allclose(measured.angular_momentum_contact,
                               measured.approximate_angular_momentum_contact + measured.locked_inertia @ omega_world,
                               atol=1e-10)
    assert np.max(np.abs(measured.angular_momentum_com)) > 0.1  # the I ω term is not negligible here


def test_walking_like_state_difference_is_the_centroidal_momentum(g1):
    """With limb motion the approximation misses L_G (measured here; docs/sensitivity.md quotes it)."""
    robot, model, data = g1
    q, v = walking_like_state(robot, model)
    measured = contact_angular_momentum(model, data, q, v, contact_point(robot, q))
    exact, approx = measured_alip_state(measured), measured_alip_state(measured, approximate=True)
    difference = exact - approx
    np.testing.assert_array_equal(difference[[0, 2]], 0.0)
    np.testing.assert_allclose(difference[[3, 1]], measured.angular_momentum_com[:2], atol=1e-12)  # (L_x, L_y)
    # not negligible: -2.62 kg·m²/s of the exact L_y = 9.66 (the swing leg and the arms), +0.49 of L_x = -1.35
    assert abs(difference[1]) > 0.1 * abs(exact[1]) and abs(difference[3]) > 0.1 * abs(exact[3])
    # the locked-inertia term (eqs. 14-15 with I ω, I of the whole robot) does not close the gap either
    omega_world = pin.Quaternion(q[3:7].reshape(4, 1)).toRotationMatrix() @ v[3:6]
    residual = measured.angular_momentum_com - measured.locked_inertia @ omega_world
    assert np.max(np.abs(residual[:2])) > 0.05


def test_heading_frame_is_the_stance_yaw(g1):
    """Turning the whole robot by ψ about z and reading the state in the ψ heading frame changes nothing."""
    robot, model, data = g1
    q, v = walking_like_state(robot, model)
    base = measured_alip_state(contact_angular_momentum(model, data, q, v, contact_point(robot, q)))
    psi = 0.7
    turn = pin.SE3(pin.utils.rotate("z", psi), np.array([0.3, -0.2, 0.0]))
    pose = turn * pin.XYZQUATToSE3(q[:7])
    q_turned = q.copy()
    q_turned[:7] = pin.SE3ToXYZQUAT(pose)
    turned = measured_alip_state(contact_angular_momentum(model, data, q_turned, v, contact_point(robot, q_turned)), psi)
    np.testing.assert_allclose(turned, base, atol=1e-10)


def test_planner_state_function_is_the_one_used(g1):
    """The planner's measured state and this module's use one conversion (world -> heading frame)."""
    model = AlipModel(33.34, 0.64)
    stance = StanceState("left", np.array([0.1, 0.2]), 0.4, 0.0)
    com, vel, L = np.array([0.15, 0.1, 0.7]), np.array([0.3, -0.1, 0.0]), np.array([1.0, 5.0, 0.2])
    state = alip_state_about_contact(model, stance, com, vel, L)
    c, s = np.cos(-0.4), np.sin(-0.4)
    assert state[1] == pytest.approx(s * L[0] + c * L[1]) and state[3] == pytest.approx(c * L[0] - s * L[1])
    assert state[0] == pytest.approx(c * 0.05 - s * -0.1)


def test_bad_input_is_refused(g1):
    robot, model, data = g1
    with pytest.raises(ParameterError, match="q, v"):
        contact_angular_momentum(model, data, robot.q_reference[:-1], np.zeros(model.nv), np.zeros(3))
    with pytest.raises(ParameterError, match="contact_point"):
        contact_angular_momentum(model, data, robot.q_reference, np.zeros(model.nv), [0.0, np.nan, 0.0])
