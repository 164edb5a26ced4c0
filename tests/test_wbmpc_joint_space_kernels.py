"""The compiled joint-space terms (wbmpc.ocp.kernels.joint_space): M(q) and b(q, v) against Pinocchio's crba
(WORLD convention, upper triangle, armature included) and nonLinearEffects on random states of every robot."""

import numpy as np
import pinocchio as pin
import pytest

from robots import load_robot
from tests.robot_extras import needs_h1_extra
from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.tree import KinematicTree

ROBOTS = ["bolt", "g1", pytest.param("h1", marks=needs_h1_extra)]


@pytest.mark.parametrize("robot_name", ROBOTS)
def test_inertia_and_nonlinear_effects_equal_pinocchios(robot_name):
    """M's upper triangle (its strict lower triangle untouched) and b at random (q, v), base far from the
    origin: ~1e-16 relative (1e-12 allowed); the armature on M's diagonal."""
    model = load_robot(robot_name).pinocchio_model
    assert np.any(model.armature[6:] > 0.0)
    data = model.createData()
    tree, links = KinematicTree(model), LinkInertias(model)
    rng = np.random.default_rng(7)
    nv = model.nv
    for scale in (1.0, 10.0):
        q = pin.randomConfiguration(model, -scale * np.ones(model.nq), scale * np.ones(model.nq))
        v = 2.0 * rng.standard_normal(nv)
        tree.evaluate(q, v, np.zeros(nv))
        M, b = np.full((nv, nv), 7.0), np.zeros(nv)
        links.evaluate(tree, M, b)
        expected_M = np.triu(pin.crba(model, data, q, pin.Convention.WORLD))
        expected_b = pin.nonLinearEffects(model, data, q, v)
        assert np.abs(np.triu(M) - expected_M).max() <= 1e-12 * np.abs(expected_M).max()
        assert np.all(np.tril(M, -1)[np.tril_indices(nv, -1)] == 7.0)
        assert np.abs(b - expected_b).max() <= 1e-12 * np.abs(expected_b).max()


def test_bad_inputs_are_refused_naming_them():
    with pytest.raises(ParameterError, match="not supported by the compiled joint-space terms: the root joint"):
        LinkInertias(pin.buildSampleModelManipulator())
    model = load_robot("bolt").pinocchio_model
    tree, links = KinematicTree(model), LinkInertias(model)
    with pytest.raises(ParameterError, match="^M has shape"):
        links.evaluate(tree, np.zeros((3, 3)), np.zeros(model.nv))
    with pytest.raises(ParameterError, match="^b has shape"):
        links.evaluate(tree, np.zeros((model.nv, model.nv)), np.zeros(3))
