"""State conventions: converting between Pinocchio and MuJoCo coordinates of the same robot.

                     Pinocchio (q, v)                          MuJoCo (qpos, qvel)
    base position    q[0:3], world frame [m]                   qpos[0:3], world frame [m]
    base orientation q[3:7] = (x, y, z, w)                     qpos[3:7] = (w, x, y, z)
    base linear vel. v[0:3], BASE (local) frame [m/s]          qvel[0:3], WORLD frame [m/s]
    base angular vel v[3:6], base frame [rad/s]                qvel[3:6], base frame [rad/s]
    joints           q[7:], v[6:] in URDF tree order           same order (robot joints first)
    torques          tau (nu,) = generalized forces on v[6:]   ctrl[actuator index] (one motor per joint)

With R the base rotation (base -> world): qvel[0:3] = R v[0:3]. The base accelerations differ
by more than a rotation: Pinocchio's a[0:3] is the spatial acceleration in the base frame, while
MuJoCo's qacc[0:3] is the time derivative of the world-frame velocity, so
qacc[0:3] = R (a[0:3] + omega x v[0:3]).

The functions work on the robot-only layout (qpos (nq,), qvel (nv,), ctrl (nu,)) by default. A
MuJoCo model with more degrees of freedom or actuators (a pushed ball, ...) is handled by a
:class:`MujocoIndexMap` built from the compiled model, through :func:`read_mujoco_state`,
:func:`write_mujoco_state` and :func:`write_mujoco_torque`.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from robots.description import RobotDescription
from wbmpc.errors import ParameterError

FREE_JOINT_NAME = "root_joint"
"""Name of the floating base's free joint in the MuJoCo model."""


