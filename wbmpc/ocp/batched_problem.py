"""A shooting problem evaluated over the whole horizon at once: the same function as
:class:`~wbmpc.ocp.problem.ShootingProblem`, with the per-node Python work cut to the Pinocchio calls.

The node-by-node pipeline (action model -> differential model -> cost sum -> residuals) makes
about 25 Python calls per node and keeps one Pinocchio data per node; over a 100-node horizon that
glue, and the cache misses of 100 data objects, cost twice Pinocchio's own work. This problem
reads the same node models (contacts, cost terms, weights, references) and evaluates them as:

- a Python loop over the nodes doing only what needs Pinocchio: contact-constrained dynamics
  (``constraintDynamics`` with the node's contact set, or ABA without contacts) and, in
  :meth:`calcDiff`, its derivatives; one Pinocchio data per contact set, so it stays in cache;
  the Euler step (and, in the rollout, the feedback update) are compiled (:mod:`wbmpc.ocp.kernels.lie`);
- compiled passes over all nodes for everything else: the frame kinematics of the active frame
  terms (:mod:`wbmpc.ocp.kernels.frames`), residual rows, activations, cost values and Gauss-Newton
  derivatives (assembled per residual kind), the Lie-group Jacobians of the Euler step and of the
  state residual, Euler transition Jacobians, the dt scaling.

The compiled Jacobian of exp6 is exact where Pinocchio's ``Jexp6`` loses up to ~6e-8 (base
rotations of 1e-5..1e-2 rad per node, see :mod:`wbmpc.ocp.kernels.lie`), so the two evaluations agree
to rounding except there, by that much.

Supported nodes: :class:`~wbmpc.ocp.integrator.IntegratedActionModelEuler` over
:class:`~wbmpc.ocp.dynamics.DifferentialActionModelContactFwdDynamics` (Pinocchio backend) on a
free-flyer robot with 1-dof joints, every running node with the same cost terms (switched on
and off per node), each term one of: state (:class:`~wbmpc.ocp.residuals.ResidualState`), control
(:class:`~wbmpc.ocp.residuals.ResidualControl`), frame height and frame translation. The terminal
node, any model, is evaluated node-wise. :func:`batched_evaluation_support` says whether a
problem qualifies and why not; :class:`~wbmpc.walking.WalkingOCP` uses this problem when it does.

After :meth:`calc` / :meth:`calcDiff` the stacked arrays (``xnext``, ``Fx``, ``Fu``, ``Lx``, ...,
which the node datas view) and :meth:`node_costs` / :meth:`term_costs` hold the results; the
node datas' other buffers (accelerations, forces, residuals) are not filled.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.errors import ParameterError
from wbmpc.ocp.dynamics import DifferentialActionModelContactFwdDynamics
from wbmpc.ocp.integrator import IntegratedActionModelEuler
from wbmpc.ocp.kernels.costs import cost_rows_value
from wbmpc.ocp.kernels.feedback import rollout_node_start
from wbmpc.ocp.kernels.frames import FrameKinematics, frame_kinematics_support
from wbmpc.ocp.kernels.integration import euler_transition_jacobians, free_flyer_euler_step
from wbmpc.ocp.kernels.lie import free_flyer_dintegrate, free_flyer_state_difference, free_flyer_state_jacobians
from wbmpc.ocp.problem import RolloutError, ShootingProblem
from wbmpc.ocp.residuals import ResidualControl, ResidualFrameHeight, ResidualFrameTranslation, ResidualState

# residual kinds of the compiled pass
STATE, CONTROL, FRAME_HEIGHT, FRAME_TRANSLATION = 0, 1, 2, 3
_KINDS = {ResidualState: STATE, ResidualControl: CONTROL, ResidualFrameHeight: FRAME_HEIGHT,
          ResidualFrameTranslation: FRAME_TRANSLATION}


def batched_evaluation_support(problem: ShootingProblem) -> str | None:
    """None if ``problem`` can be evaluated by :class:`BatchedShootingProblem`, else the reason."""
    state = problem.state
    if not state._compiled_difference:
        return "the robot is not a free-flyer root followed by 1-dof joints"
    reason = frame_kinematics_support(state.pinocchio)
    if reason is not None:
        return reason
    names = None
    for k, model in enumerate(problem.running_models):
        if type(model) is not IntegratedActionModelEuler:
            return f"running node {k} is a {type(model).__name__}, not an IntegratedActionModelEuler"
        dam = model.differential
        if type(dam) is not DifferentialActionModelContactFwdDynamics or dam.backend != "pinocchio":
            return f"running node {k} is not contact forward dynamics with the Pinocchio backend"
        items = dam.costs.costs
        if names is None:
            names = list(items)
        elif list(items) != names:
            return f"running node {k} has the cost terms {list(items)}, node 0 has {names}"
        for name, item in items.items():
            residual_type = type(item.cost.residual)
            if residual_type not in _KINDS:
                return f"cost {name!r} has a {residual_type.__name__} residual (batched: {[t.__name__ for t in _KINDS]})"
    return None


class BatchedShootingProblem(ShootingProblem):
    """Drop-in :class:`~wbmpc.ocp.problem.ShootingProblem` with horizon-batched evaluation.

    Same constructor; raises :class:`~wbmpc.errors.ParameterError` when the nodes are not
    supported (see :func:`batched_evaluation_support`). Call :meth:`sync` after changing the node
    models (contact sets, cost activity, weights, references) and before the next evaluation;
    :meth:`~wbmpc.walking.WalkingOCP.update` does it.
    """

    def __init__(self, x0: np.ndarray, running_models: list, terminal_model):
        super().__init__(x0, running_models, terminal_model)
        reason = batched_evaluation_support(self)
        if reason is not None:
            raise ParameterError(f"running_models cannot be evaluated batched: {reason}")
        state = self.state
        N, nv, nx, ndx, nu = self.T, state.nv, state.nx, state.ndx, self.nu
        self._pin_model = state.pinocchio
        first = self.running_models[0].differential.costs
        first_data = self.running_datas[0].differential.costs
        self._term_names = list(first.costs)
        n_terms = len(self._term_names)
        nr = first_data.r.size
        # term layout (identical at every running node): kind, first row, frame slot
        self._term_kind = np.zeros(n_terms, dtype=np.int64)
        self._term_row = np.zeros(n_terms, dtype=np.int64)
        self._term_slot = np.full(n_terms, -1, dtype=np.int64)
        frame_ids: list[int] = []
        for j, (name, item) in enumerate(first.costs.items()):
            residual = item.cost.residual
            self._term_kind[j] = _KINDS[type(residual)]
            self._term_row[j] = first_data.rows[name].start
            if self._term_kind[j] in (FRAME_HEIGHT, FRAME_TRANSLATION):
                if residual.frame_id not in frame_ids:
                    frame_ids.append(residual.frame_id)
                self._term_slot[j] = frame_ids.index(residual.frame_id)
        self._kinematics = FrameKinematics(self._pin_model, frame_ids) if frame_ids else None
        self._state_terms = [j for j in range(n_terms) if self._term_kind[j] == STATE]
        self._row_term = first_data.row_term.copy()
        self._w = np.stack([d.differential.costs.w for d in self.running_datas])
        self._lb = np.stack([d.differential.costs.lb for d in self.running_datas])
        self._ub = np.stack([d.differential.costs.ub for d in self.running_datas])
        self._dt = np.array([m.dt for m in self.running_models])
        # per-node configuration, refreshed by sync()
        self._term_scale = np.zeros((N, n_terms))
        self._reference = np.zeros((N, n_terms, max(nx, nu, 3)))
        self._frame_needed = np.zeros((N, max(len(frame_ids), 1)), dtype=np.bool_)  # frames of active terms
        # per node: (constraint models or None, Pinocchio data, constraint datas, proximal settings)
        self._node_dynamics: list = [None] * N
        self._contact_sets: dict = {}
        self._node_terms = None
        # evaluation buffers
        self._tau = np.zeros(nv)
        self._euler_dx = np.zeros((N, ndx))
        self._da_dx = np.zeros((N, nv, ndx))
        self._da_du = np.zeros((N, nv, nu))
        self._J_q = np.zeros((nv, nv))  # scratch of the compiled pass
        self._J_dq = np.zeros((nv, nv))
        self._state_residual = np.zeros((N, n_terms, ndx))
        self._state_jacobian = np.zeros((N, n_terms, nv, nv))
        self._frame_position = np.zeros((N, max(len(frame_ids), 1), 3))
        self._frame_jacobian = np.zeros((N, max(len(frame_ids), 1), 3, nv))
        self._node_cost = np.zeros(N)
        self._term_cost = np.zeros((N, n_terms))
        self._scratch_r = np.zeros(nr)
        self._difference_ok = np.ones(N, dtype=np.bool_)
        self._no_gaps = np.zeros((N + 1, ndx))
        # dynamics prepared ahead for the next calcDiff (see prepare_dynamics)
        self._prepared = np.zeros(N, dtype=np.bool_)
        self._prepared_x = np.zeros((N, nx))
        self._prepared_u = np.zeros((N, nu))
        self._prepared_key: list = [None] * N
        self._prepared_xnext = np.zeros((N, nx))
        self._prepared_euler_dx = np.zeros((N, ndx))
        self._prepared_da_dx = np.zeros((N, nv, ndx))
        self._prepared_da_du = np.zeros((N, nv, nu))
        self.prepared_used = 0  # nodes the last calcDiff took from the preparation
        self.sync()

    # ----------------------------------------------------------------- configuration
    def sync(self) -> None:
        """Read the node models' contact sets, cost activity, weights and references."""
        nx, nu = self.nx, self.nu
        scale, reference = self._term_scale, self._reference
        if self._node_terms is None:  # (j, kind, item) per node, in term order
            self._node_terms = [
                [(j, int(self._term_kind[j]), m.differential.costs.costs[name])
                 for j, name in enumerate(self._term_names)] for m in self.running_models]
        for k, model in enumerate(self.running_models):
            row_scale = scale[k]
            row_reference = reference[k]
            for j, kind, item in self._node_terms[k]:
                if not item.active or item.weight == 0.0:
                    row_scale[j] = 0.0
                    continue
                row_scale[j] = item.weight
                residual = item.cost.residual
                if kind == FRAME_HEIGHT:
                    row_reference[j, 0] = residual.reference
                elif kind == FRAME_TRANSLATION:
                    row_reference[j, :3] = residual.reference
                elif kind == STATE:
                    row_reference[j, :nx] = residual.reference
                else:
                    row_reference[j, :nu] = residual.reference
            self._node_dynamics[k] = self._dynamics_of(model.differential)
        self._node_contact_keys = [m.differential.active_key for m in self.running_models]
        self._refresh_frame_needed()

    def term_index(self, name: str) -> int:
        """Column of the running cost term ``name`` in the batched arrays."""
        try:
            return self._term_names.index(name)
        except ValueError:
            raise ParameterError(f"no running cost term {name!r}; terms: {self._term_names}") from None

    def sync_contacts(self) -> None:
        """Read the node models' contact sets only (the part of :meth:`sync` that
        :meth:`set_term_columns` does not cover); nodes whose contact set is unchanged are skipped."""
        keys = self._node_contact_keys
        for k, model in enumerate(self.running_models):
            dam = model.differential
            if dam.active_key != keys[k] or dam._moving_references:
                self._node_dynamics[k] = self._dynamics_of(dam)
                keys[k] = dam.active_key

    def set_term_columns(self, columns: dict) -> None:
        """Write the activity, weight and reference of frame terms over the whole horizon at once:
        ``columns[name] = (scale (N,), reference (N, d) or None)`` with scale = weight where the
        term is active and 0 elsewhere, d = 1 (frame height) or 3 (frame translation).

        The fast path of :meth:`sync` for a caller that updates the node models from the same
        arrays (:meth:`wbmpc.walking.WalkingOCP.update`); the result is the one :meth:`sync`
        would read from them (tested).
        """
        for name, (scale, reference) in columns.items():
            j = self.term_index(name)
            kind = self._term_kind[j]
            if kind not in (FRAME_HEIGHT, FRAME_TRANSLATION):
                raise ParameterError(f"set_term_columns: {name!r} is not a frame term")
            self._term_scale[:, j] = scale
            if reference is not None:
                d = 1 if kind == FRAME_HEIGHT else 3
                self._reference[:, j, :d] = np.asarray(reference, dtype=float).reshape(self.T, d)
        self._refresh_frame_needed()

    def _refresh_frame_needed(self) -> None:
        """The frames whose kinematics each node needs: those of its active frame terms."""
        needed = self._frame_needed
        needed[:] = False
        for j in range(len(self._term_names)):
            if self._term_kind[j] in (FRAME_HEIGHT, FRAME_TRANSLATION):
                needed[:, self._term_slot[j]] |= self._term_scale[:, j] != 0.0

    def _dynamics_of(self, dam) -> tuple:
        """(constraint models or None without contacts, Pinocchio data, constraint datas, proximal
        settings) of a node's contact set; the data is shared by every node with that set (one per
        set keeps it in cache)."""
        for name in dam._moving_references:  # Baumgarte position reference (Kp > 0) may have moved
            dam.constraint_models[name].joint2_placement = dam.contacts[name].reference_placement()
        key = dam.active_key
        entry = self._contact_sets.get(key)
        if entry is not None and not dam.nc:
            return (None,) + entry
        if entry is None:
            pdata = self._pin_model.createData()
            constraint_datas = pin.StdVec_RigidConstraintData()
            for constraint in dam.active_constraints:
                constraint_datas.append(constraint.createData())
            if dam.nc:
                pin.initConstraintDynamics(self._pin_model, pdata, dam.active_constraints, constraint_datas)
            entry = self._contact_sets[key] = (pdata, constraint_datas, dam.proximal_settings)
        return (dam.active_constraints if dam.nc else None, *entry)

    # ----------------------------------------------------------------- preparation
    def prepare_dynamics(self, xs: np.ndarray, us: np.ndarray, keys: list, deadline: float | None = None) -> int:
        """Compute ahead the part of the next :meth:`calcDiff` that is known before it is called.

        In a receding-horizon loop most of the next guess is the current solution shifted by one
        node: only node 0 waits for the measured state. This computes, for each node k with
        ``keys[k]`` not None, the contact dynamics of the contact set ``keys[k]`` at (xs[k], us[k])
        and their derivatives (Pinocchio's ``constraintDynamics`` and
        ``computeConstraintDynamicsDerivatives``, ~20 µs per Bolt node, two thirds of calcDiff).
        The next :meth:`calcDiff` (or :meth:`calc_and_diff`) takes them for every node whose
        state, control and contact set are then exactly these (bit-identical results) and computes
        the others, then the preparation is spent. Contact sets with a moving Baumgarte position
        reference (Kp > 0) are not prepared (their constraint depends on the update).

        Args:
            xs: (N, nx) states of the running nodes of the next evaluation (row 0 may be anything
                when keys[0] is None).
            us: (N, nu) their controls [N·m].
            keys: N contact-set keys (``active_key`` of the node's dynamics, a set present in the
                current horizon) or None (not prepared).
            deadline: ``time.perf_counter()`` value [s] after which no further node is prepared
                (the nodes left are computed by the next calcDiff), or None.

        Returns:
            The number of nodes prepared.
        """
        N = self.T
        xs, us = np.asarray(xs, dtype=float), np.asarray(us, dtype=float)
        if xs.shape != (N, self.nx) or us.shape != (N, self.nu) or len(keys) != N:
            raise ParameterError(f"prepare_dynamics: xs {xs.shape}, us {us.shape}, {len(keys)} keys; expected "
                                 f"({N}, {self.nx}), ({N}, {self.nu}), {N}")
        entries = {}
        for k, model in enumerate(self.running_models):
            if not model.differential._moving_references:
                entries.setdefault(self._node_contact_keys[k], self._node_dynamics[k])
        self._prepared[:] = False
        count = 0
        for k in range(N):
            if deadline is not None and time.perf_counter() >= deadline:
                break
            entry = None if keys[k] is None else entries.get(keys[k])
            if entry is None:
                continue
            self._dynamics_and_derivatives(entry, self._dt[k], xs[k], us[k], self._prepared_xnext[k],
                                           self._prepared_euler_dx[k], self._prepared_da_dx[k],
                                           self._prepared_da_du[k])
            self._prepared_x[k] = xs[k]
            self._prepared_u[k] = us[k]
            self._prepared_key[k] = keys[k]
            self._prepared[k] = True
            count += 1
        return count

    def _take_prepared(self, xs: np.ndarray, us: np.ndarray) -> np.ndarray | None:
        """Copy the prepared dynamics of the nodes they match (state, control, contact set) into
        the evaluation buffers and spend the preparation; returns the mask of those nodes, or None."""
        self.prepared_used = 0
        if not self._prepared.any():
            return None
        N = self.T
        # the same contact set (prepare_dynamics never prepares one with a moving reference)
        same_set = np.array([a == b for a, b in zip(self._prepared_key, self._node_contact_keys)], dtype=np.bool_)
        match = (self._prepared & same_set & np.all(xs[:N] == self._prepared_x, axis=1)
                 & np.all(us == self._prepared_u, axis=1))
        self._prepared[:] = False
        nodes = np.flatnonzero(match)
        self.prepared_used = int(nodes.size)
        self.xnext[nodes] = self._prepared_xnext[nodes]
        self._euler_dx[nodes] = self._prepared_euler_dx[nodes]
        self._da_dx[nodes] = self._prepared_da_dx[nodes]
        self._da_du[nodes] = self._prepared_da_du[nodes]
        return match

    # ----------------------------------------------------------------- evaluation
    def _node_dynamics_calc(self, k: int, x: np.ndarray, u: np.ndarray) -> None:
        """Accelerations of node k by contact-constrained dynamics, then x⁺ by the Euler step.
        The rollout inlines this for speed; it serves the nodes without contact and :meth:`calc`."""
        model, nq = self._pin_model, self.state.nq
        constraints, pdata, constraint_datas, settings = self._node_dynamics[k]
        q, v = x[:nq], x[nq:]
        tau = self._tau
        tau[6:] = u
        if constraints is not None:
            a = pin.constraintDynamics(model, pdata, q, v, tau, constraints, constraint_datas, settings)
        else:
            a = pin.aba(model, pdata, q, v, tau)
        free_flyer_euler_step(x, a, self._dt[k], self._euler_dx[k], self.xnext[k])

    def _dynamics_and_derivatives(self, entry: tuple, dt: float, x: np.ndarray, u: np.ndarray, xnext: np.ndarray,
                                  euler_dx: np.ndarray, da_dx: np.ndarray, da_du: np.ndarray) -> None:
        """The Pinocchio work of one node in :meth:`calcDiff` and :meth:`prepare_dynamics`.

        Contact dynamics of the contact set ``entry`` (an item of ``_node_dynamics``) at the state
        x (nx,) and joint torques u (nu,) [N·m] (ABA without contact), the Euler step of dt [s]
        into xnext (nx,) and euler_dx (ndx,), then ∂a/∂x into da_dx (nv, ndx) and ∂a/∂u into
        da_du (nv, nu).
        """
        model, nq, nv = self._pin_model, self.state.nq, self.state.nv
        constraints, pdata, constraint_datas, settings = entry
        q, v = x[:nq], x[nq:]
        tau = self._tau
        tau[6:] = u
        if constraints is None:
            a = pin.aba(model, pdata, q, v, tau)
            free_flyer_euler_step(x, a, dt, euler_dx, xnext)
            da_dq, da_dv, da_dtau = pin.computeABADerivatives(model, pdata, q, v, tau)
        else:
            a = pin.constraintDynamics(model, pdata, q, v, tau, constraints, constraint_datas, settings)
            free_flyer_euler_step(x, a, dt, euler_dx, xnext)
            da_dq, da_dv, da_dtau = pin.computeConstraintDynamicsDerivatives(
                model, pdata, constraints, constraint_datas, settings)[:3]
        da_dx[:, :nv] = da_dq
        da_dx[:, nv:] = da_dv
        da_du[:] = da_dtau[:, 6:]

    def _frame_kinematics(self, xs: np.ndarray, jacobians: bool) -> None:
        """Positions (and LOCAL_WORLD_ALIGNED Jacobians) of the frames of the active frame terms."""
        if self._kinematics is not None:
            self._kinematics.evaluate(xs[:self.T, :self.state.nq], self._frame_needed, self._frame_position,
                                      self._frame_jacobian if jacobians else None)

    def _state_residuals(self, xs: np.ndarray) -> None:
        """x ⊖ x_ref of every active state term (compiled; Pinocchio near a half turn)."""
        for j in self._state_terms:
            ok = state_residuals(self._reference[:, j, :self.nx], xs, self.state.nq, self._term_scale[:, j],
                                 self._state_residual[:, j], self._difference_ok)
            if not ok:
                for k in np.flatnonzero(~self._difference_ok):
                    self.state.diff(self._reference[k, j, :self.nx], xs[k], out=self._state_residual[k, j])

    def _state_jacobians(self, xs: np.ndarray) -> None:
        """∂(x ⊖ x_ref)/∂q of every active state term (compiled; Pinocchio near a half turn)."""
        nq = self.state.nq
        for j in self._state_terms:
            ok = free_flyer_state_jacobians(self._reference[:, j, :self.nx], xs, self._term_scale[:, j],
                                            self._state_jacobian[:, j], self._difference_ok)
            if not ok:
                for k in np.flatnonzero(~self._difference_ok):
                    self._state_jacobian[k, j] = pin.dDifference(self._pin_model, self._reference[k, j, :nq],
                                                                 xs[k, :nq], pin.ARG1)

    def _running_cost(self, xs, us) -> float:
        self._state_residuals(xs)
        return batched_cost_values(xs, us, self._dt, self._term_kind, self._term_row, self._term_slot,
                                   self._term_scale, self._reference, self._row_term, self._w, self._lb, self._ub,
                                   self._state_residual, self._frame_position, self._scratch_r,
                                   self._node_cost, self._term_cost)

    def calc(self, xs, us) -> float:
        """Next states (``xnext``) and costs of every node; returns the total cost."""
        xs, us = np.asarray(xs, dtype=float), np.asarray(us, dtype=float)
        for k in range(self.T):
            self._node_dynamics_calc(k, xs[k], us[k])
        self._frame_kinematics(xs, jacobians=False)
        cost = self._running_cost(xs, us)
        self.terminal_model.calc(self.terminal_data, xs[-1])
        self.cost = cost + self.terminal_data.cost
        return self.cost

    def calcDiff(self, xs, us) -> float:
        """Derivatives of every node (values too: calc is not needed first); returns the total
        cost. Nodes prepared by :meth:`prepare_dynamics` at these (x, u, contact set) take the
        prepared dynamics."""
        xs, us = np.asarray(xs, dtype=float), np.asarray(us, dtype=float)
        dynamics, dts, euler_dx, xnext, da_dx, da_du = (self._node_dynamics, self._dt, self._euler_dx, self.xnext,
                                                         self._da_dx, self._da_du)
        prepared = self._take_prepared(xs, us)
        nodes = range(self.T) if prepared is None else np.flatnonzero(~prepared).tolist()
        for k in nodes:
            self._dynamics_and_derivatives(dynamics[k], dts[k], xs[k], us[k], xnext[k], euler_dx[k], da_dx[k], da_du[k])
        self._frame_kinematics(xs, jacobians=True)
        self._state_residuals(xs)
        self._state_jacobians(xs)
        cost = batched_cost_derivatives(
            xs, us, self._dt, self._term_kind, self._term_row, self._term_slot, self._term_scale, self._reference,
            self._row_term, self._w, self._lb, self._ub, self._state_residual, self._state_jacobian,
            self._frame_position, self._frame_jacobian, self._da_dx, self._da_du, self._euler_dx, self._J_q, self._J_dq,
            self._scratch_r, self._node_cost, self._term_cost, self.Fx, self.Fu, self.Lx, self.Lu, self.Lxx, self.Luu)
        self.terminal_model.calc(self.terminal_data, xs[-1])
        self.terminal_model.calcDiff(self.terminal_data, xs[-1])
        self.cost = cost + self.terminal_data.cost
        return self.cost

    def calc_and_diff(self, xs, us) -> float:
        return self.calcDiff(xs, us)

    def forward_rollout(self, xs, us, k, K, fs, alpha, xs_try, us_try, dx) -> float:
        """The FDDP rollout of :meth:`ShootingProblem.forward_rollout`, node costs batched."""
        N = self.T
        closing = not (alpha == 1.0 or fs is None)
        gaps = self._no_gaps if fs is None else fs
        model, nq = self._pin_model, self.state.nq
        constraint_dynamics = pin.constraintDynamics
        dynamics, dts, euler_dx, xnexts, tau = self._node_dynamics, self._dt, self._euler_dx, self.xnext, self._tau
        xnext = self.x0
        for t in range(N):
            x_try = xs_try[t]
            code = rollout_node_start(t, xnext, gaps, alpha, closing, xs, us, k, K, x_try, dx, us_try, tau)
            if code == 1:  # relative half turn: Pinocchio's difference
                self._feedback(t, xs, us, k, K, alpha, x_try, dx, us_try)
                tau[6:] = us_try[t]
            elif code == 2:
                raise RolloutError(f"control not finite at node {t}")
            constraints, pdata, constraint_datas, settings = dynamics[t]
            if constraints is None:
                self._node_dynamics_calc(t, x_try, us_try[t])
            else:
                a = constraint_dynamics(model, pdata, x_try[:nq], x_try[nq:], tau, constraints, constraint_datas,
                                        settings)
                free_flyer_euler_step(x_try, a, dts[t], euler_dx[t], xnexts[t])
            xnext = xnexts[t]
        if closing:
            self.state.integrate(xnext, fs[N] * (alpha - 1.0), out=xs_try[N])
        else:
            xs_try[N] = xnext
        if not np.isfinite(xs_try).all():
            raise RolloutError("rollout diverged (state not finite)")
        self._frame_kinematics(xs_try, jacobians=False)
        cost = self._running_cost(xs_try, us_try)
        self.terminal_model.calc(self.terminal_data, xs_try[N])
        cost += self.terminal_data.cost
        if not np.isfinite(cost):
            raise RolloutError("rollout cost not finite")
        return cost

    def node_costs(self) -> np.ndarray:
        """Integrated cost of each running node (N,) after the last evaluation."""
        return self._node_cost.copy()

    def term_costs(self) -> dict[str, float]:
        """Total cost of each named term over the horizon (running terms scaled by dt)."""
        totals = {name: float(self._dt @ self._term_cost[:, j]) for j, name in enumerate(self._term_names)}
        terminal = self.terminal_model.differential.costs
        for name, cost in terminal.term_costs(self.terminal_data.differential.costs).items():
            totals[f"terminal_{name}"] = totals.get(f"terminal_{name}", 0.0) + cost
        return totals


