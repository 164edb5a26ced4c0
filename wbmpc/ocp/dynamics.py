"""Contact-constrained forward dynamics of a floating-base robot (Crocoddyl's
DifferentialActionModelContactFwdDynamics), with its analytical derivatives.

For the active contacts (stacked Jacobian Jc (nc, nv), drift a0 (nc,)), the acceleration a and
contact forces λ solve the KKT system

    [M  Jcᵀ] [ a ]   [τ − b]
    [Jc −μI] [−λ ] = [ −a0 ]

where M includes the rotor armature (``model.armature``), b the nonlinear effects and μ ≥ 0 the
contact damping (``contact_damping``, Crocoddyl's ``JMinvJt_damping``, Pinocchio's
``ProximalSettings.mu`` with one proximal iteration). μ = 0 is the rigid contact. With μ > 0

    λ = −(Jc M⁻¹ Jcᵀ + μ I)⁻¹ (a0 + Jc M⁻¹ (τ − b)),   Jc a + a0 = −μ λ:

a compliant contact, whose acceleration gives way by μ per unit of force ([m/s² per N] on force
rows, [rad/s² per N·m] on moment rows), and, where Jc is rank deficient (two flat feet without
ankle roll: an internal squeeze between them loads no joint), the damped least-squares split of
the force the rigid contact leaves undetermined (its component along the null space of Jcᵀ is
−(that component of a0)/μ instead of arbitrary). The derivatives below are those of this
regularised system (both backends).

``damping_lever_arms`` weighs the damping per row: a 6D contact with lever arms r (3,) [m]
(:func:`wbmpc.ocp.contacts.sole_lever_arms`) gets μ on its force rows and μ / r² on its moment
rows, i.e. −μ S⁻² in the KKT matrix with S = diag(1, 1, 1, r): the compliance of a sole made of
four corner point contacts each damped by 4 μ (:class:`~wbmpc.ocp.contacts.SoleCorners`), whose
least-squares split of an undetermined force keeps the moments, hence the centres of pressure,
small (the sole's metric, not the Euclidean one of newtons and newton-metres). Two drifts:

- ``sole_corners=False`` (the "sole" damping): the 6D contact's spatial drift a0, solved as the
  uniform damping of the scaled constraint S Jc a + S a0 = −μ λ̃, λ = S λ̃: the "kkt" backend only
  (``constraintDynamics`` damps every row by one μ);
- ``sole_corners=True`` (the "corners" damping): the four corner point contacts themselves, whose
  classical accelerations add δ(v, ω) to a0 (zero for a sole at rest). The "kkt" backend solves
  S Jc a + S (a0 + δ) = −μ λ̃; the "pinocchio" backend the corners (``constraintDynamics`` with
  one damping 4 μ for every row, so every contact of the node must be such a sole, with Baumgarte
  Kp = 0 and μ > 0), the wrench W = Gᵀ (f_1..f_4): same numbers, and batched.

Two interchangeable backends compute it (they agree to ~1e-13, see the tests):

- ``"pinocchio"`` (default): Pinocchio's ``constraintDynamics`` and
  ``computeConstraintDynamicsDerivatives`` with ``RigidConstraintModel`` s carrying the same
  Baumgarte gains: two binding calls per node, the fast path.
- ``"kkt"``: Crocoddyl's formulas written out, compiled: the contacts' Jacobians, drifts and
  drift derivatives from one pass over the kinematic tree (:class:`~wbmpc.ocp.contacts.ContactSet`,
  :mod:`wbmpc.ocp.kernels.tree`), the damped KKT solve and its derivatives without forming the
  KKT inverse (:mod:`wbmpc.ocp.kernels.kkt`); Pinocchio gives M and b (``computeAllTerms``, or
  ``crba`` and ``nonLinearEffects`` where the costs read other kinematics) and the RNEA
  derivatives with the contact forces as external forces. Also the path for nodes without
  contacts. Models: a free flyer followed by revolute joints.

The "kkt" backend's calc (no derivatives) takes ``rollout_dynamics`` (:data:`ROLLOUT_DYNAMICS`,
:meth:`DifferentialActionModelContactFwdDynamics.calc_dynamics`): "pinocchio" (default) the path
above, the one the derivatives need; "compiled" (a rollout's, opt-in) the KKT solve by triangular
solves on M's tree-sparse Lᵀ D L factors (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`) and,
where the costs read no Pinocchio kinematics, M and b on the contacts' tree
(:mod:`wbmpc.ocp.kernels.joint_space`): the same numbers to rounding (~1e-15), not to the bit.

The "kkt" backend's derivative pass (the calc whose derivatives follow, then
:meth:`~DifferentialActionModelContactFwdDynamics.calc_diff_dynamics`) takes ``derivative_dynamics``
(:data:`DERIVATIVE_DYNAMICS`) at a node with contacts: "pinocchio" (default) the path above (Pinocchio's M and
b, ``computeRNEADerivatives``); "compiled" (opt-in) the RNEA derivatives with the contact forces compiled on the
contacts' tree (:mod:`wbmpc.ocp.kernels.rnea_derivatives`), in one compiled call with the contacts' derivatives and
the KKT derivatives (:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_derivatives`), and, where the costs read
no Pinocchio kinematics, M and b compiled too (:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics`,
the same explicit-inverse solve): the same numbers to rounding (~1e-15), not to the bit.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.ocp.actuation import ActuationFloatingBase
from wbmpc.ocp.contacts import ContactModel6D, ContactSet, ContactSetWork, SoleCorners
from wbmpc.ocp.costs import CostModelSum
from wbmpc.ocp.kernels.contact_dynamics import (
    contact_kkt_derivatives,
    contact_kkt_dynamics,
    contact_kkt_solve,
    contact_kkt_tree_dynamics,
    contact_kkt_tree_dynamics_derivatives,
    contact_kkt_tree_solve,
    kkt_rnea_derivatives,
)
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.kkt import (
    KKTBuffers,
    damped_kkt_derivatives,
    damped_kkt_dynamics,
    damped_kkt_solve,
    velocity_parents,
)
from wbmpc.ocp.kernels.rnea_derivatives import RNEADerivatives
from wbmpc.ocp.kernels.tree import KinematicTree, tree_support
from wbmpc.ocp.residuals.base import DataCollector
from wbmpc.ocp.state import StateMultibody

#: the dynamics of a "kkt" node's calc without derivatives (a rollout): "pinocchio" (Pinocchio's M and b,
#: the explicit-inverse KKT solve the derivatives use) or "compiled" (M and b compiled on the contacts' tree,
#: the KKT solve by triangular solves: the same numbers to rounding)
ROLLOUT_DYNAMICS = ("pinocchio", "compiled")
#: the dynamics of a "kkt" node's derivative pass (its calc with the explicit-inverse solve, then its derivatives):
#: "pinocchio" (Pinocchio's M, b and RNEA derivatives) or "compiled" (the RNEA derivatives and, without Pinocchio
#: kinematics for the costs, M and b compiled on the contacts' tree: the same numbers to rounding)
DERIVATIVE_DYNAMICS = ("pinocchio", "compiled")


class DifferentialActionModelContactFwdDynamics:
    """Continuous-time node: a = f(x, u) under rigid contacts, and the node's running cost l(x, u).

    Args:
        state: the multibody state.
        actuation: floating-base actuation (nu = nv − 6).
        contacts: contact name -> contact model (:mod:`wbmpc.ocp.contacts`); kept sorted by name.
        costs: named cost terms of the node.
        active_contacts: names of the contacts enforced at this node (default: all).
        backend: "pinocchio" (constraint dynamics and its derivatives, default) or "kkt"
            (Crocoddyl's formulas); same results.
        contact_damping: μ of the KKT system above, >= 0 (0: rigid contacts, the default), in
            [m/s² per N] (force rows) and [rad/s² per N·m] (moment rows).
        damping_lever_arms: None (every row damped by μ, Crocoddyl's ``JMinvJt_damping``) or
            contact name -> lever arms (3,) [m] of rectangular soles (6D contacts) whose moment
            rows get μ / r² (module docstring); with backend "pinocchio" every contact of the node,
            each with Kp = 0, and sole_corners.
        sole_corners: those soles are four corner point contacts (their classical drift, module
            docstring); False: 6D contacts with the spatial drift (backend "kkt").
    """

    BACKENDS = ("pinocchio", "kkt")

    def __init__(self, state: StateMultibody, actuation: ActuationFloatingBase, contacts: dict,
                 costs: CostModelSum, active_contacts=None, backend: str = "pinocchio",
                 contact_damping: float = 0.0, damping_lever_arms: dict | None = None, sole_corners: bool = False):
        if backend not in self.BACKENDS:
            raise ParameterError(f"backend={backend!r} is not one of {self.BACKENDS}")
        if isinstance(contact_damping, bool) or not (np.isfinite(contact_damping) and contact_damping >= 0.0):
            raise ParameterError(f"contact_damping={contact_damping!r} must be finite and >= 0")
        self.contact_damping = float(contact_damping)
        self._damping_row_scales = {}  # contact name -> row scales S (nc,) of the damped KKT system
        self._sole_corners = {}  # contact name -> SoleCorners (the same soles)
        for name, arms in (damping_lever_arms or {}).items():
            if name not in contacts or not isinstance(contacts[name], ContactModel6D):
                raise ParameterError(f"damping_lever_arms: {name!r} is not a 6D contact of this node "
                                     f"(contacts: {sorted(contacts)})")
            try:
                corners = SoleCorners(arms)
            except ParameterError as err:
                raise ParameterError(f"damping_lever_arms[{name!r}]: {err}") from None
            self._sole_corners[name] = corners
            self._damping_row_scales[name] = np.concatenate([np.ones(3), corners.lever_arms])
        if self._sole_corners and backend == "pinocchio" and not sole_corners:
            raise ParameterError("damping_lever_arms with backend='pinocchio' need sole_corners=True (constraintDynamics "
                                 "damps every row by one mu; the soles are then four corner point contacts); or use "
                                 "backend='kkt'")
        self.sole_corners = bool(sole_corners) and bool(self._sole_corners)
        # contact name -> SoleCorners whose drift the KKT path adds (the "corners" model), else empty
        self._drift_corners = self._sole_corners if self.sole_corners else {}
        if self._sole_corners and backend == "pinocchio":
            plain = sorted(set(contacts) - set(self._sole_corners))
            if plain:
                raise ParameterError(f"damping_lever_arms with backend='pinocchio' need every contact given lever arms "
                                     f"(constraintDynamics damps every row by one mu; {plain} have none): "
                                     "give them all, or use backend='kkt'")
            if self.contact_damping == 0.0:
                raise ParameterError("damping_lever_arms with backend='pinocchio' need contact_damping > 0 (four rigid "
                                     "corner contacts over-constrain a sole), got 0; or use backend='kkt'")
        self.damping_lever_arms = {name: c.lever_arms.copy() for name, c in self._sole_corners.items()}
        self.backend = backend
        if backend == "kkt" and contacts:
            reason = tree_support(state.pinocchio)
            if reason is not None:
                raise ParameterError(f"backend='kkt' with contacts needs the compiled tree kinematics: {reason}; "
                                     "use backend='pinocchio'")
        self.state = state
        #: the parent of each velocity row (the sparsity of M the rollouts' KKT solve keeps)
        self.velocity_parents = velocity_parents(state.pinocchio)
        self.actuation = actuation
        self.nu = actuation.nu
        self.contacts = dict(sorted(contacts.items()))
        self.costs = costs
        if costs.nu != self.nu:
            raise ParameterError(f"costs were built for nu={costs.nu}, the actuation has nu={self.nu}")
        self._costs_use_force_derivatives = any(
            getattr(item.cost.residual, "uses_contact_forces", False) for item in costs.costs.values())
        # contact name -> its Pinocchio constraints (a sole with lever arms: its four corners)
        self.constraint_models = {
            name: self._sole_corners[name].constraint_models(c) if name in self._sole_corners and backend == "pinocchio"
            else [c.rigid_constraint_model()] for name, c in self.contacts.items()}
        # one proximal iteration from λ = 0: the damped KKT solve (mu = 0: the exact one); the
        # derivatives read settings.iter = 1 and differentiate that same solve. Corners: 4 μ each.
        corner_damping = 4.0 if self._sole_corners and backend == "pinocchio" else 1.0
        self.proximal_settings = pin.ProximalSettings(1e-12, corner_damping * self.contact_damping, 1)
        names = list(self.contacts) if active_contacts is None else list(active_contacts)
        self.set_active_contacts(names)

    def set_active_contacts(self, names) -> None:
        """Enforce exactly the contacts in ``names`` (between solves; never during one)."""
        names = tuple(names)
        if names == getattr(self, "active_key", None):
            return  # unchanged: keep the cached constraint set (datas compare it by identity)
        unknown = set(names) - set(self.contacts)
        if unknown:
            raise ParameterError(f"unknown contact(s) {sorted(unknown)}; known contacts: {list(self.contacts)}")
        active = [name for name in self.contacts if name in set(names)]
        if getattr(self, "active_key", None) == tuple(active):
            return
        self.active_contacts = active
        self.active_key = tuple(self.active_contacts)
        self.nc = sum(self.contacts[name].nc for name in self.active_contacts)
        self.active_constraints = pin.StdVec_RigidConstraintModel()
        self._active_rows = []  # (contact name, rows in the stacked force vector)
        # (contact name, rows of Pinocchio's lambda_c, force map to the contact's force or None)
        self._constraint_rows = []
        row = raw = 0
        for name in self.active_contacts:
            constraints = self.constraint_models[name]
            for constraint in constraints:
                self.active_constraints.append(constraint)
            corners = self._sole_corners.get(name) if len(constraints) > 1 else None
            n_raw = self.contacts[name].nc if corners is None else corners.force_map.shape[1]
            self._constraint_rows.append((name, slice(raw, raw + n_raw), None if corners is None else corners.force_map))
            self._active_rows.append((name, slice(row, row + self.contacts[name].nc)))
            row += self.contacts[name].nc
            raw += n_raw
        #: (nc, rows of lambda_c): the stacked contact forces from Pinocchio's lambda_c (corner
        #: contacts), None when they are the same rows
        self.force_map = None
        if raw != row:
            self.force_map = np.zeros((row, raw))
            for (_, raw_rows, force_map), (_, rows) in zip(self._constraint_rows, self._active_rows):
                self.force_map[rows, raw_rows] = np.eye(rows.stop - rows.start) if force_map is None else force_map
        self._moving_references = [name for name in self.active_contacts if self.contacts[name].gains[0] != 0.0]
        #: the active contacts as arrays for the compiled KKT path (:class:`~wbmpc.ocp.contacts.ContactSet`)
        self.contact_set = ContactSet([(name, self.contacts[name]) for name in self.active_contacts],
                                      self._drift_corners) if self.backend == "kkt" else None
        scaled = [name for name in self.active_contacts if name in self._damping_row_scales]
        #: stacked row scales S (nc,) of the active contacts (ones: uniform damping)
        self.row_scales = np.concatenate(
            [self._damping_row_scales.get(name, np.ones(self.contacts[name].nc)) for name in self.active_contacts]) \
            if scaled else np.ones(self.nc)

    def update_moving_references(self) -> None:
        """Move the Baumgarte position reference of every active contact with Kp > 0 to the
        contact's current reference placement (it may have moved since the last evaluation)."""
        for name in self._moving_references:  # never corners (Kp = 0)
            self.constraint_models[name][0].joint2_placement = self.contacts[name].reference_placement()

    def create_constraint_datas(self, pdata: pin.Data) -> pin.StdVec_RigidConstraintData:
        """Constraint datas of the active contact set, initialised with ``pdata`` for
        ``constraintDynamics`` (the node datas and the batched problem's per-set cache use it)."""
        constraint_datas = pin.StdVec_RigidConstraintData()
        for constraint in self.active_constraints:
            constraint_datas.append(constraint.createData())
        if self.nc:
            pin.initConstraintDynamics(self.state.pinocchio, pdata, self.active_constraints, constraint_datas)
        return constraint_datas

    def createData(self) -> "DifferentialActionDataContactFwdDynamics":
        return DifferentialActionDataContactFwdDynamics(self)

    def calc(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.xout (nv,) accelerations [m/s², rad/s²], contact forces and data.cost.

        With ``u=None`` (terminal node) only the kinematics and the state costs are computed.
        """
        if u is None:
            model = self.state.pinocchio
            pdata = data.select_pinocchio(None)
            pin.computeAllTerms(model, pdata, x[:self.state.nq], x[self.state.nq:])
            data.cost = self.costs.calc(data.costs, x, None, data.shared)
            return
        self.calc_dynamics(data, x, u)
        data.cost = self.costs.calc(data.costs, x, u, data.shared)

    def calc_dynamics(self, data, x: np.ndarray, u: np.ndarray, rollout_dynamics: str = "pinocchio",
                      derivative_dynamics: str = "pinocchio") -> None:
        """The dynamics part of :meth:`calc` (no cost): data.xout (nv,) and the contact forces.

        ``rollout_dynamics`` (:data:`ROLLOUT_DYNAMICS`, the "kkt" backend; ``constraintDynamics``, the
        "pinocchio" backend's nodes with contacts, ignores it):

        - "pinocchio" (default): Pinocchio's M and b (``computeAllTerms``, or ``crba`` and
          ``nonLinearEffects`` without ``data.kinematics_for_costs``) and the explicit-inverse KKT
          solve (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_dynamics`), which leaves the factors
          :meth:`calc_diff_dynamics` reads: every calc whose derivatives follow;
        - "compiled" (a rollout, opt-in): the KKT solve by triangular solves on M's tree-sparse Lᵀ D L
          factors (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`) and, with contacts and without
          ``data.kinematics_for_costs`` (the batched problem), M and b compiled on the contacts' tree
          (:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_solve`; Pinocchio's data is not
          touched): the same numbers to rounding (~1e-15), not to the bit. It leaves nothing for
          :meth:`calc_diff_dynamics`, which then refuses to run until a "pinocchio" calc.

        ``derivative_dynamics`` (:data:`DERIVATIVE_DYNAMICS`, with ``rollout_dynamics="pinocchio"``): "compiled" takes
        M and b compiled on the contacts' tree where "compiled" rollouts do (contacts, no positioned soles, no
        ``data.kinematics_for_costs``: :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics`), then
        the same explicit-inverse solve; elsewhere, and with "pinocchio" (default), it changes nothing.

        Raises:
            ParameterError: ``rollout_dynamics`` is not one of :data:`ROLLOUT_DYNAMICS`, or ``derivative_dynamics``
                not one of :data:`DERIVATIVE_DYNAMICS`.
        """
        derivatives = rollout_dynamics == "pinocchio"  # the solve that leaves the factors of the derivatives
        if not derivatives and rollout_dynamics != "compiled":
            raise ParameterError(f"rollout_dynamics={rollout_dynamics!r} must be one of {ROLLOUT_DYNAMICS}")
        if derivative_dynamics not in DERIVATIVE_DYNAMICS:
            raise ParameterError(f"derivative_dynamics={derivative_dynamics!r} must be one of {DERIVATIVE_DYNAMICS}")
        model = self.state.pinocchio
        nq = self.state.nq
        q, v = x[:nq], x[nq:]
        if self.nc and self.backend == "pinocchio":
            self._calc_constraint_dynamics(data, q, v, u)
            return
        nc = self.nc
        contact_set = self.contact_set
        one_call = nc and not contact_set.has_positioned_soles  # contacts and KKT solve in one compiled call
        # a compiled rollout node (or a compiled derivative pass) whose caller needs no Pinocchio kinematics: M and b
        # compiled in that call too
        tree_terms = one_call and not data.kinematics_for_costs and (not derivatives or derivative_dynamics == "compiled")
        pdata = data.select_pinocchio(None)
        if data.kinematics_for_costs:
            pin.computeAllTerms(model, pdata, q, v)
        elif not tree_terms:  # M (upper triangle) and b only, the same numbers
            pin.crba(model, pdata, q, pin.Convention.WORLD)
            pin.nonLinearEffects(model, pdata, q, v)
        self._share_active_contacts(data)
        self.actuation.calc(data.tau, u)
        data.kkt_for_derivatives = derivatives
        if tree_terms:
            contact_set.refresh_references()
            solved = (contact_kkt_tree_dynamics if derivatives else contact_kkt_tree_solve)(
                x, self.contact_damping, self.row_scales, *contact_set.kernel_arguments,
                *data.contact_kkt_tree_arguments(contact_set.kinds.size, nc, derivatives))
        elif one_call:
            contact_set.refresh_references()
            solved = (contact_kkt_dynamics if derivatives else contact_kkt_solve)(
                x, pdata.M, pdata.nle, self.contact_damping, self.row_scales, *contact_set.kernel_arguments,
                *data.contact_kkt_arguments(contact_set.kinds.size, nc, derivatives))
        else:
            Jc, a0 = data.Jc_all[:nc], data.a0_all[:nc]
            if nc:  # the contacts' Jacobians and drifts (zero joint accelerations), compiled
                contact_set.calc(data.tree, data.contact_work, q, v, data.zero_acceleration, Jc, a0)
            buffers = data.kkt_buffers(nc)
            solved = (damped_kkt_dynamics(pdata.M, pdata.nle, data.tau, Jc, a0, self.row_scales, self.contact_damping,
                                          data.xout, data.force_all[:nc], *buffers.dynamics_buffers()) if derivatives
                      else damped_kkt_solve(pdata.M, pdata.nle, data.tau, Jc, a0, self.row_scales,
                                            self.contact_damping, self.velocity_parents, data.xout,
                                            data.force_all[:nc], *buffers.solve_buffers()))
        if not solved:
            data.xout[:] = np.nan  # M or the contacts' Delassus matrix is not positive definite: the rollout fails
        forces = data.force_all
        for name, rows in self._active_rows:
            data.contacts[name].force[:] = forces[rows]

    def _share_active_contacts(self, data) -> None:
        """Point ``data``'s shared contacts (what the costs read) at the model's active contacts, when they changed."""
        if data.active_contacts is not self.active_contacts:
            data.active_contacts = self.active_contacts
            data.shared.contacts = {name: data.contacts[name] for name in self.active_contacts}

    def _calc_constraint_dynamics(self, data, q, v, u) -> None:
        """Pinocchio backend of calc: constraintDynamics with the active RigidConstraintModels."""
        pdata, constraint_datas = data.select_pinocchio(self)
        self.update_moving_references()
        data.tau[6:] = u
        data.xout[:] = pin.constraintDynamics(self.state.pinocchio, pdata, q, v, data.tau, self.active_constraints,
                                              constraint_datas, self.proximal_settings)
        forces = pdata.lambda_c
        contacts = data.contacts
        for name, rows, force_map in self._constraint_rows:
            if force_map is None:
                contacts[name].force[:] = forces[rows]
            else:
                np.matmul(force_map, forces[rows], out=contacts[name].force)
        self._share_active_contacts(data)

    def _calc_diff_constraint_dynamics(self, data) -> None:
        """Pinocchio backend of calcDiff: computeConstraintDynamicsDerivatives."""
        model = self.state.pinocchio
        nv = self.state.nv
        pdata, constraint_datas = data.select_pinocchio(self)
        ddq_dq, ddq_dv, ddq_dtau, dlambda_dq, dlambda_dv, dlambda_dtau = pin.computeConstraintDynamicsDerivatives(
            model, pdata, self.active_constraints, constraint_datas, self.proximal_settings)
        data.Fx[:, :nv] = ddq_dq
        data.Fx[:, nv:] = ddq_dv
        data.Fu[:] = ddq_dtau[:, 6:]
        if not self._costs_use_force_derivatives:
            return
        for name, rows, force_map in self._constraint_rows:
            cdata = data.contacts[name]
            if force_map is None:
                cdata.df_dx[:, :nv] = dlambda_dq[rows]
                cdata.df_dx[:, nv:] = dlambda_dv[rows]
                cdata.df_du[:] = dlambda_dtau[rows, 6:]
            else:
                np.matmul(force_map, dlambda_dq[rows], out=cdata.df_dx[:, :nv])
                np.matmul(force_map, dlambda_dv[rows], out=cdata.df_dx[:, nv:])
                np.matmul(force_map, dlambda_dtau[rows, 6:], out=cdata.df_du)

    def calcDiff(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.Fx (nv, ndx), Fu (nv, nu), force derivatives and the cost derivatives.

        Uses what :meth:`calc` stored (accelerations, forces, Jc); call calc first.
        """
        if u is not None:
            self.calc_diff_dynamics(data, x, u)
        self.costs.calcDiff(data.costs, x, u, data.shared)
        self._copy_cost_derivatives(data)

    def calc_diff_dynamics(self, data, x: np.ndarray, u: np.ndarray, derivative_dynamics: str = "pinocchio") -> None:
        """The dynamics part of :meth:`calcDiff` (no cost): data.Fx (nv, ndx), data.Fu (nv, nu)
        and the contact forces' derivatives; after :meth:`calc_dynamics` (or calc) at (x, u).

        ``derivative_dynamics`` (:data:`DERIVATIVE_DYNAMICS`; the "kkt" backend's nodes with contacts): "pinocchio"
        (default) Pinocchio's ``computeRNEADerivatives``; "compiled" the RNEA derivatives compiled on the tree the
        calc left, in one compiled call with the contacts' and the KKT derivatives
        (:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_derivatives`; with positioned soles the contacts'
        derivatives apart): the same numbers to rounding. Independent of the calc's ``derivative_dynamics``.

        Raises:
            ParameterError: ``derivative_dynamics`` is not one of :data:`DERIVATIVE_DYNAMICS`, or the last calc was a
                "compiled" rollout's.
        """
        if derivative_dynamics not in DERIVATIVE_DYNAMICS:
            raise ParameterError(f"derivative_dynamics={derivative_dynamics!r} must be one of {DERIVATIVE_DYNAMICS}")
        if self.nc and self.backend == "pinocchio":
            self._calc_diff_constraint_dynamics(data)
            return
        if not data.kkt_for_derivatives:
            raise ParameterError("calc_diff_dynamics after calc_dynamics(..., rollout_dynamics='compiled'): the KKT "
                                 "solve left no factors for the derivatives; call calc_dynamics with "
                                 "rollout_dynamics='pinocchio' first")
        nc = self.nc
        if nc and derivative_dynamics == "compiled":
            self._calc_diff_compiled(data, x)
            return
        model = self.state.pinocchio
        pdata = data.pinocchio
        nq = self.state.nq
        q, v = x[:nq], x[nq:]
        dtau_dq = pdata.dtau_dq
        da0_dx = data.da0_dx_all[:nc]
        for joint in data.fext_joints:
            data.fext[joint] = pin.Force.Zero()
        data.fext_joints = []
        if nc:  # drift derivatives, the contact forces on their joints, the point forces' rotation term
            work = data.contact_work
            extra = self.contact_set.derivatives(data.tree, work, v, data.xout, data.force_all[:nc], da0_dx)
            for c, joint in enumerate(self.contact_set.joint_ids):
                data.fext[joint] = pin.Force(work.fext[c])
                data.fext_joints.append(joint)
        pin.computeRNEADerivatives(model, pdata, q, v, data.xout, data.fext)
        if nc and extra:
            dtau_dq = np.add(pdata.dtau_dq, work.dtau_dq_extra, out=data.dtau_dq)
        df_dx, df_du = data.df_dx_all[:nc], data.df_du_all[:nc]
        damped_kkt_derivatives(dtau_dq, pdata.dtau_dv, da0_dx, self.row_scales, data.Fx, data.Fu, df_dx, df_du,
                               *data.kkt_buffers(nc).derivative_buffers())
        self._copy_force_derivatives(data, df_dx, df_du)

    def calc_and_diff_dynamics(self, data, x: np.ndarray, u: np.ndarray, derivative_dynamics: str = "pinocchio") -> None:
        """:meth:`calc_dynamics` (``rollout_dynamics="pinocchio"``) then :meth:`calc_diff_dynamics` at (x, u) with
        ``derivative_dynamics``; with "compiled" at a node whose calc takes M and b compiled (contacts, no positioned
        soles, no ``data.kinematics_for_costs``) in one compiled call
        (:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics_derivatives`): the same numbers to the
        bit as the two calls.

        Raises:
            ParameterError: ``derivative_dynamics`` is not one of :data:`DERIVATIVE_DYNAMICS`.
        """
        nc = self.nc
        if (derivative_dynamics != "compiled" or not nc or self.backend != "kkt" or data.kinematics_for_costs
                or self.contact_set.has_positioned_soles):
            self.calc_dynamics(data, x, u, "pinocchio", derivative_dynamics)
            self.calc_diff_dynamics(data, x, u, derivative_dynamics)
            return
        data.select_pinocchio(None)
        self._share_active_contacts(data)
        self.actuation.calc(data.tau, u)
        data.kkt_for_derivatives = True
        contact_set = self.contact_set
        contact_set.refresh_references()
        contact_kkt_tree_dynamics_derivatives(x, self.contact_damping, self.row_scales, *contact_set.kernel_arguments,
                                              *data.contact_kkt_tree_derivative_arguments(contact_set.kinds.size, nc))
        forces = data.force_all
        contacts = data.contacts
        df_dx, df_du = data.df_dx_all, data.df_du_all
        for name, rows in self._active_rows:
            cdata = contacts[name]
            cdata.force[:] = forces[rows]
            cdata.df_dx[:] = df_dx[rows]
            cdata.df_du[:] = df_du[rows]

    def _calc_diff_compiled(self, data, x: np.ndarray) -> None:
        """calc_diff_dynamics with derivative_dynamics="compiled" at a node with contacts (the module's docstring)."""
        nc = self.nc
        contact_set = self.contact_set
        k = contact_set.kinds.size
        df_dx, df_du = data.df_dx_all[:nc], data.df_du_all[:nc]
        if not contact_set.has_positioned_soles:
            contact_kkt_derivatives(x, self.row_scales, *contact_set.kernel_arguments,
                                    *data.contact_kkt_derivative_arguments(k, nc))
        else:  # the soles' Kp term (Pinocchio's log6) in the drift derivatives, then the rest in one call
            work = data.contact_work
            v = x[self.state.nq:]
            da0_dx = data.da0_dx_all[:nc]
            extra = contact_set.derivatives(data.tree, work, v, data.xout, data.force_all[:nc], da0_dx)
            tree, (links, rnea) = data.tree, data.derivative_terms()
            kkt_rnea_derivatives(tree.parents, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, links.mass,
                                 links.lever, links.rotational, links.gravity, links.body, contact_set.joints,
                                 work.fext[:k], extra, work.dtau_dq_extra, *rnea.arguments(), data.dtau_dq,
                                 data.dtau_dv, da0_dx, self.row_scales, data.Fx, data.Fu, df_dx, df_du,
                                 *data.kkt_buffers(nc).derivative_buffers())
        self._copy_force_derivatives(data, df_dx, df_du)

    def _copy_force_derivatives(self, data, df_dx: np.ndarray, df_du: np.ndarray) -> None:
        """Each active contact's rows of the stacked force derivatives into its data."""
        for name, rows in self._active_rows:
            cdata = data.contacts[name]
            cdata.df_dx[:] = df_dx[rows]
            cdata.df_du[:] = df_du[rows]

    def contact_force_jacobians(self, data) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Derivatives of each active contact's force (world-aligned for point contacts, as
        ``data.contacts[name].force``) after calcDiff at (x, u): name -> (∂λ/∂x (nc, ndx), ∂λ/∂u (nc, nu))."""
        if self.nc and self.backend == "pinocchio" and not self._costs_use_force_derivatives:
            pdata, constraint_datas = data.select_pinocchio(self)
            _, _, _, dlambda_dq, dlambda_dv, dlambda_dtau = pin.computeConstraintDynamicsDerivatives(
                self.state.pinocchio, pdata, self.active_constraints, constraint_datas, self.proximal_settings)
            return {name: (np.hstack([dlambda_dq[rows], dlambda_dv[rows]]), dlambda_dtau[rows, 6:].copy())
                    if force_map is None else
                    (force_map @ np.hstack([dlambda_dq[rows], dlambda_dv[rows]]), force_map @ dlambda_dtau[rows, 6:])
                    for name, rows, force_map in self._constraint_rows}
        return {name: (data.contacts[name].df_dx.copy(), data.contacts[name].df_du.copy())
                for name in self.active_contacts}

    @staticmethod
    def _copy_cost_derivatives(data) -> None:
        c = data.costs
        data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu = c.Lx, c.Lu, c.Lxx, c.Lxu, c.Luu


class DifferentialActionDataContactFwdDynamics:
    """Per-node buffers of :class:`DifferentialActionModelContactFwdDynamics`."""

    def __init__(self, model: DifferentialActionModelContactFwdDynamics):
        state = model.state
        nv, ndx, nu = state.nv, state.ndx, model.nu
        nc_max = sum(c.nc for c in model.contacts.values())
        self._model = state.pinocchio
        self.velocity_parents = model.velocity_parents
        self._plain_pinocchio = state.pinocchio.createData()
        self._constraint_pinocchio = None  # created on the first constraint-dynamics evaluation
        self.pinocchio = self._plain_pinocchio
        self._constraint_key = None
        self._constraint_datas = None
        self.contacts = {name: c.createData(nu) for name, c in model.contacts.items()}
        self.shared = DataCollector(self.pinocchio, {})
        self.costs = model.costs.createData()
        self.tau = np.zeros(nv)
        self.xout = np.zeros(nv)
        self.Jc_all = np.zeros((nc_max, nv))
        self.a0_all = np.zeros(nc_max)
        self.da0_dx_all = np.zeros((nc_max, ndx))
        self.force_all = np.zeros(nc_max)  # stacked contact forces (kkt backend)
        self.df_dx_all = np.zeros((nc_max, ndx))
        self.df_du_all = np.zeros((nc_max, nu))
        self.dtau_dq = np.zeros((nv, nv))  # RNEA derivative with the point forces' rotation terms
        self.dtau_dv = np.zeros((nv, nv))  # the compiled RNEA derivative's ∂τ/∂v
        self._kkt_buffers: dict[int, KKTBuffers] = {}  # contact rows -> the KKT kernels' buffers
        self._contact_kkt_arguments: dict[tuple, tuple] = {}  # (contacts, rows, derivatives) -> its arguments
        # the compiled tree kinematics the contacts of the kkt backend read, and their buffers (None: the
        # pinocchio backend)
        self.tree = KinematicTree(state.pinocchio) if model.backend == "kkt" and nc_max else None
        self.contact_work = ContactSetWork(len(model.contacts), nv) if self.tree is not None else None
        #: the link inertias of the compiled M and b ("compiled" rollouts without Pinocchio kinematics; built by
        #: the first such calc), M (nv, nv) (upper triangle) and b (nv,) they leave
        self.links: LinkInertias | None = None
        #: the compiled RNEA derivatives' scratch (derivative_dynamics="compiled"; built by the first such calcDiff)
        self.rnea: RNEADerivatives | None = None
        self.M = np.zeros((nv, nv))
        self.nle = np.zeros(nv)
        self.zero_acceleration = np.zeros(nv)
        #: the "kkt" backend's calc leaves Pinocchio's kinematics, CoM and Jacobians for the costs
        #: (``computeAllTerms``); False: only what the dynamics need (M, b), for a caller that evaluates
        #: the costs from its own kinematics (the batched problem)
        self.kinematics_for_costs = True
        #: the last "kkt" calc left M⁻¹, A, Y and J̃ for the derivatives (False: a "compiled" rollout's solve)
        self.kkt_for_derivatives = True
        self._ndx = ndx
        self.active_contacts = None
        self.fext_joints: list[int] = []
        self.fext = pin.StdVec_Force()
        for _ in range(state.pinocchio.njoints):
            self.fext.append(pin.Force.Zero())
        self.Fx = np.zeros((nv, ndx))
        self.Fu = np.zeros((nv, nu))
        self.cost = 0.0
        c = self.costs
        self.Lx, self.Lu, self.Lxx, self.Lxu, self.Luu = c.Lx, c.Lu, c.Lxx, c.Lxu, c.Luu

    def contact_kkt_arguments(self, n_contacts: int, nc: int, derivatives: bool = True) -> tuple:
        """The buffers :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_dynamics` takes after the
        contact set's arrays, for ``n_contacts`` active contacts of ``nc`` stacked rows (tau ... a0, xout,
        the forces, the KKT buffers), made once per size; ``derivatives=False``: those of
        :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_solve` (the velocity rows' parents, the
        KKT solve buffers)."""
        key = (n_contacts, nc, derivatives)
        arguments = self._contact_kkt_arguments.get(key)
        if arguments is None:
            buffers = self.kkt_buffers(nc)
            arguments = self._contact_kkt_arguments[key] = (
                *self._tree_arguments(), *self._contact_frame_arguments(n_contacts, nc),
                *(buffers.dynamics_buffers() if derivatives else (self.velocity_parents, *buffers.solve_buffers())))
        return arguments

    def contact_kkt_tree_arguments(self, n_contacts: int, nc: int, derivatives: bool = False) -> tuple:
        """The buffers :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_solve` takes after the
        contact set's arrays, for ``n_contacts`` active contacts of ``nc`` stacked rows (tau ... J, the link
        inertias, M, b, the contacts' frame kinematics, Jc, a0, xout, the forces, the KKT solve buffers), made
        once per size; ``derivatives=True``: those of
        :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics` (the KKT dynamics buffers last)."""
        key = (n_contacts, nc, "tree", derivatives)
        arguments = self._contact_kkt_arguments.get(key)
        if arguments is None:
            if self.links is None:
                self.links = LinkInertias(self._model)
            buffers = self.kkt_buffers(nc)
            arguments = self._contact_kkt_arguments[key] = (
                *self._tree_arguments(), *self.links.arguments(), self.M, self.nle,
                *self._contact_frame_arguments(n_contacts, nc),
                *(buffers.dynamics_buffers() if derivatives else (self.velocity_parents, *buffers.solve_buffers())))
        return arguments

    def derivative_terms(self) -> tuple[LinkInertias, RNEADerivatives]:
        """The link inertias and the scratch of the compiled RNEA derivatives (made on first use)."""
        if self.links is None:
            self.links = LinkInertias(self._model)
        if self.rnea is None:
            self.rnea = RNEADerivatives(self._model)
        return self.links, self.rnea

    def contact_kkt_tree_derivative_arguments(self, n_contacts: int, nc: int) -> tuple:
        """The buffers :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics_derivatives` takes after
        the contact set's arrays, for ``n_contacts`` active contacts of ``nc`` stacked rows, made once per size."""
        key = (n_contacts, nc, "tree derivatives")
        arguments = self._contact_kkt_arguments.get(key)
        if arguments is None:
            links, rnea = self.derivative_terms()
            work, k = self.contact_work, n_contacts
            Minv, A, Y, J_scaled, *rest = self.kkt_buffers(nc).derivative_buffers()
            arguments = self._contact_kkt_arguments[key] = (
                *self.contact_kkt_tree_arguments(n_contacts, nc, True), work.v_dq[:k], work.a_dq[:k], work.a_dv[:k],
                self.da0_dx_all[:nc], work.fext[:k], work.dtau_dq_extra, rnea.variation, rnea.motions, self.dtau_dq,
                self.dtau_dv, self.Fx, self.Fu, self.df_dx_all[:nc], self.df_du_all[:nc], *rest)
        return arguments

    def contact_kkt_derivative_arguments(self, n_contacts: int, nc: int) -> tuple:
        """The buffers :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_derivatives` takes after the contact
        set's arrays, for ``n_contacts`` active contacts of ``nc`` stacked rows (xout ... AtYA), made once per size."""
        key = (n_contacts, nc, "derivatives")
        arguments = self._contact_kkt_arguments.get(key)
        if arguments is None:
            links, rnea = self.derivative_terms()
            tree, work, k = self.tree, self.contact_work, n_contacts
            arguments = self._contact_kkt_arguments[key] = (
                self.xout, self.force_all[:nc], tree.parents, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J,
                work.oRf[:k], work.opf[:k], work.fJf[:k], work.velocity[:k], work.v_dq[:k], work.a_dq[:k],
                work.a_dv[:k], self.da0_dx_all[:nc], work.fext[:k], work.dtau_dq_extra, links.mass, links.lever,
                links.rotational, links.gravity, links.body, *rnea.arguments(), self.dtau_dq, self.dtau_dv, self.Fx,
                self.Fu, self.df_dx_all[:nc], self.df_du_all[:nc], *self.kkt_buffers(nc).derivative_buffers())
        return arguments

    def _tree_arguments(self) -> tuple:
        """The one-call contact kernels' arguments after the contact set's arrays, up to the tree's Jacobian
        columns: tau, the zero accelerations and :class:`~wbmpc.ocp.kernels.tree.KinematicTree`'s arrays."""
        tree = self.tree
        return (self.tau, self.zero_acceleration, tree.parents, tree.placement_rotation, tree.placement_translation,
                tree.axes, tree.idx_q, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J)

    def _contact_frame_arguments(self, n_contacts: int, nc: int) -> tuple:
        """The one-call contact kernels' contact frame kinematics of ``n_contacts`` contacts, Jc, a0 of ``nc``
        rows, the accelerations and the forces (the arguments from oRf to force)."""
        work, k = self.contact_work, n_contacts
        return (work.oRf[:k], work.opf[:k], work.fJf[:k], work.velocity[:k], work.acceleration[:k], self.Jc_all[:nc],
                self.a0_all[:nc], self.xout, self.force_all[:nc])

    def kkt_buffers(self, nc: int) -> KKTBuffers:
        """The buffers of the KKT kernels for ``nc`` contact rows (made on first use; the last
        dynamics at that size leave M⁻¹, A and Y there for the derivatives)."""
        buffers = self._kkt_buffers.get(nc)
        if buffers is None:
            buffers = self._kkt_buffers[nc] = KKTBuffers(self.xout.size, nc, self._ndx)
        return buffers

    def select_pinocchio(self, model):
        """Pinocchio data of the current evaluation, made current for the costs.

        ``model=None`` (KKT path, flight and terminal nodes): a data never used by constraint
        dynamics (after ``constraintDynamics`` a data gives wrong RNEA derivatives). Otherwise
        the node's constraint-dynamics data and the RigidConstraintData of ``model``'s active
        contact set, re-initialised only when the set changed (a few nodes per MPC tick).
        """
        if model is None:
            pdata = self._plain_pinocchio
        else:
            pdata = self._constraint_pinocchio
            if pdata is None:
                pdata = self._constraint_pinocchio = self._model.createData()
            if self._constraint_key != model.active_key:
                self._constraint_datas = model.create_constraint_datas(pdata)
                self._constraint_key = model.active_key
        if self.pinocchio is not pdata:
            self.pinocchio = pdata
            self.shared.pinocchio = pdata
        return pdata if model is None else (pdata, self._constraint_datas)
