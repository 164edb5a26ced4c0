"""Unitree G1 (29 actuated joints) from example-robot-data, with 6D flat-foot contacts.

Contact frames: "left_sole" / "right_sole", added to the Pinocchio model at the centre of each
sole, on the sole plane (ankle_roll_link frame: x = 0.035 m, z = -0.035 m, the middle of the
URDF's four 5 mm corner spheres at z = -0.03 m). Torque and velocity limits are the URDF's
(Unitree's motor ratings); the armature is the reflected rotor inertia of each motor class
(values used by BeyondMimic / mjlab, computed from Unitree's rotor inertias and planetary
gear ratios). Sources in ``docs/robots.md``.
"""

from __future__ import annotations

import numpy as np

from robots.description import MujocoContactSettings, RobotDescription
from robots.feet import add_sole_frames, sole_sphere_geoms
from robots.joint_tables import values_by_joint_suffix
from robots.posture import both_sides, configuration_with_joint_angles, standing_on_floor
from robots.registry import register_robot
from robots.urdf_source import build_floating_base_model, example_robot_data_files
from wbmpc.errors import ParameterError

# Reflected rotor inertia per Unitree motor class [kg·m²].
ARMATURE_5020 = 0.003609725
ARMATURE_7520_14 = 0.010177520
ARMATURE_7520_22 = 0.025101925
ARMATURE_4010 = 0.00425

# Joint-name suffix -> armature [kg·m²] (ankles and waist roll/pitch: two 5020 motors in parallel).
ARMATURE_BY_JOINT = {
    "hip_pitch_joint": ARMATURE_7520_14,
    "hip_roll_joint": ARMATURE_7520_22,
    "hip_yaw_joint": ARMATURE_7520_14,
    "knee_joint": ARMATURE_7520_22,
    "ankle_pitch_joint": 2.0 * ARMATURE_5020,
    "ankle_roll_joint": 2.0 * ARMATURE_5020,
    "waist_yaw_joint": ARMATURE_7520_14,
    "waist_roll_joint": 2.0 * ARMATURE_5020,
    "waist_pitch_joint": 2.0 * ARMATURE_5020,
    "shoulder_pitch_joint": ARMATURE_5020,
    "shoulder_roll_joint": ARMATURE_5020,
    "shoulder_yaw_joint": ARMATURE_5020,
    "elbow_joint": ARMATURE_5020,
    "wrist_roll_joint": ARMATURE_5020,
    "wrist_pitch_joint": ARMATURE_4010,
    "wrist_yaw_joint": ARMATURE_4010,
}

FOOT_FRAMES = {"left": "left_sole", "right": "right_sole"}
ANKLE_LINKS = {"left": "left_ankle_roll_link", "right": "right_ankle_roll_link"}
SOLE_CENTER_IN_ANKLE = np.array([0.035, 0.0, -0.035])  # [m], ankle_roll_link frame
SOLE_SPHERES_IN_ANKLE = ((-0.05, 0.025, -0.03), (-0.05, -0.025, -0.03), (0.12, 0.03, -0.03), (0.12, -0.03, -0.03))
SOLE_SPHERE_RADIUS = 0.005  # [m] (URDF collision spheres)
# Support rectangle about the sole frame [m]: the sphere centres span x in [-0.05, 0.12] (0.17 m) and
# y in +-0.025 at the heel, +-0.03 at the toe (the narrower 0.05 m is taken).
SOLE_SIZE = (0.17, 0.05)

# Standing posture (knees bent, arms slightly away from the body); ankle pitch keeps the soles flat.
STANDING_JOINTS = {
    **both_sides({
        "hip_pitch_joint": -0.312,
        "knee_joint": 0.669,
        "ankle_pitch_joint": -(0.669 - 0.312),
        "elbow_joint": 0.6,
        "shoulder_pitch_joint": 0.2,
    }),
    "left_shoulder_roll_joint": 0.2,
    "right_shoulder_roll_joint": -0.2,
}


@register_robot("g1")
def load_g1() -> RobotDescription:
    """Unitree G1, 29 actuated joints (example-robot-data), flat feet with 6D sole contacts."""
    files = example_robot_data_files("g1_description", "urdf/g1_29dof_rev_1_0.urdf")
    model = build_floating_base_model(files)
    add_sole_frames(model, FOOT_FRAMES, ANKLE_LINKS, SOLE_CENTER_IN_ANKLE)
    joint_names = tuple(model.names[2:])
    nu = model.nv - 6
    if len(joint_names) != nu or any(model.joints[j].nv != 1 for j in range(2, model.njoints)):
        raise ParameterError(f"G1 model must have {nu} one-dof actuated joints, got {joint_names}")
    q_reference = standing_on_floor(model, configuration_with_joint_angles(model, STANDING_JOINTS), FOOT_FRAMES, 0.0)
    return RobotDescription(
        name="g1",
        pinocchio_model=model,
        foot_frames=FOOT_FRAMES,
        contact_type="flat6d",
        foot_radius=SOLE_SPHERE_RADIUS,
        contact_frame_height=0.0,
        q_reference=q_reference,
        v_reference=np.zeros(model.nv),
        torque_limit=np.array(model.effortLimit[6:]),
        velocity_limit=np.array(model.velocityLimit[6:]),
        armature=values_by_joint_suffix(joint_names, ARMATURE_BY_JOINT, "G1 motor class armature [kg·m²]"),
        actuated_joint_names=joint_names,
        model_path=files.urdf_path,
        package_dirs=files.package_dirs,
        mesh_dir=files.robot_dir / "meshes",
        mujoco_contact=MujocoContactSettings(),
        mujoco_foot_geoms=sole_sphere_geoms(ANKLE_LINKS, SOLE_SPHERES_IN_ANKLE, SOLE_SPHERE_RADIUS),
        sole_size=SOLE_SIZE,
        sources={
            "kinematics, inertias, torque_limit, velocity_limit": "example-robot-data g1_description/urdf/g1_29dof_rev_1_0.urdf",
            "armature": "Unitree motor classes 5020 / 7520-14 / 7520-22 / 4010 reflected inertias (BeyondMimic, mjlab)",
            "q_reference": "knees bent (hip -0.312, knee 0.669 rad), soles flat, on the floor",
            "foot frames": "sole centres, middle of the URDF's four 5 mm sole spheres",
            "sole_size": "rectangle spanned by the URDF's sole sphere centres (0.17 x 0.05 m)",
        },
    )