@njit(cache=True)
def state_residuals(references, xs, nq, scale, out, ok):
    """out[k] = xs[k] ⊖ references[k] (compiled free-flyer difference) where scale[k] != 0;
    ok[k] False where Pinocchio must take over (half-turn); returns True if none did."""
    all_ok = True
    for k in range(out.shape[0]):
        ok[k] = True
        if scale[k] == 0.0:
            continue
        if not free_flyer_state_difference(references[k], xs[k], nq, out[k]):
            ok[k] = False
            all_ok = False
    return all_ok


@njit(cache=True)
def _fill_residual_rows(k, x, u, term_kind, term_row, term_slot, term_scale, reference, state_residual,
                        frame_position, r):
    """Residual rows r (nr,) of node k's active terms from the precomputed state residuals and frame positions."""
    for j in range(term_kind.size):
        if term_scale[k, j] == 0.0:
            continue
        row = term_row[j]
        kind = term_kind[j]
        if kind == 0:  # state
            ndx = state_residual.shape[2]
            for i in range(ndx):
                r[row + i] = state_residual[k, j, i]
        elif kind == 1:  # control
            for i in range(u.size):
                r[row + i] = u[i] - reference[k, j, i]
        elif kind == 2:  # frame height
            r[row] = frame_position[k, term_slot[j], 2] - reference[k, j, 0]
        else:  # frame translation
            for i in range(3):
                r[row + i] = frame_position[k, term_slot[j], i] - reference[k, j, i]


