"""MuJoCo model of a robot, built with MjSpec from the SAME robot file as the Pinocchio model.

Pipeline (:func:`build_mujoco_spec`):
    1. read the robot file (:func:`robot_file_spec`):
       * a URDF (Bolt, G1): resolve its ``package://`` mesh paths to files on disk, inject
         ``<mujoco><compiler meshdir=... fusestatic="false" discardvisual="false"
         balanceinertia="false"/></mujoco>`` so that every URDF link stays a MuJoCo body (the foot
         frames exist as bodies) and inertias are taken as written, parse with
         ``mujoco.MjSpec.from_string`` and add a free joint "root_joint" on the root link;
       * an MJCF (H1): parse with ``mujoco.MjSpec.from_file``, name the root body's free joint
         "root_joint" (add one if it has none), and drop the file's actuators and lights (this
         pipeline adds its own);
    2. remove the source's collision geoms (URDF: copies of the visual meshes; see
       ``docs/robots.md``) and add collision spheres under the feet, plus a site per foot frame;
    3. set the armature on the actuated joints (joint damping and friction loss 0, as in the
       Pinocchio model), add one torque motor per actuated joint with ``ctrlrange =
       ±torque_limit`` (Pinocchio joint order), a floor, a light, a tracking camera, and the
       contact/solver options.

The returned MjSpec can be modified before ``spec.compile()`` (terrain boxes, low-friction
patches: see :func:`add_box_geom`). The robot's joints come first in qpos/qvel, in the same
order as in Pinocchio (checked on build; :mod:`robots.conventions` maps the base coordinates).

Collision filtering: robot foot spheres and the floor use contype = conaffinity = 1. Geoms added
with :func:`add_box_geom` do too, and take priority 1 when they set their own friction, so
that their friction (not the foot's) is used in the contact (MuJoCo otherwise takes the max).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from robots.conventions import FREE_JOINT_NAME, MujocoIndexMap
from wbmpc.errors import ParameterError

if TYPE_CHECKING:  # pragma: no cover
    from robots.description import RobotDescription

FLOOR_GEOM_NAME = "floor"
TRACKING_CAMERA_NAME = "track"
CAMERA_FRAMING_BASE_HEIGHT = 0.341  # [m] base height the tracking camera's view is framed for (Bolt's)
ROBOT_COLLISION_BITS = 1  # contype / conaffinity of the feet, floor and terrain
INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
CONES = {"elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC, "pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL}


def foot_geom_name(side: str, index: int = 0) -> str:
    """Name of the ``index``-th collision sphere of foot ``side`` ("left_foot", "left_foot_1", ...)."""
    return f"{side}_foot" if index == 0 else f"{side}_foot_{index}"


def foot_site_name(side: str) -> str:
    """Name of the site placed at the foot frame of ``side`` ("left_foot_frame")."""
    return f"{side}_foot_frame"


def _resolve_package_path(uri: str, package_dirs: tuple[Path, ...]) -> Path:
    relative = uri[len("package://"):]
    for directory in package_dirs:
        candidate = Path(directory) / relative
        if candidate.is_file():
            return candidate.resolve()
    raise ParameterError(f"mesh {uri!r} not found under package_dirs={[str(p) for p in package_dirs]}")


def mujoco_urdf_text(robot: "RobotDescription") -> str:
    """The robot's URDF text with mesh paths made explicit and the ``<mujoco>`` compiler block.

    Only two edits: ``package://`` mesh paths become paths relative to ``robot.mesh_dir`` (or
    absolute when outside it) and the compiler block is inserted after ``<robot ...>``.
    """
    if robot.model_format != "urdf":
        raise ParameterError(f"robot '{robot.name}' is described by an {robot.model_format.upper()}, not a URDF")
    text = Path(robot.model_path).read_text()
    mesh_dir = Path(robot.mesh_dir).resolve()

    def replace(match: re.Match) -> str:
        path = _resolve_package_path(match.group(2), robot.package_dirs)
        try:
            name = str(path.relative_to(mesh_dir))
        except ValueError:
            name = str(path)
        return f"{match.group(1)}{name}{match.group(3)}"

    text = re.sub(r'(filename=")(package://[^"]+)(")', replace, text)
    block = (
        f'<mujoco><compiler meshdir="{mesh_dir}" fusestatic="false" discardvisual="false" '
        'balanceinertia="false" strippath="false"/></mujoco>'
    )
    text, count = re.subn(r"(<robot\b[^>]*>)", lambda m: m.group(1) + block, text, count=1)
    if count != 1:
        raise ParameterError(f"{robot.model_path} has no <robot> element")
    return text


def robot_file_spec(robot: "RobotDescription") -> mujoco.MjSpec:
    """MjSpec of ``robot.model_path`` as read, with a free joint "root_joint" on the root body.

    A URDF is read through :func:`mujoco_urdf_text`. An MJCF is read as it is, its mesh
    directory set to ``robot.mesh_dir``; its actuators and lights are removed, since
    :func:`build_mujoco_spec` adds one torque motor per actuated joint and its own light.

    Returns:
        The MjSpec (not compiled), no actuator; its collision geoms are still the file's.
    """
    if robot.model_format == "urdf":
        spec = mujoco.MjSpec.from_string(mujoco_urdf_text(robot))
    else:
        spec = mujoco.MjSpec.from_file(str(robot.model_path))
        spec.meshdir = str(Path(robot.mesh_dir).resolve())
        for element in [*spec.actuators, *spec.lights]:
            spec.delete(element)
    root = spec.worldbody.first_body()
    if root is None:
        raise ParameterError(f"{robot.model_path} defines no body")
    free_joints = [joint for joint in root.joints if joint.type == mujoco.mjtJoint.mjJNT_FREE]
    if free_joints:
        free_joints[0].name = FREE_JOINT_NAME
    else:
        root.add_freejoint(name=FREE_JOINT_NAME)
    return spec


def build_mujoco_spec(
    robot: "RobotDescription",
    timestep: float = 0.001,
    floor: bool = True,
    integrator: str = "implicitfast",
    link_collisions: bool = False,
    foot_friction: float | None = None,
) -> mujoco.MjSpec:
    """Build the MjSpec of ``robot`` (not compiled; modify it, then call ``spec.compile()``).

    Args:
        robot: the description (robot file, foot geoms, actuator limits, contact settings).
        timestep: simulation step [s] (default 1 kHz).
        floor: add an infinite floor plane at z = 0 named "floor".
        integrator: "implicitfast" (default), "euler", "implicit" or "rk4".
        link_collisions: keep the robot file's collision geoms of the links other than the lower
            legs and feet (base, shoulders, upper legs) so that a falling robot lands on its body
            instead of passing through the floor; off by default (see ``docs/robots.md``).
        foot_friction: override ``robot.mujoco_contact.friction`` for the feet and floor [-].

    Returns:
        The MjSpec: robot joints first (free joint "root_joint" then the actuated joints in
        Pinocchio order), actuators named after their joints in Pinocchio order.
    """
    if not (isinstance(timestep, (int, float)) and 0.0 < timestep <= 0.01):
        raise ParameterError(f"timestep={timestep!r} s must be in (0, 0.01]")
    if integrator not in INTEGRATORS:
        raise ParameterError(f"integrator={integrator!r} must be one of {sorted(INTEGRATORS)}")
    contact = robot.mujoco_contact
    friction = contact.friction if foot_friction is None else float(foot_friction)
    if not (np.isfinite(friction) and friction > 0.0):
        raise ParameterError(f"foot_friction={foot_friction!r} must be > 0")
    if contact.cone not in CONES:
        raise ParameterError(f"mujoco_contact.cone={contact.cone!r} must be one of {sorted(CONES)}")

    spec = robot_file_spec(robot)
    spec.modelname = robot.name
    root = spec.worldbody.first_body()

    # --- geoms: the file's visuals stay (group 1, no collision); its collision geoms are removed
    # (or kept for the upper links when link_collisions); feet get spheres.
    foot_bodies = {body for geoms in robot.mujoco_foot_geoms.values() for body, _, _ in geoms}
    lower_links = set(foot_bodies)
    for body_name in foot_bodies:  # the link carrying each foot body (lower leg)
        parent = spec.body(body_name).parent
        if parent is not None:
            lower_links.add(parent.name)
    for geom in list(spec.geoms):
        if geom.contype == 0 and geom.conaffinity == 0:  # visual geom (URDF <visual>, MJCF visual class)
            geom.group = 1
            continue
        body_name = geom.parent.name
        if link_collisions and body_name not in lower_links:
            geom.contype = geom.conaffinity = ROBOT_COLLISION_BITS
            geom.group = 3
            geom.condim = 3
            geom.friction = [friction, 0.005, 0.0001]
        else:
            spec.delete(geom)

    for side, geoms in robot.mujoco_foot_geoms.items():
        for index, (body_name, position, radius) in enumerate(geoms):
            body = spec.body(body_name)
            if body is None:
                raise ParameterError(f"mujoco_foot_geoms['{side}'] names body {body_name!r}, not in {robot.model_path.name}")
            body.add_geom(
                name=foot_geom_name(side, index),
                type=mujoco.mjtGeom.mjGEOM_SPHERE,
                size=[radius, 0.0, 0.0],
                pos=list(position),
                contype=ROBOT_COLLISION_BITS,
                conaffinity=ROBOT_COLLISION_BITS,
                condim=contact.condim,
                friction=[friction, 0.005, 0.0001],
                solref=list(contact.solref),
                solimp=list(contact.solimp),
                priority=0,
                group=0,
                rgba=[0.85, 0.3, 0.2, 1.0] if side == "left" else [0.2, 0.35, 0.85, 1.0],
            )
    model = robot.pinocchio_model
    for side, frame_name in robot.foot_frames.items():
        frame = model.frames[model.getFrameId(frame_name)]
        parent_body = _body_of_frame(spec, model, frame)
        placement = frame.placement if parent_body.name != frame_name else None
        _add_site(parent_body, foot_site_name(side), placement)

    # --- actuated joints: armature, no damping or friction loss (the Pinocchio model has none:
    # the URDFs' are 0, the H1 MJCF's damping 1 is Menagerie's default class); torque motors in
    # Pinocchio order
    for joint_name, armature, torque_limit in zip(robot.actuated_joint_names, robot.armature, robot.torque_limit):
        joint = spec.joint(joint_name)
        if joint is None:
            raise ParameterError(f"actuated joint {joint_name!r} is not a joint of the MuJoCo model")
        joint.armature = float(armature)
        joint.damping = 0.0 * joint.damping  # a float in MuJoCo 3, a (3,) array in MuJoCo 4
        joint.frictionloss = 0.0
        actuator = spec.add_actuator(name=joint_name, target=joint_name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.set_to_motor()
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.ctrlrange = [-float(torque_limit), float(torque_limit)]

    # --- world: floor, light, camera
    if floor:
        _add_floor(spec, friction, contact)
    spec.worldbody.add_light(
        name="sun", pos=[0.0, 0.0, 3.0], dir=[0.0, 0.0, -1.0], diffuse=[0.8, 0.8, 0.8], castshadow=False,
    )
    # 3/4 front-right view of the robot, relative to the base at the reference posture [m], framed for a base
    # standing CAMERA_FRAMING_BASE_HEIGHT high and scaled by the robot's (the G1 2.2x as far, the H1 2.9x).
    scale = robot.base_height_reference / CAMERA_FRAMING_BASE_HEIGHT
    camera_position, camera_target = scale * np.array([0.7, -0.8, 0.1]), scale * np.array([0.0, 0.0, -0.12])
    camera = root.add_camera(
        name=TRACKING_CAMERA_NAME, pos=list(camera_position),
        quat=list(_look_at_quaternion(camera_position, camera_target)),
    )
    camera.mode = mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM  # follows the robot's CoM, fixed orientation

    # --- options
    spec.option.timestep = float(timestep)
    spec.option.integrator = INTEGRATORS[integrator]
    spec.option.cone = CONES[contact.cone]
    spec.option.impratio = contact.impratio
    spec.option.solver = mujoco.mjtSolver.mjSOL_NEWTON
    spec.option.iterations = 50
    spec.option.noslip_iterations = contact.noslip_iterations
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.6, 0.6, 0.6]
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 720
    return spec


def _look_at_quaternion(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(w, x, y, z) orientation of a MuJoCo camera at ``eye`` looking at ``target`` (z up)."""
    backward = (eye - target) / np.linalg.norm(eye - target)  # camera z axis (looks along -z)
    right = np.cross([0.0, 0.0, 1.0], backward)
    right /= np.linalg.norm(right)
    up = np.cross(backward, right)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([right, up, backward]).reshape(9))
    return quat


