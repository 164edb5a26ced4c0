"""``RobotDescription``: everything the library needs to know about one robot.

A description bundles the Pinocchio model (with the real actuator numbers written into it), the
contact points and their type, a reference posture standing on the floor, and the robot file
(URDF or MJCF) from which the MuJoCo model is built (see :mod:`robots.mujoco_model`). Controllers, the
sequencer and the simulator read robots only through this object, so adding a robot is one
module that builds a description (see :mod:`robots.registry` and ``docs/robots.md``).

Conventions (Pinocchio side, used everywhere in the library):
    * configuration ``q`` (nq,): base position in the world frame [m], base orientation as a unit
      quaternion stored (x, y, z, w), then the actuated joint angles [rad];
    * velocity ``v`` (nv,): base linear then angular velocity expressed in the BASE (LOCAL)
      frame [m/s, rad/s], then joint velocities [rad/s];
    * torques ``tau`` (nu,): actuated joints in Pinocchio order, ``v[6:]`` [N·m].
"""

from __future__ import annotations

import dataclasses
import types
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError

MODEL_FORMATS = {".urdf": "urdf", ".xml": "mjcf"}
"""Robot file suffix -> ``RobotDescription.model_format``: a URDF or a MuJoCo MJCF."""

CONTACT_TYPES = ("point3d", "flat6d")
"""Allowed ``RobotDescription.contact_type`` values: 3D point contacts (forces only) or 6D flat-foot
contacts (force and moment at the sole)."""