@njit(cache=True)
def batched_cost_values(xs, us, dt, term_kind, term_row, term_slot, term_scale, reference, row_term, w, lb, ub,
                        state_residual, frame_position, r, node_cost, term_cost):
    """Cost of every running node (dt-scaled, node_cost (N,)) and of its terms (unscaled,
    term_cost (N, n_terms)); returns the total running cost."""
    total = 0.0
    for k in range(dt.size):
        _fill_residual_rows(k, xs[k], us[k], term_kind, term_row, term_slot, term_scale, reference,
                            state_residual, frame_position, r)
        value = cost_rows_value(r, row_term, term_scale[k], w[k], lb[k], ub[k], term_cost[k])
        node_cost[k] = dt[k] * value
        total += node_cost[k]
    return total


@njit(cache=True)
def _row_coefficients(r, w, lb, ub, scale):
    """Gradient and Hessian coefficients (c, h) of one residual row under the dead-zone activation."""
    below = r - lb
    above = r - ub
    e = min(below, 0.0) + max(above, 0.0)
    h = scale * w if (below <= 0.0 or above >= 0.0) else 0.0
    return scale * w * e, h


@njit(cache=True)
def _add_frame_rows(J, rows, first_row, r, w, lb, ub, scale, Lx, Lxx):
    """Rows ``rows`` of a frame Jacobian J (3, nv) with residual rows r[first_row:]: Jᵀ c, Jᵀ diag(h) J."""
    nv = J.shape[1]
    for a in range(rows.size):
        i = first_row + a
        c, h = _row_coefficients(r[i], w[i], lb[i], ub[i], scale)
        Jrow = J[rows[a]]
        for b in range(nv):
            Lx[b] += c * Jrow[b]
            if h != 0.0 and Jrow[b] != 0.0:
                hb = h * Jrow[b]
                for d in range(nv):
                    Lxx[b, d] += hb * Jrow[d]


