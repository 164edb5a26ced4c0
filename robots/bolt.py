"""Bolt: the ODRI point-footed biped of the spec paper (1.25 kg, 6 torque-controlled joints).

Kinematics and inertias come from example-robot-data's ``bolt.urdf``; its effort and velocity
limits (1000) are placeholders, so the actuator numbers below replace them in BOTH engines.
Each number's source is in ``docs/robots.md``.
"""

from __future__ import annotations

import numpy as np

from robots.description import MujocoContactSettings, RobotDescription
from robots.posture import standing_on_floor
from robots.registry import register_robot
from robots.urdf_source import build_floating_base_model, example_robot_data_files
from wbmpc.errors import ParameterError

# ODRI / Solo-style actuator (robot_properties_bolt config.py; Grimminger et al., RA-L 2020).
MOTOR_TORQUE_CONSTANT = 0.025  # [N·m/A] (T-Motor Antigravity 4004, Kt)
MOTOR_MAX_CURRENT = 12.0  # [A] ODRI driver current limit used on the robots
GEAR_RATIO = 9.0  # [-] two-stage 3:1 timing-belt transmission
ROTOR_INERTIA = 4.5e-6  # [kg·m²] motor rotor inertia about its axis
MOTOR_NO_LOAD_SPEED = 300.0 * 24.0 * 2.0 * np.pi / 60.0  # [rad/s] KV 300 rpm/V at 24 V, motor side

JOINT_TORQUE_LIMIT = MOTOR_TORQUE_CONSTANT * MOTOR_MAX_CURRENT * GEAR_RATIO  # 2.7 N·m
JOINT_ARMATURE = ROTOR_INERTIA * GEAR_RATIO**2  # 3.645e-4 kg·m² reflected rotor inertia
JOINT_VELOCITY_LIMIT = MOTOR_NO_LOAD_SPEED / GEAR_RATIO  # ~83.8 rad/s (no-load bound, not enforced)

FOOT_RADIUS = 0.016  # [m] foot sphere, centred at the FL_FOOT / FR_FOOT frames
FOOT_FRAMES = {"left": "FL_FOOT", "right": "FR_FOOT"}
ACTUATED_JOINTS = ("FL_HAA", "FL_HFE", "FL_KFE", "FR_HAA", "FR_HFE", "FR_KFE")
REFERENCE_POSTURE = "standing"  # SRDF group state


@register_robot("bolt")
def load_bolt() -> RobotDescription:
    """Bolt (example-robot-data), point feet (16 mm spheres), real ODRI actuator limits."""
    files = example_robot_data_files("bolt_description", "robots/bolt.urdf", "srdf/bolt.srdf")
    model = build_floating_base_model(files)
    joint_names = tuple(model.names[2:])
    if joint_names != ACTUATED_JOINTS:
        raise ParameterError(f"bolt.urdf joints {joint_names} differ from the expected {ACTUATED_JOINTS}")
    q_standing = model.referenceConfigurations[REFERENCE_POSTURE]
    q_reference = standing_on_floor(model, q_standing, FOOT_FRAMES, FOOT_RADIUS)
    nu = model.nv - 6
    return RobotDescription(
        name="bolt",
        pinocchio_model=model,
        foot_frames=FOOT_FRAMES,
        contact_type="point3d",
        foot_radius=FOOT_RADIUS,
        contact_frame_height=FOOT_RADIUS,
        q_reference=q_reference,
        v_reference=np.zeros(model.nv),
        torque_limit=np.full(nu, JOINT_TORQUE_LIMIT),
        velocity_limit=np.full(nu, JOINT_VELOCITY_LIMIT),
        armature=np.full(nu, JOINT_ARMATURE),
        actuated_joint_names=joint_names,
        model_path=files.urdf_path,
        package_dirs=files.package_dirs,
        mesh_dir=files.robot_dir / "meshes" / "stl",
        mujoco_contact=MujocoContactSettings(),
        mujoco_foot_geoms={side: ((frame, (0.0, 0.0, 0.0), FOOT_RADIUS),) for side, frame in FOOT_FRAMES.items()},
        sources={
            "kinematics, inertias": "example-robot-data bolt_description/robots/bolt.urdf",
            "q_reference": "bolt.srdf group state 'standing', base lowered so foot spheres touch z = 0",
            "torque_limit": "Kt 0.025 N·m/A x 12 A x gear 9 = 2.7 N·m (ODRI actuator; robot_properties_bolt)",
            "armature": "rotor 4.5e-6 kg·m² x 9² = 3.645e-4 kg·m² (robot_properties_bolt motor_inertia)",
            "velocity_limit": "KV 300 rpm/V x 24 V / 9 = 83.8 rad/s no-load bound (not enforced)",
            "foot_radius": "16 mm foot sphere (issue 4); foot frame at the sphere centre",
        },
    )

