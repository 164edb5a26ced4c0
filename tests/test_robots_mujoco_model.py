"""MuJoCo model built from the URDF: structure, actuators, contacts, extra geoms, errors."""

import mujoco
import numpy as np
import pytest

from robots import load_robot
from robots.conventions import pinocchio_to_mujoco_state
from robots.mujoco_model import (
    FLOOR_GEOM_NAME,
    TRACKING_CAMERA_NAME,
    add_box_geom,
    build_mujoco_spec,
    compile_mujoco_model,
    foot_geom_name,
    mujoco_urdf_text,
)
from wbmpc.errors import ParameterError


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


@pytest.fixture(scope="module")
def mj_model(bolt):
    return compile_mujoco_model(bolt)


def colliding_geoms(model):
    return sorted(model.geom(i).name for i in range(model.ngeom) if model.geom_contype[i] or model.geom_conaffinity[i])


def test_structure_matches_the_description(bolt, mj_model):
    assert (mj_model.nq, mj_model.nv, mj_model.nu) == (bolt.nq, bolt.nv, bolt.nu)
    assert mj_model.opt.timestep == 0.001
    assert mj_model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    joint_names = [mj_model.joint(i).name for i in range(mj_model.njnt)]
    assert joint_names == ["root_joint", *bolt.actuated_joint_names]
    assert [mj_model.actuator(i).name for i in range(mj_model.nu)] == list(bolt.actuated_joint_names)
    np.testing.assert_array_equal(mj_model.actuator_ctrlrange, np.column_stack([-bolt.torque_limit, bolt.torque_limit]))
    assert np.all(mj_model.actuator_ctrllimited == 1)
    np.testing.assert_array_equal(mj_model.dof_armature[6:], bolt.armature)
    assert np.all(mj_model.dof_damping == 0) and np.all(mj_model.dof_frictionloss == 0)
    assert mj_model.body_mass.sum() == pytest.approx(bolt.mass, abs=1e-12)
    assert mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_CAMERA, TRACKING_CAMERA_NAME) >= 0


def test_only_the_foot_spheres_and_the_floor_collide(bolt, mj_model):
    assert colliding_geoms(mj_model) == sorted([FLOOR_GEOM_NAME, foot_geom_name("left"), foot_geom_name("right")])
    for side, frame in bolt.foot_frames.items():
        geom = mj_model.geom(foot_geom_name(side))
        assert geom.type[0] == mujoco.mjtGeom.mjGEOM_SPHERE
        assert geom.size[0] == bolt.foot_radius
        assert mj_model.body(geom.bodyid[0]).name == frame
        assert geom.friction[0] == 1.0 and geom.condim[0] == 3
    # visual meshes are kept (group 1), collision meshes of the links can be turned on
    assert sum(mj_model.geom_type == mujoco.mjtGeom.mjGEOM_MESH) == 9
    with_links = compile_mujoco_model(bolt, link_collisions=True)
    assert len(colliding_geoms(with_links)) == 3 + 5  # + base, shoulders, upper legs


def test_reference_posture_rests_on_the_floor(bolt, mj_model):
    data = mujoco.MjData(mj_model)
    data.qpos[:], data.qvel[:] = pinocchio_to_mujoco_state(bolt, bolt.q_reference, bolt.v_reference)
    mujoco.mj_forward(mj_model, data)
    assert data.ncon == 2
    np.testing.assert_allclose(data.contact.dist, 0.0, atol=1e-12)
    np.testing.assert_allclose(data.subtree_com[0][2], bolt.com_height_reference, atol=1e-12)


def test_box_geoms_with_their_own_friction_take_priority(bolt):
    spec = build_mujoco_spec(bolt)
    add_box_geom(spec, "ice", [0.0, 0.0, 0.001], [0.2, 0.2, 0.001], friction=0.05)
    add_box_geom(spec, "block", [0.5, 0.0, 0.003], [0.01, 0.02, 0.003], yaw=0.3)
    model = spec.compile()
    data = mujoco.MjData(model)
    qpos, _ = pinocchio_to_mujoco_state(bolt, bolt.q_reference, bolt.v_reference)
    qpos[2] += 0.002  # the feet now rest on the 2 mm ice patch
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    ice = model.geom("ice").id
    touching_ice = [data.contact[i] for i in range(data.ncon) if ice in (data.contact[i].geom1, data.contact[i].geom2)]
    assert len(touching_ice) == 2  # one per foot
    assert np.allclose([c.friction[0] for c in touching_ice], 0.05)
    assert model.geom("block").priority[0] == 0 and model.geom("ice").priority[0] == 1
    with pytest.raises(ParameterError, match=r"half_extents=.* must be 3 positive numbers"):
        add_box_geom(spec, "bad", [0, 0, 0], [0.1, 0.0, 0.1])
    with pytest.raises(ParameterError, match=r"friction=-1.0 must be > 0"):
        add_box_geom(spec, "bad", [0, 0, 0], [0.1, 0.1, 0.1], friction=-1.0)


def test_urdf_text_only_gains_the_compiler_block_and_explicit_mesh_paths(bolt):
    text = mujoco_urdf_text(bolt)
    assert "package://" not in text
    assert 'fusestatic="false"' in text and 'discardvisual="false"' in text
    original = bolt.model_path.read_text()
    assert text.count("<joint ") == original.count("<joint ") and text.count("<link ") == original.count("<link ")


def test_bad_options_are_rejected(bolt):
    with pytest.raises(ParameterError, match=r"timestep=0 s must be in \(0, 0.01\]"):
        build_mujoco_spec(bolt, timestep=0)
    with pytest.raises(ParameterError, match=r"integrator='leapfrog' must be one of"):
        build_mujoco_spec(bolt, integrator="leapfrog")
    with pytest.raises(ParameterError, match=r"foot_friction=0.0 must be > 0"):
        build_mujoco_spec(bolt, foot_friction=0.0)