@njit(cache=True)
def _node_cost_derivatives(k, dt, term_kind, term_row, term_slot, term_scale, w, lb, ub, r, state_jacobian,
                           frame_jacobian, Lx, Lu, Lxx, Luu):
    """dt-scaled Gauss-Newton gradient and Hessian of node k from its residual rows r, term by
    term with the residuals' structure (the state residual's configuration Jacobian is identity
    outside its 6×6 base block; controls enter only Lu, Luu; frames only the configuration block).
    Lxu stays zero: no supported residual couples x and u."""
    nv = Lxx.shape[0] // 2
    nu = Lu.size
    Lx[:] = 0.0
    Lu[:] = 0.0
    Lxx[:, :] = 0.0
    Luu[:, :] = 0.0
    z_row = np.array([2])
    xyz_rows = np.array([0, 1, 2])
    for j in range(term_kind.size):
        scale = dt * term_scale[k, j]
        if scale == 0.0:
            continue
        row = term_row[j]
        kind = term_kind[j]
        if kind == 0:  # state: r = x ⊖ x_ref, Rx = [[B, 0, 0], [0, I, 0], [0, 0, I]]
            B = state_jacobian[k, j]
            c = np.empty(6)
            h = np.empty(6)
            for i in range(6):
                c[i], h[i] = _row_coefficients(r[row + i], w[k, row + i], lb[k, row + i], ub[k, row + i], scale)
            for a in range(6):
                g = 0.0
                for m in range(6):
                    g += B[m, a] * c[m]
                Lx[a] += g
                for b in range(6):
                    s = 0.0
                    for m in range(6):
                        s += B[m, a] * h[m] * B[m, b]
                    Lxx[a, b] += s
            for i in range(6, 2 * nv):
                ci, hi = _row_coefficients(r[row + i], w[k, row + i], lb[k, row + i], ub[k, row + i], scale)
                Lx[i] += ci
                Lxx[i, i] += hi
        elif kind == 1:  # control: Ru = I
            for i in range(nu):
                ci, hi = _row_coefficients(r[row + i], w[k, row + i], lb[k, row + i], ub[k, row + i], scale)
                Lu[i] += ci
                Luu[i, i] += hi
        elif kind == 2:  # frame height: z row of the world-aligned linear Jacobian
            _add_frame_rows(frame_jacobian[k, term_slot[j]], z_row, row, r, w[k], lb[k], ub[k], scale, Lx, Lxx)
        else:  # frame translation
            _add_frame_rows(frame_jacobian[k, term_slot[j]], xyz_rows, row, r, w[k], lb[k], ub[k], scale, Lx, Lxx)


