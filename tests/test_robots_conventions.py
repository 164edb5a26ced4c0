"""Pinocchio <-> MuJoCo conventions, checked by comparing both engines on random states.

Both models come from the same robot file (Bolt and G1: URDF, H1: MJCF); at the same physical
state they must give the same mass and centre of mass, the same foot placements, velocities and
contact Jacobians, the same mass matrix (armature included) and the same free-fall forward
dynamics, up to rounding.
"""

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from robot_extras import ALL_ROBOTS

from robots import load_robot
from robots.conventions import (
    MujocoIndexMap,
    base_rotation,
    base_yaw,
    mujoco_to_pinocchio_acceleration,
    mujoco_to_pinocchio_state,
    pinocchio_to_mujoco_acceleration,
    pinocchio_to_mujoco_state,
    read_mujoco_state,
    velocity_transform,
    write_mujoco_state,
    write_mujoco_torque,
)
from robots.mujoco_model import add_box_geom, build_mujoco_spec, compile_mujoco_model, foot_site_name
from wbmpc.errors import ParameterError

N_STATES = 25


@pytest.fixture(scope="module", params=ALL_ROBOTS)
def robot(request):
    """Each engine-comparison test runs on Bolt, G1 and H1."""
    return load_robot(request.param)


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


@pytest.fixture(scope="module")
def mj_model(robot):
    model = compile_mujoco_model(robot, floor=False)
    # free flight without joint-limit constraints: only the rigid-body dynamics are compared
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
    return model


def full_mass_matrix(mj_model, mj_data, out):
    """Dense MuJoCo mass matrix into ``out`` (mj_fullM's signature changed in MuJoCo 4)."""
    try:
        mujoco.mj_fullM(mj_model, mj_data, out)
    except TypeError:
        mujoco.mj_fullM(mj_model, out, mj_data.qM)