def _vector(name: str, value, size: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise ParameterError(f"{name} has shape {array.shape}, expected ({size},)")
    return array


def _rotation_from_quaternion_wxyz(w: float, x: float, y: float, z: float) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion (same formula as Pinocchio and MuJoCo)."""
    return np.array([
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ])


def base_rotation(q: np.ndarray) -> np.ndarray:
    """Base-to-world rotation (3, 3) of a Pinocchio configuration ``q`` (quaternion q[3:7] = x, y, z, w)."""
    x, y, z, w = np.asarray(q, dtype=float)[3:7]
    return _rotation_from_quaternion_wxyz(w, x, y, z)


def base_yaw(quaternion_xyzw) -> np.ndarray:
    """Yaw [rad] in (-pi, pi] of base orientations given as Pinocchio quaternions (x, y, z, w),
    shape (4,) or (n, 4); returns a scalar array or shape (n,)."""
    quaternion = np.asarray(quaternion_xyzw, dtype=float)
    # one quaternion (the loop's 1 kHz path): Python floats, the same IEEE arithmetic without numpy's scalar overhead
    x, y, z, w = quaternion.tolist() if quaternion.ndim == 1 else np.moveaxis(quaternion, -1, 0)
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pinocchio_to_mujoco_state(robot: RobotDescription, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio (q (nq,), v (nv,)) -> MuJoCo (qpos (nq,), qvel (nv,)), robot-only layout.

    Quaternion (x, y, z, w) -> (w, x, y, z); base linear velocity base frame -> world frame;
    angular velocity and joints unchanged. New arrays; the inputs are not modified.
    """
    q = _vector("q", q, robot.nq)
    v = _vector("v", v, robot.nv)
    qpos = q.copy()
    qpos[3] = q[6]
    qpos[4:7] = q[3:6]
    qvel = v.copy()
    qvel[0:3] = base_rotation(q) @ v[0:3]
    return qpos, qvel


def mujoco_to_pinocchio_state(robot: RobotDescription, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo (qpos (nq,), qvel (nv,)) -> Pinocchio (q (nq,), v (nv,)), robot-only layout.

    Inverse of :func:`pinocchio_to_mujoco_state` (exact for the quaternion, to rounding for the
    base velocity rotation).
    """
    qpos = _vector("qpos", qpos, robot.nq)
    qvel = _vector("qvel", qvel, robot.nv)
    q = qpos.copy()
    q[3:6] = qpos[4:7]
    q[6] = qpos[3]
    v = qvel.copy()
    v[0:3] = base_rotation(q).T @ qvel[0:3]
    return q, v


def pinocchio_to_mujoco_acceleration(
    robot: RobotDescription, q: np.ndarray, v: np.ndarray, a: np.ndarray
) -> np.ndarray:
    """Pinocchio acceleration ``a`` (nv,) at (q, v) -> MuJoCo ``qacc`` (nv,), robot-only layout.

    qacc[0:3] = R (a[0:3] + omega x v[0:3]) (derivative of the world-frame base velocity);
    angular and joint accelerations are unchanged.
    """
    q = _vector("q", q, robot.nq)
    v = _vector("v", v, robot.nv)
    a = _vector("a", a, robot.nv)
    qacc = a.copy()
    qacc[0:3] = base_rotation(q) @ (a[0:3] + np.cross(v[3:6], v[0:3]))
    return qacc


def mujoco_to_pinocchio_acceleration(
    robot: RobotDescription, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray
) -> np.ndarray:
    """MuJoCo ``qacc`` (nv,) at (qpos, qvel) -> Pinocchio acceleration ``a`` (nv,), robot-only layout."""
    q, v = mujoco_to_pinocchio_state(robot, qpos, qvel)
    qacc = _vector("qacc", qacc, robot.nv)
    a = qacc.copy()
    a[0:3] = base_rotation(q).T @ qacc[0:3] - np.cross(v[3:6], v[0:3])
    return a


def velocity_transform(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """Matrix T (nv, nv) with qvel = T v at configuration ``q`` (block diag(R, I)).

    Joint-space quantities map with it: M_pinocchio = T^T M_mujoco T, tau_pinocchio = T^T f_mujoco.
    """
    q = _vector("q", q, robot.nq)
    T = np.eye(robot.nv)
    T[0:3, 0:3] = base_rotation(q)
    return T


@dataclasses.dataclass(frozen=True)
class MujocoIndexMap:
    """Where the robot's coordinates live in a compiled MuJoCo model (possibly with extra bodies).

    Attributes:
        qpos_base: (7,) qpos addresses of the free joint (position, quaternion w, x, y, z).
        qvel_base: (6,) qvel addresses of the free joint.
        qpos_joints: (nu,) qpos address of each actuated joint, Pinocchio order.
        qvel_joints: (nu,) qvel address of each actuated joint, Pinocchio order.
        actuators: (nu,) actuator index driving each actuated joint, Pinocchio order.
        nq_mujoco, nv_mujoco, nu_mujoco: sizes of the MuJoCo model.
    """

    qpos_base: np.ndarray
    qvel_base: np.ndarray
    qpos_joints: np.ndarray
    qvel_joints: np.ndarray
    actuators: np.ndarray
    nq_mujoco: int
    nv_mujoco: int
    nu_mujoco: int

    @classmethod
    def from_model(cls, robot: RobotDescription, mj_model: mujoco.MjModel) -> "MujocoIndexMap":
        """Look the robot's joints and actuators up by name in ``mj_model``."""
        free = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, FREE_JOINT_NAME)
        if free < 0 or mj_model.jnt_type[free] != mujoco.mjtJoint.mjJNT_FREE:
            raise ParameterError(f"the MuJoCo model has no free joint named {FREE_JOINT_NAME!r}")
        qpos_joints, qvel_joints, actuators = [], [], []
        for name in robot.actuated_joint_names:
            joint = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if joint < 0:
                raise ParameterError(f"joint {name!r} of robot '{robot.name}' is not in the MuJoCo model")
            qpos_joints.append(mj_model.jnt_qposadr[joint])
            qvel_joints.append(mj_model.jnt_dofadr[joint])
            matches = [i for i in range(mj_model.nu)
                       if mj_model.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT and mj_model.actuator_trnid[i, 0] == joint]
            if len(matches) != 1:
                raise ParameterError(f"joint {name!r} must be driven by exactly one actuator (found {len(matches)})")
            actuators.append(matches[0])
        qpos0, dof0 = mj_model.jnt_qposadr[free], mj_model.jnt_dofadr[free]
        return cls(
            qpos_base=np.arange(qpos0, qpos0 + 7), qvel_base=np.arange(dof0, dof0 + 6),
            qpos_joints=np.array(qpos_joints), qvel_joints=np.array(qvel_joints), actuators=np.array(actuators),
            nq_mujoco=mj_model.nq, nv_mujoco=mj_model.nv, nu_mujoco=mj_model.nu,
        )

    @property
    def qpos_indices(self) -> np.ndarray:
        """(nq,) qpos addresses of the robot-only layout [base (7), joints (nu)]."""
        return np.concatenate([self.qpos_base, self.qpos_joints])

    @property
    def qvel_indices(self) -> np.ndarray:
        """(nv,) qvel addresses of the robot-only layout [base (6), joints (nu)]."""
        return np.concatenate([self.qvel_base, self.qvel_joints])

    @property
    def is_identity(self) -> bool:
        """True when the MuJoCo model holds exactly the robot, in the robot-only layout."""
        return (self.nq_mujoco == len(self.qpos_indices) and self.nv_mujoco == len(self.qvel_indices)
                and np.array_equal(self.qpos_indices, np.arange(self.nq_mujoco))
                and np.array_equal(self.qvel_indices, np.arange(self.nv_mujoco))
                and np.array_equal(self.actuators, np.arange(self.nu_mujoco)))


def read_mujoco_state(
    robot: RobotDescription, index_map: MujocoIndexMap, mj_data: mujoco.MjData
) -> tuple[np.ndarray, np.ndarray]:
    """The robot's Pinocchio state (q (nq,), v (nv,)) read from ``mj_data`` (new arrays)."""
    return mujoco_to_pinocchio_state(robot, mj_data.qpos[index_map.qpos_indices], mj_data.qvel[index_map.qvel_indices])


def write_mujoco_state(
    robot: RobotDescription, index_map: MujocoIndexMap, mj_data: mujoco.MjData, q: np.ndarray, v: np.ndarray
) -> None:
    """Write the Pinocchio state (q (nq,), v (nv,)) into ``mj_data.qpos``/``qvel`` (other entries kept)."""
    qpos, qvel = pinocchio_to_mujoco_state(robot, q, v)
    mj_data.qpos[index_map.qpos_indices] = qpos
    mj_data.qvel[index_map.qvel_indices] = qvel


def write_mujoco_torque(robot: RobotDescription, index_map: MujocoIndexMap, mj_data: mujoco.MjData, tau: np.ndarray) -> None:
    """Write joint torques ``tau`` (nu,) [N·m], Pinocchio order, into ``mj_data.ctrl``.

    MuJoCo clamps ctrl to the actuators' ctrlrange (±torque_limit) when it steps.
    """
    tau = _vector("tau", tau, robot.nu)
    mj_data.ctrl[index_map.actuators] = tau
