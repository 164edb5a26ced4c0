"""Build the Crocoddyl twin of a wbmpc ShootingProblem (test and benchmark oracle only).

The library never imports Crocoddyl; tests and ``wbmpc bench ddp`` use this module to solve the
very same problem with Crocoddyl 3.2 and compare node by node. Every wbmpc component maps to
its Crocoddyl counterpart:

=============================  ==========================================================
wbmpc                          Crocoddyl
=============================  ==========================================================
StateMultibody                 StateMultibody
ActuationFloatingBase          ActuationModelFloatingBase
ContactModel3D (LWA)           ContactModel3D(..., LOCAL_WORLD_ALIGNED, gains)
ContactModel6D (LOCAL)         ContactModel6D(..., LOCAL, gains)
ResidualState                  ResidualModelState
ResidualControl                ResidualModelControl
ResidualFrameTranslation       ResidualModelFrameTranslation
ResidualFrameHeight            ResidualModelFrameTranslation + weights (0, 0, 1)
ResidualFrameVelocity          ResidualModelFrameVelocity(..., LOCAL)
ResidualCoMPosition            ResidualModelCoMPosition
ResidualContactForce           ResidualModelContactForce
ResidualFrictionCone           ResidualModelContactFrictionCone
ResidualWrenchCone             ResidualModelContactWrenchCone (WrenchCone: the same rows, reordered)
ResidualFrameRotation          ResidualModelFrameRotation
ActivationQuad/WeightedQuad    ActivationModelQuad/WeightedQuad
ActivationQuadraticBarrier     ActivationModelQuadraticBarrier
IntegratedActionModelEuler     IntegratedActionModelEuler
=============================  ==========================================================
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.activations import ActivationQuad, ActivationQuadraticBarrier, ActivationWeightedQuad
from wbmpc.ocp.contacts import ContactModel3D, ContactModel6D
from wbmpc.ocp.problem import ShootingProblem
from wbmpc.ocp.residuals import (
    ResidualCoMPosition,
    ResidualContactForce,
    ResidualControl,
    ResidualFrameHeight,
    ResidualFrameRotation,
    ResidualFrameTranslation,
    ResidualFrameVelocity,
    ResidualFrictionCone,
    ResidualState,
    ResidualWrenchCone,
)


def _crocoddyl():
    import crocoddyl

    return crocoddyl


class NoCrocoddylTwin(TypeError):
    """A term, contact or damping of the wbmpc problem that Crocoddyl has no model of (the message names it):
    the problem cannot be mirrored, so there is no Crocoddyl baseline of it."""


class CrocoddylMirror:
    """Crocoddyl models sharing the Pinocchio model of a wbmpc problem.

    ``mirror.problem`` is a ``crocoddyl.ShootingProblem`` equal to ``problem``;
    :meth:`update` refreshes contact status and references after the wbmpc problem changed.
    """

    def __init__(self, problem: ShootingProblem):
        croc = _crocoddyl()
        self.source = problem
        self.model = problem.state.pinocchio
        self.state = croc.StateMultibody(self.model)
        self.actuation = croc.ActuationModelFloatingBase(self.state)
        self.running_models = [self._node(m) for m in problem.running_models]
        self.terminal_model = self._node(problem.terminal_model)
        self.problem = croc.ShootingProblem(problem.x0.copy(), self.running_models, self.terminal_model)
        self.problem.nthreads = 1  # single thread, like wbmpc (its OpenMP default spins on busy cores)
        self.update()

    # ----------------------------------------------------------------- translation
    def _activation(self, activation):
        croc = _crocoddyl()
        if isinstance(activation, ActivationWeightedQuad):
            return croc.ActivationModelWeightedQuad(activation.weights.copy())
        if isinstance(activation, ActivationQuadraticBarrier):
            return croc.ActivationModelQuadraticBarrier(croc.ActivationBounds(activation.lower, activation.upper))
        if isinstance(activation, ActivationQuad):
            return croc.ActivationModelQuad(activation.nr)
        raise NoCrocoddylTwin(f"no Crocoddyl twin for activation {type(activation).__name__}")

    def _cost(self, cost, nu: int):
        croc = _crocoddyl()
        residual = cost.residual
        activation = self._activation(cost.activation)
        if isinstance(residual, ResidualState):
            r = croc.ResidualModelState(self.state, residual.reference.copy(), nu)
        elif isinstance(residual, ResidualControl):
            r = croc.ResidualModelControl(self.state, residual.reference.copy())
        elif isinstance(residual, ResidualFrameTranslation):
            r = croc.ResidualModelFrameTranslation(self.state, residual.frame_id, residual.reference.copy(), nu)
        elif isinstance(residual, ResidualFrameHeight):
            r = croc.ResidualModelFrameTranslation(self.state, residual.frame_id, np.array([0.0, 0.0, residual.reference]), nu)
            weights = np.array([0.0, 0.0, 1.0])
            if isinstance(cost.activation, ActivationWeightedQuad):
                weights = weights * cost.activation.weights[0]
            activation = croc.ActivationModelWeightedQuad(weights)
        elif isinstance(residual, ResidualFrameVelocity):
            r = croc.ResidualModelFrameVelocity(self.state, residual.frame_id, pin.Motion(residual.reference),
                                                pin.LOCAL, nu)
        elif isinstance(residual, ResidualCoMPosition):
            r = croc.ResidualModelCoMPosition(self.state, residual.reference.copy(), nu)
        elif isinstance(residual, ResidualContactForce):
            frame_id = self._contact_frames[residual.contact_name]
            nc = residual.nr
            force = pin.Force(residual.reference) if nc == 6 else pin.Force(residual.reference, np.zeros(3))
            r = croc.ResidualModelContactForce(self.state, frame_id, force, nc, nu)
        elif isinstance(residual, ResidualFrictionCone):
            frame_id = self._contact_frames[residual.contact_name]
            cone = croc.FrictionCone(np.eye(3), residual.mu, residual.nr - 1, True)
            r = croc.ResidualModelContactFrictionCone(self.state, frame_id, cone, nu)
            activation = croc.ActivationModelQuadraticBarrier(croc.ActivationBounds(cone.lb, cone.ub))
        elif isinstance(residual, ResidualWrenchCone):
            if residual.center_x != 0.0:
                raise NoCrocoddylTwin(f"Crocoddyl's WrenchCone is centred on its contact frame; this one's centre is "
                                      f"center_x={residual.center_x} m along it")
            frame_id = self._contact_frames[residual.contact_name]
            cone = croc.WrenchCone(np.eye(3), residual.mu, np.array([2.0 * residual.half_length, 2.0 * residual.half_width]),
                                   4, True)
            r = croc.ResidualModelContactWrenchCone(self.state, frame_id, cone, nu)
            activation = croc.ActivationModelQuadraticBarrier(croc.ActivationBounds(cone.lb, cone.ub))
        elif isinstance(residual, ResidualFrameRotation):
            r = croc.ResidualModelFrameRotation(self.state, residual.frame_id, residual.reference.copy(), nu)
        else:
            raise NoCrocoddylTwin(f"no Crocoddyl twin for residual {type(residual).__name__}")
        return croc.CostModelResidual(self.state, activation, r), r

    def _node(self, node):
        croc = _crocoddyl()
        dam = node.differential
        nu = dam.nu
        self._contact_frames = {name: c.frame_id for name, c in dam.contacts.items()}
        contacts = croc.ContactModelMultiple(self.state, nu)
        for name, c in dam.contacts.items():
            gains = np.array(c.gains)
            if isinstance(c, ContactModel3D):
                model = croc.ContactModel3D(self.state, c.frame_id, c.reference.copy(), pin.LOCAL_WORLD_ALIGNED, nu, gains)
            elif isinstance(c, ContactModel6D):
                model = croc.ContactModel6D(self.state, c.frame_id, pin.SE3(c.reference), pin.LOCAL, nu, gains)
            else:
                raise NoCrocoddylTwin(f"no Crocoddyl twin for contact {type(c).__name__}")
            contacts.addContact(name, model, True)
        costs = croc.CostModelSum(self.state, nu)
        residuals = {}
        for name, item in dam.costs.costs.items():
            cost, residual = self._cost(item.cost, nu)
            costs.addCost(name, cost, item.weight, item.active)
            residuals[name] = residual
        if dam._damping_row_scales:  # Crocoddyl damps every row by one JMinvJt_damping
            raise NoCrocoddylTwin("no Crocoddyl twin for a sole-weighted contact damping (contact_damping_moments='sole')")
        cdam = croc.DifferentialActionModelContactFwdDynamics(self.state, self.actuation, contacts, costs,
                                                              dam.contact_damping, True)
        iam = croc.IntegratedActionModelEuler(cdam, node.dt)
        iam._wbmpc_residuals = residuals  # keep the references reachable for update()
        return iam

    # ----------------------------------------------------------------- refresh
    def update(self) -> None:
        """Copy x0, contact status, cost status and references from the wbmpc problem."""
        src = self.source
        self.problem.x0 = src.x0.copy()
        pairs = list(zip(src.running_models, self.running_models)) + [(src.terminal_model, self.terminal_model)]
        for node, iam in pairs:
            dam, cdam = node.differential, iam.differential
            for name in dam.contacts:
                cdam.contacts.changeContactStatus(name, name in dam.active_contacts)
            for name, item in dam.costs.costs.items():
                cdam.costs.changeCostStatus(name, item.active)
                residual = item.cost.residual
                twin = iam._wbmpc_residuals[name]
                if isinstance(residual, ResidualFrameHeight):
                    twin.reference = np.array([0.0, 0.0, residual.reference])
                elif isinstance(residual, ResidualContactForce):
                    ref = residual.reference
                    twin.reference = pin.Force(ref) if ref.size == 6 else pin.Force(ref, np.zeros(3))
                elif isinstance(residual, ResidualFrameVelocity):
                    twin.reference = pin.Motion(residual.reference)
                elif isinstance(residual, ResidualFrameRotation):
                    twin.reference = residual.reference.copy()
                elif isinstance(residual, (ResidualFrameTranslation, ResidualCoMPosition, ResidualState, ResidualControl)):
                    twin.reference = residual.reference.copy()
