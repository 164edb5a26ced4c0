"""The compiled tree kinematics (wbmpc.ocp.kernels.tree) and damped KKT kernels (wbmpc.ocp.kernels.kkt)
against Pinocchio on random states of every robot."""

import numpy as np
import pinocchio as pin
import pytest

from robots import load_robot
from tests.robot_extras import needs_h1_extra
from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.kkt import KKTBuffers, damped_kkt_derivatives, damped_kkt_dynamics
from wbmpc.ocp.kernels.tree import KinematicTree, frame_acceleration_derivatives, frame_motion, tree_accelerations

ROBOTS = ["bolt", "g1", pytest.param("h1", marks=needs_h1_extra)]


def _random_state(model, rng):
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    return q, rng.standard_normal(model.nv), rng.standard_normal(model.nv)


@pytest.mark.parametrize("robot_name", ROBOTS)
def test_tree_motion_and_the_feet_kinematics_equal_pinocchios(robot_name):
    """Joint placements, world velocities and accelerations (also updated alone from a, as the contacts'
    derivatives do), the world Jacobian; each foot frame's LOCAL
    Jacobian, velocity, spatial acceleration and their derivatives (getJointAccelerationDerivatives moved to
    the frame) at random (q, v, a): ~1e-15 (1e-12 allowed)."""
    robot = load_robot(robot_name)
    model = robot.pinocchio_model
    data = model.createData()
    tree = KinematicTree(model)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, v, a = _random_state(model, rng)
        pin.computeRNEADerivatives(model, data, q, v, a)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        tree.evaluate(q, v, np.zeros(model.nv))
        drift = tree.oa.copy()
        tree_accelerations(v, a, tree.parents, tree.idx_v, tree.ov, tree.J, tree.oa)  # a alone, on calc's tree
        updated = tree.oa.copy()
        tree.evaluate(q, v, a)
        assert np.array_equal(updated, tree.oa) and not np.allclose(drift, tree.oa)
        assert tree.J == pytest.approx(data.J, abs=1e-12)
        for i in range(1, model.njoints):
            assert tree.R[i] == pytest.approx(data.oMi[i].rotation, abs=1e-12)
            assert tree.p[i] == pytest.approx(data.oMi[i].translation, abs=1e-12)
            assert tree.ov[i] == pytest.approx(data.ov[i].vector, abs=1e-12)
            assert tree.oa[i] == pytest.approx(data.oa[i].vector, abs=1e-12)
        for frame_name in robot.foot_frames.values():
            fid = model.getFrameId(frame_name)
            frame = model.frames[fid]
            joint = frame.parentJoint
            oRf, opf, Jf = np.zeros((3, 3)), np.zeros(3), np.zeros((6, model.nv))
            vf, af = np.zeros(6), np.zeros(6)
            frame_motion(joint, frame.placement.rotation, frame.placement.translation, tree.parents, tree.idx_v,
                         tree.R, tree.p, tree.ov, tree.oa, tree.J, oRf, opf, Jf, vf, af)
            assert oRf == pytest.approx(data.oMf[fid].rotation, abs=1e-12)
            assert opf == pytest.approx(data.oMf[fid].translation, abs=1e-12)
            assert Jf == pytest.approx(pin.getFrameJacobian(model, data, fid, pin.LOCAL), abs=1e-12)
            assert vf == pytest.approx(pin.getFrameVelocity(model, data, fid, pin.LOCAL).vector, abs=1e-12)
            assert af == pytest.approx(pin.getFrameAcceleration(model, data, fid, pin.LOCAL).vector, abs=1e-12)
            v_dq, a_dq, a_dv = np.zeros((6, model.nv)), np.zeros((6, model.nv)), np.zeros((6, model.nv))
            frame_acceleration_derivatives(joint, oRf, opf, tree.parents, tree.idx_v, tree.ov, tree.oa, tree.J,
                                           v_dq, a_dq, a_dv)
            joint_v_dq, joint_a_dq, joint_a_dv, _ = pin.getJointAccelerationDerivatives(model, data, joint, pin.LOCAL)
            fXj = frame.placement.inverse().toActionMatrix()
            assert v_dq == pytest.approx(fXj @ joint_v_dq, abs=1e-12)
            assert a_dq == pytest.approx(fXj @ joint_a_dq, abs=1e-12)
            assert a_dv == pytest.approx(fXj @ joint_a_dv, abs=1e-12)


