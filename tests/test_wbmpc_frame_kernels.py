"""Compiled frame kinematics (and the centre of mass) against Pinocchio on Bolt, G1 and H1."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robot_extras import needs_h1_extra

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.frames import FrameKinematics
from wbmpc.ocp.kernels.tree import tree_support


@pytest.mark.parametrize("robot_name", ["bolt", "g1"])
@pytest.mark.parametrize("rows", [3, 6])
def test_positions_and_jacobians_match_pinocchio(robot_name, rows):
    """Positions, rotations and the LOCAL_WORLD_ALIGNED Jacobian (linear rows, or linear and angular)."""
    robot = load_robot(robot_name)
    model = robot.pinocchio_model
    frame_ids = [model.getFrameId(name) for name in robot.foot_frames.values()]
    kinematics = FrameKinematics(model, frame_ids)
    rng = np.random.default_rng(0)
    qs = np.array([pin.integrate(model, np.asarray(robot.q_reference, dtype=float), rng.standard_normal(model.nv))
                   for _ in range(20)])
    needed = rng.random((20, len(frame_ids))) < 0.7
    positions = np.full((20, len(frame_ids), 3), np.nan)
    jacobians = np.full((20, len(frame_ids), rows, model.nv), np.nan)
    rotations = np.full((20, len(frame_ids), 3, 3), np.nan)
    kinematics.evaluate(qs, needed, positions, jacobians, rotations)
    data = model.createData()
    for t, q in enumerate(qs):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for s, frame_id in enumerate(frame_ids):
            if not needed[t, s]:
                assert np.isnan(positions[t, s]).all() and np.isnan(rotations[t, s]).all()  # untouched
                continue
            np.testing.assert_allclose(positions[t, s], data.oMf[frame_id].translation, rtol=0, atol=1e-14)
            np.testing.assert_allclose(rotations[t, s], data.oMf[frame_id].rotation, rtol=0, atol=1e-14)
            expected = pin.getFrameJacobian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)[:rows]
            np.testing.assert_allclose(jacobians[t, s], expected, rtol=0, atol=1e-13)


@pytest.mark.parametrize("robot_name", ["g1", pytest.param("h1", marks=needs_h1_extra)])
def test_center_of_mass_and_its_jacobian_match_pinocchio(robot_name):
    """The centre of mass and its Jacobian (3, nv) against Pinocchio's centerOfMass / jacobianCenterOfMass at
    random configurations, computed only where asked (with the frames' kinematics in the same pass, or alone, or
    without the Jacobian)."""
    robot = load_robot(robot_name)
    model = robot.pinocchio_model
    frame_ids = [model.getFrameId(name) for name in robot.foot_frames.values()]
    kinematics = FrameKinematics(model, frame_ids)
    assert kinematics.total_mass == pytest.approx(sum(inertia.mass for inertia in model.inertias))
    rng = np.random.default_rng(1)
    T = 20
    qs = np.array([pin.integrate(model, np.asarray(robot.q_reference, dtype=float), rng.standard_normal(model.nv))
                   for _ in range(T)])
    needed = rng.random((T, len(frame_ids))) < 0.5
    com_needed = rng.random(T) < 0.7
    positions = np.full((T, len(frame_ids), 3), np.nan)
    com = np.full((T, 3), np.nan)
    com_jacobians = np.full((T, 3, model.nv), np.nan)
    kinematics.evaluate(qs, needed, positions, np.zeros((T, len(frame_ids), 6, model.nv)),
                        com_needed=com_needed, com=com, com_jacobians=com_jacobians)
    alone = np.full((T, 3), np.nan)  # no frame needed, no Jacobian
    FrameKinematics(model, []).evaluate(qs, np.zeros((T, 0), dtype=bool), np.zeros((T, 0, 3)),
                                        com_needed=com_needed, com=alone)
    data = model.createData()
    for t, q in enumerate(qs):
        if not com_needed[t]:
            assert np.isnan(com[t]).all() and np.isnan(com_jacobians[t]).all() and np.isnan(alone[t]).all()
            continue
        expected = pin.centerOfMass(model, data, q)
        np.testing.assert_allclose(com[t], expected, rtol=0, atol=1e-13)
        np.testing.assert_allclose(alone[t], expected, rtol=0, atol=1e-13)
        np.testing.assert_allclose(com_jacobians[t], pin.jacobianCenterOfMass(model, data, q), rtol=0, atol=1e-13)
        pin.framesForwardKinematics(model, data, q)
        for s, frame_id in enumerate(frame_ids):
            if needed[t, s]:
                np.testing.assert_allclose(positions[t, s], data.oMf[frame_id].translation, rtol=0, atol=1e-14)
    with pytest.raises(ParameterError, match="com=None .*com_needed"):
        kinematics.evaluate(qs, needed, positions, com_needed=com_needed)


def test_positions_only():
    robot = load_robot("bolt")
    model = robot.pinocchio_model
    kinematics = FrameKinematics(model, [model.getFrameId("FL_FOOT")])
    positions = np.zeros((1, 1, 3))
    kinematics.evaluate(np.asarray(robot.q_reference, dtype=float)[None], np.ones((1, 1), dtype=bool), positions)
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(robot.q_reference, dtype=float))
    np.testing.assert_allclose(positions[0, 0], data.oMf[model.getFrameId("FL_FOOT")].translation, atol=1e-14)


def test_jacobians_of_another_row_count_are_refused():
    robot = load_robot("bolt")
    model = robot.pinocchio_model
    kinematics = FrameKinematics(model, [model.getFrameId("FL_FOOT")])
    with pytest.raises(ParameterError, match=r"jacobians has shape \(1, 1, 4, 12\)"):
        kinematics.evaluate(np.asarray(robot.q_reference, dtype=float)[None], np.ones((1, 1), dtype=bool),
                            np.zeros((1, 1, 3)), np.zeros((1, 1, 4, model.nv)))


def test_unsupported_models_are_named():
    model = pin.buildSampleModelManipulator()  # fixed base
    assert "free flyer" in tree_support(model)
    with pytest.raises(ParameterError, match="free flyer"):
        FrameKinematics(model, [0])
