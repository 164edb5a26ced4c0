"""The measured ALIP state from the whole body: the angular momentum about the stance contact point, exactly.

The ALIP planner (:mod:`sequencer.alip`, seed 001) needs L, the robot's angular momentum about the stance
contact point. The paper approximates it from the CoM state (eqs. 14-15)::

    L_y ≈ m p_z v_x − m p_x v_z + I_y ω_y,     L_x ≈ −m p_z v_y + m p_y v_z + I_x ω_x

with p = c − p_contact. The exact value follows from Pinocchio's centroidal momentum h_G = (m v_G, L_G)
(``pinocchio.computeCentroidalMomentum``: about the CoM G, axes of the world frame) by moving the moment
point to the contact::

    L_contact = L_G + (c − p_contact) × m v_G

(a momentum's moment about a fixed point). The CoM terms are the paper's r × m v exactly, so the
approximation without the I ω terms (what :meth:`sequencer.alip.model.AlipModel.state_from_velocity` and the
planner use) is exact if and only if the centroidal angular momentum L_G is zero; with the I ω terms it is
exact when the robot moves as one rigid body and I is its locked (composite) inertia about G. Limb motion
(swinging legs and arms) puts momentum into L_G that neither term sees: ``tests/test_walking_alip_state.py``
measures it on the G1.

Frames: every vector here is in the world frame (Pinocchio's convention: q the free flyer's world pose,
v its velocity in the base frame) unless said; :func:`measured_alip_state` turns it into the ALIP state of
the stance's heading frame (world rotated about z by the stance yaw), (p_x, L_y, p_y, L_x). The walking
controller's planning stage (:class:`wbmpc.walking.planning.PlanningStage`) hands :func:`contact_angular_momentum`
to the ALIP planner (``[footstep_planner] angular_momentum = "exact"`` of the walking preset).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from sequencer.alip.model import AlipModel
from sequencer.alip.planner import alip_state_about_contact
from sequencer.planner import StanceState
from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class CentroidalMeasurement:
    """The whole body's centroidal state at one instant and its angular momentum about a contact point.

    Attributes:
        mass: total mass m [kg].
        com: CoM position c [m], world frame, shape (3,).
        com_velocity: CoM velocity v_G [m/s], world frame, shape (3,).
        angular_momentum_com: centroidal angular momentum L_G about the CoM [kg·m²/s], world axes, shape (3,).
        contact_point: the stance contact point p_contact [m], world frame, shape (3,).
        angular_momentum_contact: L_contact = L_G + (c − p_contact) × m v_G [kg·m²/s], world axes, shape (3,).
        locked_inertia: composite rigid-body inertia about the CoM I_G [kg·m²], world axes, shape (3, 3)
            (``pinocchio.ccrba``; the I of eqs. 14-15 read as the whole robot's).
    """

    mass: float
    com: np.ndarray
    com_velocity: np.ndarray
    angular_momentum_com: np.ndarray
    contact_point: np.ndarray
    angular_momentum_contact: np.ndarray
    locked_inertia: np.ndarray

    @property
    def approximate_angular_momentum_contact(self) -> np.ndarray:
        """The paper's eqs. 14-15 without the I ω terms in 3D: (c − p_contact) × m v_G [kg·m²/s], world, shape (3,)."""
        return np.cross(self.com - self.contact_point, self.mass * self.com_velocity)


def contact_angular_momentum(model: pin.Model, data: pin.Data, q, v, contact_point) -> CentroidalMeasurement:
    """Centroidal momentum of configuration ``q`` (nq,) and velocity ``v`` (nv,) (Pinocchio's convention) and the
    exact angular momentum about ``contact_point`` (3,) [m], world frame. Writes into ``data``."""
    q, v = np.asarray(q, dtype=float).reshape(-1), np.asarray(v, dtype=float).reshape(-1)
    contact = np.asarray(contact_point, dtype=float).reshape(-1)
    if q.shape != (model.nq,) or v.shape != (model.nv,):
        raise ParameterError(f"q, v must have shapes ({model.nq},), ({model.nv},); got {q.shape}, {v.shape}")
    if contact.shape != (3,) or not np.all(np.isfinite(contact)):
        raise ParameterError(f"contact_point={contact_point!r} must be 3 finite numbers [m] (world frame)")
    pin.ccrba(model, data, q, v)  # Ag, hg (about the CoM, world axes), Ig, com
    mass = float(data.Ig.mass)
    com = data.com[0].copy()
    linear = data.hg.linear.copy()  # m v_G
    angular = data.hg.angular.copy()  # L_G
    return CentroidalMeasurement(
        mass=mass, com=com, com_velocity=linear / mass, angular_momentum_com=angular, contact_point=contact.copy(),
        angular_momentum_contact=angular + np.cross(com - contact, linear),
        locked_inertia=data.Ig.inertia.copy(),
    )


def measured_alip_state(measurement: CentroidalMeasurement, stance_yaw: float = 0.0,
                        approximate: bool = False) -> np.ndarray:
    """ALIP state (p_x, L_y, p_y, L_x) of a measurement in the stance's heading frame (yaw ``stance_yaw`` [rad]),
    about its contact point, shape (4,): exact (L_contact) or, with ``approximate``, the paper's eqs. 14-15
    without the I ω terms at the measured CoM height above the contact."""
    stance = StanceState("left", measurement.contact_point[:2], float(stance_yaw), 0.0)  # the foot's name is unused
    model = AlipModel(measurement.mass, max(measurement.com[2] - measurement.contact_point[2], 1e-9))
    if approximate:
        return alip_state_about_contact(model, stance, measurement.com, measurement.com_velocity,
                                        p_z=measurement.com[2] - measurement.contact_point[2])
    return alip_state_about_contact(model, stance, measurement.com, measurement.com_velocity,
                                    measurement.angular_momentum_contact)