def _body_of_frame(spec: mujoco.MjSpec, model, frame):
    """MuJoCo body holding a Pinocchio frame (the body of the same name, else the joint's child)."""
    body = spec.body(frame.name)
    if body is not None:
        return body
    joint_name = model.names[frame.parentJoint]
    joint = spec.joint(joint_name)
    if joint is None:
        raise ParameterError(f"frame {frame.name!r}: no MuJoCo body or joint {joint_name!r} to attach a site to")
    return joint.parent


def _add_site(body, name: str, placement) -> None:
    if placement is None:
        body.add_site(name=name, size=[0.005, 0.0, 0.0], group=4)
        return
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.asarray(placement.rotation, dtype=float).reshape(9))
    body.add_site(name=name, pos=list(placement.translation), quat=list(quat), size=[0.005, 0.0, 0.0], group=4)


def _add_floor(spec: mujoco.MjSpec, friction: float, contact) -> None:
    texture = spec.add_texture(
        name="floor_checker", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=[0.35, 0.4, 0.45], rgb2=[0.25, 0.3, 0.35], width=256, height=256,
    )
    material = spec.add_material(name="floor_material", texrepeat=[10.0, 10.0], texuniform=True, reflectance=0.1)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture.name
    spec.worldbody.add_geom(
        name=FLOOR_GEOM_NAME,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],  # infinite plane
        material=material.name,
        contype=ROBOT_COLLISION_BITS,
        conaffinity=ROBOT_COLLISION_BITS,
        condim=contact.condim,
        friction=[friction, 0.005, 0.0001],
        solref=list(contact.solref),
        solimp=list(contact.solimp),
    )