def test_a_model_without_a_free_flyer_is_refused_with_its_reason():
    model = pin.buildSampleModelManipulator()
    with pytest.raises(ParameterError, match="not supported by the compiled tree kinematics: the root joint is not a"):
        KinematicTree(model)


@pytest.mark.parametrize("scaled", [False, True])
def test_damped_kkt_solve_and_derivatives_equal_pinocchios_kkt_system(scaled):
    """On the G1 in double support (two 6D soles, damping 1e-3, the sole's row scales or none): the kernels'
    a and λ equal Pinocchio's forwardDynamics of S Jc, and their derivatives equal −K⁻¹ [D_τ; S D_c] with K⁻¹
    Pinocchio's KKT inverse, for arbitrary D_τ and D_c."""
    robot = load_robot("g1")
    model = robot.pinocchio_model
    data = model.createData()
    rng = np.random.default_rng(5)
    q, v, _ = _random_state(model, rng)
    tau = np.concatenate([np.zeros(6), rng.standard_normal(model.nv - 6)])
    pin.computeAllTerms(model, data, q, v)
    Jc = np.vstack([pin.getFrameJacobian(model, data, model.getFrameId(name), pin.LOCAL)
                    for name in robot.foot_frames.values()])
    nc, nv, mu = Jc.shape[0], model.nv, 1e-3
    a0 = rng.standard_normal(nc)
    scales = np.tile([1.0, 1.0, 1.0, 0.025, 0.09, 0.093], 2) if scaled else np.ones(nc)
    buffers = KKTBuffers(nv, nc, 2 * nv)
    a, force = np.zeros(nv), np.zeros(nc)
    assert damped_kkt_dynamics(np.triu(data.M), data.nle, tau, Jc, a0, scales, mu, a, force,
                               *buffers.dynamics_buffers())
    expected_a = pin.forwardDynamics(model, data, tau, scales[:, None] * Jc, scales * a0, mu)
    assert a == pytest.approx(expected_a, rel=1e-10, abs=1e-10)
    assert force == pytest.approx(scales * data.lambda_c, rel=1e-10, abs=1e-9)
    Kinv = pin.getKKTContactDynamicMatrixInverse(model, data, scales[:, None] * Jc)
    dtau_dq, dtau_dv, da0_dx = (rng.standard_normal((nv, nv)), rng.standard_normal((nv, nv)),
                                rng.standard_normal((nc, 2 * nv)))
    Fx, Fu = np.zeros((nv, 2 * nv)), np.zeros((nv, nv - 6))
    df_dx, df_du = np.zeros((nc, 2 * nv)), np.zeros((nc, nv - 6))
    damped_kkt_derivatives(dtau_dq, dtau_dv, da0_dx, scales, Fx, Fu, df_dx, df_du, *buffers.derivative_buffers())
    KD = Kinv @ np.vstack([np.hstack([dtau_dq, dtau_dv]), scales[:, None] * da0_dx])
    scale = np.abs(KD).max()
    assert np.abs(Fx + KD[:nv]).max() < 1e-10 * scale
    assert np.abs(df_dx - scales[:, None] * KD[nv:]).max() < 1e-10 * scale
    assert np.abs(Fu - Kinv[:nv, 6:nv]).max() < 1e-10 * np.abs(Kinv).max()
    assert np.abs(df_du + scales[:, None] * Kinv[nv:, 6:nv]).max() < 1e-10 * np.abs(Kinv).max()
    flight = KKTBuffers(nv, 0, 2 * nv)
    assert damped_kkt_dynamics(data.M, data.nle, tau, Jc[:0], a0[:0], scales[:0], mu, a, force[:0],
                               *flight.dynamics_buffers())
    assert a == pytest.approx(pin.aba(model, model.createData(), q, v, tau), rel=1e-10, abs=1e-10)