@njit(cache=True)
def batched_cost_derivatives(xs, us, dt, term_kind, term_row, term_slot, term_scale, reference, row_term, w, lb, ub,
                             state_residual, state_jacobian, frame_position, frame_jacobian, da_dx, da_du, euler_dx,
                             J_q, J_dq, r, node_cost, term_cost, Fx, Fu, Lx, Lu, Lxx, Luu):
    """Values and derivatives of every running node: Euler transition Jacobians Fx (N, ndx, ndx),
    Fu (N, ndx, nu), Gauss-Newton cost derivatives (dt-scaled); returns the total running cost."""
    ndx = state_residual.shape[2]
    nv = ndx // 2
    total = 0.0
    nq = xs.shape[1] - nv
    for k in range(dt.size):
        free_flyer_dintegrate(xs[k, :nq], euler_dx[k, :nv], J_q, J_dq)
        euler_transition_jacobians(da_dx[k], da_du[k], J_q, J_dq, dt[k], 6, Fx[k], Fu[k])
        _fill_residual_rows(k, xs[k], us[k], term_kind, term_row, term_slot, term_scale, reference,
                            state_residual, frame_position, r)
        value = cost_rows_value(r, row_term, term_scale[k], w[k], lb[k], ub[k], term_cost[k])
        node_cost[k] = dt[k] * value
        total += node_cost[k]
        _node_cost_derivatives(k, dt[k], term_kind, term_row, term_slot, term_scale, w, lb, ub, r, state_jacobian,
                               frame_jacobian, Lx[k], Lu[k], Lxx[k], Luu[k])
    return total