def add_box_geom(
    spec: mujoco.MjSpec,
    name: str,
    center_world: np.ndarray,
    half_extents: np.ndarray,
    friction: float | None = None,
    yaw: float = 0.0,
    rgba: tuple[float, float, float, float] = (0.6, 0.5, 0.35, 1.0),
) -> mujoco.MjsGeom:
    """Add a static box to the world (terrain block, low-friction patch) before compiling.

    Args:
        spec: the MjSpec from :func:`build_mujoco_spec`.
        name: unique geom name.
        center_world: (3,) box centre, world frame [m] (a 6 mm high block on the floor has
            centre z = 0.003).
        half_extents: (3,) half sizes along the box axes [m], all > 0.
        friction: sliding friction of the box [-]; when given, the box gets priority 1 so this
            value is used for contacts with the feet (MuJoCo otherwise takes the larger one).
            None: same as the feet (the max rule then gives the foot's value).
        yaw: rotation about the world z axis [rad].
        rgba: colour.

    Returns:
        The added geom (contact dimension, solref and solimp as the floor's).
    """
    center = np.asarray(center_world, dtype=float)
    half = np.asarray(half_extents, dtype=float)
    if center.shape != (3,) or not np.all(np.isfinite(center)):
        raise ParameterError(f"center_world={center_world!r} must be 3 finite numbers [m]")
    if half.shape != (3,) or not np.all(np.isfinite(half)) or np.any(half <= 0):
        raise ParameterError(f"half_extents={half_extents!r} must be 3 positive numbers [m]")
    if friction is not None and not (np.isfinite(friction) and friction > 0):
        raise ParameterError(f"friction={friction!r} must be > 0 (or None)")
    floor = spec.geom(FLOOR_GEOM_NAME)
    geom = spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(half),
        pos=list(center),
        quat=[np.cos(yaw / 2.0), 0.0, 0.0, np.sin(yaw / 2.0)],
        contype=ROBOT_COLLISION_BITS,
        conaffinity=ROBOT_COLLISION_BITS,
        rgba=list(rgba),
    )
    if floor is not None:
        geom.condim = floor.condim
        geom.solref = list(floor.solref)
        geom.solimp = list(floor.solimp)
        geom.friction = list(floor.friction)
    if friction is not None:
        geom.friction = [float(friction), 0.005, 0.0001]
        geom.priority = 1
    return geom


def compile_mujoco_model(robot: "RobotDescription", **options) -> mujoco.MjModel:
    """Compiled ``mujoco.MjModel`` of ``robot`` (options of :func:`build_mujoco_spec`).

    Its qpos/qvel/ctrl follow the robot-only layout of :mod:`robots.conventions` (checked).
    """
    model = build_mujoco_spec(robot, **options).compile()
    if not MujocoIndexMap.from_model(robot, model).is_identity:
        raise ParameterError(
            f"MuJoCo orders the joints of robot '{robot.name}' differently from Pinocchio; "
            "use robots.conventions.MujocoIndexMap to address its coordinates"
        )
    return model