def random_state(robot, rng):
    q = np.empty(robot.nq)
    q[0:3] = rng.uniform(-1.0, 1.0, 3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[7:] = rng.uniform(-np.pi, np.pi, robot.nu)
    v = rng.normal(scale=2.0, size=robot.nv)
    return q, v


def random_states(robot, seed=0):
    rng = np.random.default_rng(seed)
    return [random_state(robot, rng) for _ in range(N_STATES)]


def test_round_trip_is_exact(robot):
    for q, v in random_states(robot, seed=1):
        qpos, qvel = pinocchio_to_mujoco_state(robot, q, v)
        np.testing.assert_array_equal(qpos[3:7], [q[6], q[3], q[4], q[5]])  # (w, x, y, z)
        np.testing.assert_array_equal(qvel[3:], v[3:])  # angular (body frame) and joints unchanged
        q2, v2 = mujoco_to_pinocchio_state(robot, qpos, qvel)
        np.testing.assert_array_equal(q2, q)
        np.testing.assert_allclose(v2, v, rtol=0, atol=1e-14)
        a = np.random.default_rng(2).normal(size=robot.nv)
        qacc = pinocchio_to_mujoco_acceleration(robot, q, v, a)
        np.testing.assert_allclose(mujoco_to_pinocchio_acceleration(robot, qpos, qvel, qacc), a, rtol=0, atol=1e-13)


def test_base_rotation_matches_pinocchio(robot):
    for q, _ in random_states(robot, seed=3)[:5]:
        expected = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
        np.testing.assert_allclose(base_rotation(q), expected, atol=1e-15)


def test_foot_positions_and_velocities_agree(robot, mj_model):
    model, data = robot.pinocchio_model, robot.create_pinocchio_data()
    mj_data = mujoco.MjData(mj_model)
    sites = {side: mj_model.site(foot_site_name(side)).id for side in robot.foot_frames}
    velocity = np.zeros(6)
    for q, v in random_states(robot, seed=4):
        mj_data.qpos[:], mj_data.qvel[:] = pinocchio_to_mujoco_state(robot, q, v)
        mujoco.mj_forward(mj_model, mj_data)
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for side, frame_id in robot.foot_frame_ids.items():
            np.testing.assert_allclose(mj_data.site_xpos[sites[side]], data.oMf[frame_id].translation, rtol=0, atol=1e-12)
            mujoco.mj_objectVelocity(mj_model, mj_data, mujoco.mjtObj.mjOBJ_SITE, sites[side], velocity, 0)
            expected = pin.getFrameVelocity(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(velocity[3:], expected.linear, rtol=0, atol=1e-11)
            np.testing.assert_allclose(velocity[:3], expected.angular, rtol=0, atol=1e-11)


def test_mass_and_centre_of_mass_agree(robot, mj_model):
    model, data = robot.pinocchio_model, robot.create_pinocchio_data()
    mj_data = mujoco.MjData(mj_model)
    assert float(np.sum(mj_model.body_mass)) == pytest.approx(robot.mass, rel=1e-12)
    for q, v in random_states(robot, seed=9):
        mj_data.qpos[:], mj_data.qvel[:] = pinocchio_to_mujoco_state(robot, q, v)
        mujoco.mj_forward(mj_model, mj_data)
        # subtree_com of the world body: the whole model's centre of mass, world frame
        np.testing.assert_allclose(mj_data.subtree_com[0], pin.centerOfMass(model, data, q), rtol=0, atol=1e-12)


def test_foot_placements_and_contact_jacobians_agree(robot, mj_model):
    """Foot frame orientation (site frame) and the 6D contact Jacobian, world-aligned at the frame:
    J_pinocchio = J_mujoco T (T maps Pinocchio's v to MuJoCo's qvel)."""
    model, data = robot.pinocchio_model, robot.create_pinocchio_data()
    mj_data = mujoco.MjData(mj_model)
    sites = {side: mj_model.site(foot_site_name(side)).id for side in robot.foot_frames}
    jac_position, jac_rotation = np.zeros((3, robot.nv)), np.zeros((3, robot.nv))
    for q, v in random_states(robot, seed=10):
        mj_data.qpos[:], mj_data.qvel[:] = pinocchio_to_mujoco_state(robot, q, v)
        mujoco.mj_forward(mj_model, mj_data)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        T = velocity_transform(robot, q)
        for side, frame_id in robot.foot_frame_ids.items():
            site = sites[side]
            np.testing.assert_allclose(mj_data.site_xmat[site].reshape(3, 3), data.oMf[frame_id].rotation, rtol=0, atol=1e-12)
            mujoco.mj_jacSite(mj_model, mj_data, jac_position, jac_rotation, site)
            expected = pin.getFrameJacobian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(jac_position @ T, expected[:3], rtol=0, atol=1e-12)
            np.testing.assert_allclose(jac_rotation @ T, expected[3:], rtol=0, atol=1e-12)


def test_mass_matrices_agree_including_armature(robot, mj_model):
    model, data = robot.pinocchio_model, robot.create_pinocchio_data()
    mj_data = mujoco.MjData(mj_model)
    M_mujoco = np.zeros((robot.nv, robot.nv))
    for q, v in random_states(robot, seed=5):
        mj_data.qpos[:], mj_data.qvel[:] = pinocchio_to_mujoco_state(robot, q, v)
        mujoco.mj_forward(mj_model, mj_data)
        full_mass_matrix(mj_model, mj_data, M_mujoco)
        M_pinocchio = pin.crba(model, data, q)
        M_pinocchio = np.triu(M_pinocchio) + np.triu(M_pinocchio, 1).T
        T = velocity_transform(robot, q)
        np.testing.assert_allclose(T.T @ M_mujoco @ T, M_pinocchio, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.diag(mj_model.dof_armature)[6:, 6:], np.diag(robot.armature))


def test_forward_dynamics_agree(robot, mj_model):
    model, data = robot.pinocchio_model, robot.create_pinocchio_data()
    mj_data = mujoco.MjData(mj_model)
    index_map = MujocoIndexMap.from_model(robot, mj_model)
    rng = np.random.default_rng(6)
    worst = 0.0
    for q, v in random_states(robot, seed=7):
        tau = rng.uniform(-1.0, 1.0, robot.nu) * robot.torque_limit
        write_mujoco_state(robot, index_map, mj_data, q, v)
        write_mujoco_torque(robot, index_map, mj_data, tau)
        mujoco.mj_forward(mj_model, mj_data)
        a = pin.aba(model, data, q, v, np.concatenate([np.zeros(6), tau]))
        expected = pinocchio_to_mujoco_acceleration(robot, q, v, a)
        worst = max(worst, np.max(np.abs(mj_data.qacc - expected)) / (1.0 + np.max(np.abs(expected))))
    assert worst < 1e-10


def test_base_yaw_of_one_quaternion_is_its_row_of_the_batch_and_pinocchios_yaw():
    """base_yaw of one quaternion (the loop's path, Python floats) equals, bit for bit, its row of a batch (numpy's),
    and the yaw of Pinocchio's rotation matrix to rounding."""
    rng = np.random.default_rng(4)
    quaternions = rng.normal(size=(200, 4))
    quaternions /= np.linalg.norm(quaternions, axis=1)[:, None]
    batch = base_yaw(quaternions)
    assert [float(base_yaw(q)) for q in quaternions] == batch.tolist()
    for q, yaw in zip(quaternions[:20], batch[:20]):
        rotation = pin.Quaternion(q[3], q[0], q[1], q[2]).toRotationMatrix()
        assert yaw == pytest.approx(np.arctan2(rotation[1, 0], rotation[0, 0]), abs=1e-12)


def test_torque_order_and_clamping(bolt):
    mj_model = compile_mujoco_model(bolt, floor=False)
    index_map = MujocoIndexMap.from_model(bolt, mj_model)
    assert index_map.is_identity
    assert [mj_model.actuator(i).name for i in index_map.actuators] == list(bolt.actuated_joint_names)
    mj_data = mujoco.MjData(mj_model)
    tau = np.array([10.0, -10.0, 1.0, -1.0, 0.5, 2.7])
    write_mujoco_torque(bolt, index_map, mj_data, tau)
    mujoco.mj_forward(mj_model, mj_data)
    np.testing.assert_allclose(mj_data.actuator_force, np.clip(tau, -bolt.torque_limit, bolt.torque_limit))
    np.testing.assert_allclose(mj_data.qfrc_actuator[6:], np.clip(tau, -2.7, 2.7))
    with pytest.raises(ParameterError, match=r"tau has shape \(5,\), expected \(6,\)"):
        write_mujoco_torque(bolt, index_map, mj_data, np.zeros(5))


def test_index_map_with_an_extra_free_body(bolt):
    spec = build_mujoco_spec(bolt)
    ball = spec.worldbody.add_body(name="ball", pos=[1.0, 0.0, 0.5])
    ball.add_freejoint(name="ball_joint")
    ball.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0], mass=0.1)
    add_box_geom(spec, "block", [0.3, 0.0, 0.003], [0.02, 0.02, 0.003], friction=0.2)
    mj_model = spec.compile()
    index_map = MujocoIndexMap.from_model(bolt, mj_model)
    assert (index_map.nq_mujoco, index_map.nv_mujoco) == (bolt.nq + 7, bolt.nv + 6)
    assert not index_map.is_identity
    mj_data = mujoco.MjData(mj_model)
    q, v = random_state(bolt, np.random.default_rng(8))
    write_mujoco_state(bolt, index_map, mj_data, q, v)
    q2, v2 = read_mujoco_state(bolt, index_map, mj_data)
    np.testing.assert_array_equal(q2, q)
    np.testing.assert_allclose(v2, v, atol=1e-14)
    np.testing.assert_array_equal(mj_data.qpos[bolt.nq:bolt.nq + 3], [1.0, 0.0, 0.5])  # ball untouched


def test_bad_shapes_are_rejected(bolt):
    with pytest.raises(ParameterError, match=r"q has shape \(12,\), expected \(13,\)"):
        pinocchio_to_mujoco_state(bolt, np.zeros(12), np.zeros(12))
    with pytest.raises(ParameterError, match=r"qvel has shape \(13,\), expected \(12,\)"):
        mujoco_to_pinocchio_state(bolt, np.zeros(13), np.zeros(13))
