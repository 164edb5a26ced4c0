"""The compiled RNEA derivatives (wbmpc.ocp.kernels.rnea_derivatives): ∂τ/∂q and ∂τ/∂v against Pinocchio's
computeRNEADerivatives(model, data, q, v, a, fext) on random states of every robot, with external forces."""

import numpy as np
import pinocchio as pin
import pytest

from robots import load_robot
from tests.robot_extras import needs_h1_extra
from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.rnea_derivatives import RNEADerivatives
from wbmpc.ocp.kernels.tree import KinematicTree

ROBOTS = ["bolt", "g1", pytest.param("h1", marks=needs_h1_extra)]


def _pinocchio_forces(model, joints, forces) -> pin.StdVec_Force:
    fext = pin.StdVec_Force()
    for _ in range(model.njoints):
        fext.append(pin.Force.Zero())
    for joint, force in zip(joints, forces):
        fext[int(joint)] = fext[int(joint)] + pin.Force(force)
    return fext


@pytest.mark.parametrize("robot_name", ROBOTS)
def test_rnea_derivatives_equal_pinocchios_with_external_forces(robot_name):
    """At random (q, v, a), the base up to 10 m from the origin, with random spatial forces [N, N·m] in the LOCAL
    frames of four joints (one of them twice, the free flyer among them once): every entry of ∂τ/∂q (the
    free-flyer columns in its LOCAL tangent space) and ∂τ/∂v, ~1e-16 relative to the largest (1e-12 allowed);
    without forces too (fext_joints empty)."""
    model = load_robot(robot_name).pinocchio_model
    data = model.createData()
    tree, links, derivatives = KinematicTree(model), LinkInertias(model), RNEADerivatives(model)
    rng = np.random.default_rng(11)
    nv = model.nv
    for trial, scale in enumerate((1.0, 1.0, 10.0)):
        q = pin.randomConfiguration(model, -scale * np.ones(model.nq), scale * np.ones(model.nq))
        v, a = 2.0 * rng.standard_normal(nv), 5.0 * rng.standard_normal(nv)
        joints = rng.choice(np.arange(2, model.njoints), size=3, replace=False)
        joints = np.concatenate([joints, [joints[0], 1]])
        forces = 50.0 * rng.standard_normal((joints.size, 6))
        if trial == 1:
            joints, forces = joints[:0], forces[:0]
        expected_dq, expected_dv, _ = pin.computeRNEADerivatives(model, data, q, v, a,
                                                                 _pinocchio_forces(model, joints, forces))
        tree.evaluate(q, v, a)
        dtau_dq, dtau_dv = np.full((nv, nv), 7.0), np.full((nv, nv), 7.0)  # every entry written
        derivatives.evaluate(tree, links, joints, forces, dtau_dq, dtau_dv)
        for ours, theirs in ((dtau_dq, expected_dq), (dtau_dv, expected_dv)):
            assert np.abs(ours - theirs).max() <= 1e-12 * np.abs(theirs).max()
        assert np.count_nonzero(expected_dq[:6, 6:]) and np.count_nonzero(expected_dq[6:, :6])


def test_bad_inputs_are_refused_naming_them():
    with pytest.raises(ParameterError, match="not supported by the compiled RNEA derivatives: the root joint"):
        RNEADerivatives(pin.buildSampleModelManipulator())
    model = load_robot("bolt").pinocchio_model
    tree, links, derivatives = KinematicTree(model), LinkInertias(model), RNEADerivatives(model)
    nv = model.nv
    square = np.zeros((nv, nv))
    with pytest.raises(ParameterError, match=r"^dtau_dv has shape \(3, 3\), expected"):
        derivatives.evaluate(tree, links, [], np.zeros((0, 6)), square, np.zeros((3, 3)))
    with pytest.raises(ParameterError, match=r"^fext_joints=\[0\] must be joints 1 \.\. 7$"):
        derivatives.evaluate(tree, links, [0], np.zeros((1, 6)), square, square.copy())
    g1 = load_robot("g1").pinocchio_model
    with pytest.raises(ParameterError, match="^tree has nv=35, the link inertias nv=12, the derivatives nv=12$"):
        derivatives.evaluate(KinematicTree(g1), links, [], np.zeros((0, 6)), square, square.copy())