def _frozen_array(value, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """Return a read-only float copy of ``value`` after checking its shape and finiteness."""
    array = np.array(value, dtype=float)
    if array.shape != shape:
        raise ParameterError(f"{name} has shape {array.shape}, expected {shape}")
    if not np.all(np.isfinite(array)):
        raise ParameterError(f"{name}={array!r} must be finite (no NaN or inf)")
    array.setflags(write=False)
    return array


@dataclasses.dataclass(frozen=True, eq=False)
class MujocoContactSettings:
    """Contact parameters of the MuJoCo model (documented in ``docs/robots.md``).

    Attributes:
        friction: sliding friction coefficient of the foot geoms (MuJoCo combines with the floor
            by taking the maximum, so the floor uses the same value) [-].
        condim: contact dimensionality: 3 = normal force + 2D sliding friction (point feet), 6 adds
            torsional and rolling friction.
        cone: friction cone, "elliptic" or "pyramidal".
        impratio: ratio of frictional to normal constraint impedance (elliptic cones); > 1 makes
            friction stiffer, i.e. less creeping slip of point feet [-].
        solref: (time constant [s], damping ratio [-]) of the contact constraint.
        solimp: (d0, dwidth, width [m], midpoint, power) impedance of the contact constraint.
        noslip_iterations: MuJoCo noslip post-processing iterations (0 disables it).
    """

    friction: float = 1.0
    condim: int = 3
    cone: str = "elliptic"
    impratio: float = 10.0
    solref: tuple[float, float] = (0.005, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.95, 0.99, 0.001, 0.5, 2.0)
    noslip_iterations: int = 0


@dataclasses.dataclass(frozen=True, eq=False)
class RobotDescription:
    """One robot: Pinocchio model, contacts, reference posture, actuator limits, robot file.

    Build one with :func:`robots.load_robot` (``load_robot("bolt")``); every call returns a new
    description with its own Pinocchio model, so changing one never affects another.

    Attributes:
        name: registry name ("bolt", "g1", "h1").
        pinocchio_model: ``pin.Model`` with a free-flyer root joint named "root_joint";
            ``effortLimit[6:]``, ``velocityLimit[6:]`` and ``armature[6:]`` hold the real actuator
            numbers (the same as ``torque_limit``, ``velocity_limit`` and ``armature``). Treat it
            as read-only (copy it with ``pin.Model(robot.pinocchio_model)`` to modify).
        foot_frames: {"left": frame name, "right": frame name}; Pinocchio frames at the contact
            points (Bolt: centres of the foot spheres; G1, H1: centres of the soles).
        contact_type: "point3d" (3D force at a point) or "flat6d" (6D wrench at the sole).
        foot_radius: radius of the foot collision sphere(s) [m] (Bolt 0.016; G1, H1: the sole's
            corner spheres, 0.005).
        contact_frame_height: height of a foot frame above flat ground when the foot touches it
            [m] (Bolt: ``foot_radius``, as the frame is the sphere's centre; G1, H1: 0, the frame is
            on the sole).
        q_reference: (nq,) reference configuration, both feet touching the floor z = 0
            (Pinocchio order, quaternion (x, y, z, w)); read-only array.
        v_reference: (nv,) zeros; read-only array.
        torque_limit: (nu,) symmetric actuator torque limits |tau| <= torque_limit [N·m].
        velocity_limit: (nu,) joint speed limits [rad/s].
        armature: (nu,) reflected rotor inertia added to the joint-space mass matrix diagonal
            [kg·m²].
        actuated_joint_names: (nu,) names of the actuated joints in Pinocchio (= torque) order.
        model_path: the robot file both engines are built from: a URDF (``.urdf``, Bolt, G1) or
            a MuJoCo MJCF (``.xml``, H1); see ``model_format``.
        package_dirs: directories that resolve a URDF's ``package://`` mesh paths (empty for an
            MJCF, whose mesh paths are relative to ``mesh_dir``).
        mesh_dir: directory holding the robot file's mesh files (MuJoCo ``meshdir``).
        mujoco_contact: contact settings of the MuJoCo model.
        mujoco_foot_geoms: {"left": [(body name, position in body frame (3,) [m], radius [m]),
            ...], "right": [...]}: the collision spheres the MuJoCo model puts under each foot
            (one for Bolt, four sole corners for G1 and H1).
        sources: {quantity: where its value comes from} (also in ``docs/robots.md``).
        sole_size: (length along the foot frame's x, width along its y) [m] of the support
            rectangle centred on each foot frame (flat feet: what the OCP's wrench cone allows the
            centre of pressure); None for point feet.
    """

    name: str
    pinocchio_model: pin.Model
    foot_frames: Mapping[str, str]
    contact_type: str
    foot_radius: float
    contact_frame_height: float
    q_reference: np.ndarray
    v_reference: np.ndarray
    torque_limit: np.ndarray
    velocity_limit: np.ndarray
    armature: np.ndarray
    actuated_joint_names: tuple[str, ...]
    model_path: Path
    package_dirs: tuple[Path, ...]
    mesh_dir: Path
    mujoco_contact: MujocoContactSettings = dataclasses.field(default_factory=MujocoContactSettings)
    mujoco_foot_geoms: Mapping[str, tuple[tuple[str, tuple[float, float, float], float], ...]] = (
        dataclasses.field(default_factory=dict)
    )
    sources: Mapping[str, str] = dataclasses.field(default_factory=dict)
    sole_size: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        model = self.pinocchio_model
        nu = model.nv - 6
        if model.nq < 7 or model.joints[1].shortname() != "JointModelFreeFlyer":
            raise ParameterError(
                f"pinocchio_model of robot '{self.name}' must have a free-flyer root joint "
                f"(got joint 1 = {model.joints[1].shortname() if model.njoints > 1 else None})"
            )
        if self.contact_type not in CONTACT_TYPES:
            raise ParameterError(f"contact_type={self.contact_type!r} must be one of {CONTACT_TYPES}")
        if self.sole_size is not None:
            size = tuple(float(v) for v in self.sole_size)
            if len(size) != 2 or not all(np.isfinite(v) and v > 0 for v in size):
                raise ParameterError(f"sole_size={self.sole_size!r} must be (length, width) > 0 [m] or None")
            object.__setattr__(self, "sole_size", size)
        if set(self.foot_frames) != {"left", "right"}:
            raise ParameterError(f"foot_frames={dict(self.foot_frames)!r} must have exactly the keys 'left' and 'right'")
        for side, frame in self.foot_frames.items():
            if not model.existFrame(frame):
                raise ParameterError(f"foot_frames['{side}']={frame!r} is not a frame of the Pinocchio model")
        if len(self.actuated_joint_names) != nu:
            raise ParameterError(
                f"actuated_joint_names has {len(self.actuated_joint_names)} names, expected nu={nu}"
            )
        set_ = object.__setattr__  # frozen dataclass: normalise the fields once, here
        set_(self, "foot_frames", types.MappingProxyType(dict(self.foot_frames)))
        set_(self, "actuated_joint_names", tuple(self.actuated_joint_names))
        set_(self, "q_reference", _frozen_array(self.q_reference, "q_reference", (model.nq,)))
        set_(self, "v_reference", _frozen_array(self.v_reference, "v_reference", (model.nv,)))
        set_(self, "torque_limit", _frozen_array(self.torque_limit, "torque_limit", (nu,)))
        set_(self, "velocity_limit", _frozen_array(self.velocity_limit, "velocity_limit", (nu,)))
        set_(self, "armature", _frozen_array(self.armature, "armature", (nu,)))
        set_(self, "model_path", Path(self.model_path))
        if self.model_path.suffix not in MODEL_FORMATS:
            raise ParameterError(
                f"model_path={str(self.model_path)!r} must be a URDF or an MJCF file (suffix one of {sorted(MODEL_FORMATS)})"
            )
        set_(self, "package_dirs", tuple(Path(p) for p in self.package_dirs))
        set_(self, "mesh_dir", Path(self.mesh_dir))
        set_(self, "mujoco_foot_geoms", types.MappingProxyType(
            {side: tuple((str(b), tuple(float(x) for x in p), float(r)) for b, p, r in geoms)
             for side, geoms in self.mujoco_foot_geoms.items()}))
        set_(self, "sources", types.MappingProxyType(dict(self.sources)))
        if np.any(self.torque_limit <= 0):
            raise ParameterError(f"torque_limit={self.torque_limit} [N·m] must be > 0")
        if np.any(self.armature < 0):
            raise ParameterError(f"armature={self.armature} [kg·m²] must be >= 0")
        # The Pinocchio model carries the same actuator numbers as the description.
        effort, velocity, armature = model.effortLimit.copy(), model.velocityLimit.copy(), model.armature.copy()
        effort[6:], velocity[6:], armature[6:] = self.torque_limit, self.velocity_limit, self.armature
        model.effortLimit, model.velocityLimit, model.armature = effort, velocity, armature

    # ----------------------------------------------------------------------------- dimensions
    @property
    def nq(self) -> int:
        """Configuration size (Pinocchio; Bolt 13)."""
        return self.pinocchio_model.nq

    @property
    def nv(self) -> int:
        """Velocity (tangent) size (Bolt 12)."""
        return self.pinocchio_model.nv

    @property
    def nu(self) -> int:
        """Number of actuated joints (= torques; Bolt 6)."""
        return self.pinocchio_model.nv - 6

    @property
    def nx(self) -> int:
        """State size nq + nv."""
        return self.nq + self.nv

    @property
    def ndx(self) -> int:
        """State tangent size 2 nv."""
        return 2 * self.nv

    # ----------------------------------------------------------------------------- derived data
    @property
    def model_format(self) -> str:
        """Format of ``model_path``: "urdf" or "mjcf" (from its suffix, ``MODEL_FORMATS``)."""
        return MODEL_FORMATS[self.model_path.suffix]

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return float(pin.computeTotalMass(self.pinocchio_model))

    @property
    def base_body(self) -> str:
        """Name of the link the free flyer carries (the URDF's root link; Bolt "base_link", G1
        "pelvis"): the base body of the MuJoCo model too, which is built from the same URDF."""
        model = self.pinocchio_model
        root_joint_frame = model.getFrameId("root_joint", pin.FrameType.JOINT)
        return next(frame.name for frame in model.frames
                    if frame.type == pin.FrameType.BODY and frame.parentFrame == root_joint_frame)

    @property
    def base_height_reference(self) -> float:
        """Height of the base above the floor at ``q_reference`` [m] (Bolt 0.34, G1 0.76): the
        robot's size, by which scenarios scale their obstacles."""
        return float(self.q_reference[2])

    @property
    def com_position_reference(self) -> np.ndarray:
        """Centre of mass at ``q_reference``, world frame, shape (3,) [m]."""
        data = self.pinocchio_model.createData()
        return pin.centerOfMass(self.pinocchio_model, data, self.q_reference).copy()

    @property
    def com_height_reference(self) -> float:
        """CoM height above the floor at ``q_reference`` [m] (the LIP height z_c)."""
        return float(self.com_position_reference[2])

    @property
    def foot_frame_ids(self) -> dict[str, int]:
        """{"left": frame id, "right": frame id} in the Pinocchio model."""
        return {side: self.pinocchio_model.getFrameId(frame) for side, frame in self.foot_frames.items()}

    @property
    def x_reference(self) -> np.ndarray:
        """(nq + nv,) reference state [q_reference, v_reference] (a new writable array)."""
        return np.concatenate([self.q_reference, self.v_reference])

    def foot_positions_reference(self) -> dict[str, np.ndarray]:
        """Foot frame positions at ``q_reference``, world frame, {side: (3,)} [m]."""
        return self.foot_positions(self.q_reference)

    def foot_positions(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Foot frame positions at configuration ``q`` (nq,), world frame, {side: (3,)} [m]."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise ParameterError(f"q has shape {q.shape}, expected ({self.nq},)")
        data = self.pinocchio_model.createData()
        pin.framesForwardKinematics(self.pinocchio_model, data, q)
        return {side: data.oMf[fid].translation.copy() for side, fid in self.foot_frame_ids.items()}

    def summary(self) -> dict[str, Any]:
        """Key numbers of the description as a JSON-friendly dict (units in the key names)."""
        feet = self.foot_positions_reference()
        return {
            "name": self.name,
            "nq": self.nq, "nv": self.nv, "nu": self.nu,
            "mass_kg": self.mass,
            "contact_type": self.contact_type,
            "foot_frames": dict(self.foot_frames),
            "foot_radius_m": self.foot_radius,
            "base_height_reference_m": self.base_height_reference,
            "com_height_reference_m": self.com_height_reference,
            "foot_positions_reference_world_m": {side: p.tolist() for side, p in feet.items()},
            "actuated_joint_names": list(self.actuated_joint_names),
            "torque_limit_Nm": self.torque_limit.tolist(),
            "velocity_limit_rad_s": self.velocity_limit.tolist(),
            "armature_kg_m2": self.armature.tolist(),
            "model_path": str(self.model_path),
            "model_format": self.model_format,
            "sources": dict(self.sources),
        }

    def create_pinocchio_data(self) -> pin.Data:
        """A new ``pin.Data`` for ``pinocchio_model``."""
        return self.pinocchio_model.createData()

    def __repr__(self) -> str:
        return (
            f"RobotDescription(name={self.name!r}, nq={self.nq}, nv={self.nv}, nu={self.nu}, "
            f"mass={self.mass:.3f} kg, contact_type={self.contact_type!r}, "
            f"foot_frames={dict(self.foot_frames)})"
        )
