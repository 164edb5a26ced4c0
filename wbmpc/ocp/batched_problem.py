"""A shooting problem evaluated over the whole horizon at once: the same function as
:class:`~wbmpc.ocp.problem.ShootingProblem`, from the same definitions, with the per-node Python
work cut to the Pinocchio calls.

The node-by-node pipeline (action model -> differential model -> cost sum -> residuals) makes
about 25 Python calls per node and keeps one Pinocchio data per node; over a 100-node horizon that
glue, and the cache misses of 100 data objects, cost twice Pinocchio's own work. This problem
reads the same node models (contacts, cost terms, weights, references) and evaluates them as:

- a Python loop over the nodes doing only what needs Pinocchio: contact-constrained dynamics
  (``constraintDynamics`` with the node's contact set, or ABA without contacts) and, in
  :meth:`calcDiff`, its derivatives; one Pinocchio data per contact set, so it stays in cache;
  when a term reads contact forces, each node's stacked forces λ and their derivatives
  [∂λ/∂x, ∂λ/∂u] are copied out of it (``HorizonData.contact_force``, ``contact_force_jacobian``);
  the Euler step (and, in the rollout, the feedback law) are the compiled kernels the node-wise
  model calls (:mod:`wbmpc.ocp.kernels.integration`, :mod:`wbmpc.ocp.kernels.feedback`);
- one Python call per cost term: each residual declares its batched evaluation
  (:class:`~wbmpc.ocp.residuals.base.BatchedResidual`: its rows and Jacobian nonzeros at every
  active node, by the compiled rows its node-wise ``calc`` uses), reading the frame kinematics of
  the active frame terms (positions, rotations, Jacobians) and, for the centre-of-mass terms, the
  centre of mass and its Jacobian, computed for all nodes in one compiled pass
  (:mod:`wbmpc.ocp.kernels.frames`), and the kept contact forces;
- one compiled pass over the nodes running what the node-wise models run per node: the Euler
  transition Jacobians, the cost value, the Gauss-Newton derivatives of the cost rows
  (:mod:`wbmpc.ocp.kernels.costs`) and their dt scaling.

The node models stay the only configuration: every batched term's per-node references are rows
of one array the node residuals write into (``bind_reference``), every cost item tells the
problem when its weight or activity changes (``CostItem.bind_scale``), and :meth:`sync` reads
the contact sets.

Supported nodes: :class:`~wbmpc.ocp.integrator.IntegratedActionModelEuler` over
:class:`~wbmpc.ocp.dynamics.DifferentialActionModelContactFwdDynamics` (either backend; a "kkt"
node's dynamics are its own ``calc_dynamics`` and ``calc_diff_dynamics``) on a free-flyer robot
with 1-dof revolute joints, every running node with the same cost terms (switched on and off per
node), each term's residual a
:class:`~wbmpc.ocp.residuals.base.BatchedResidual`. A term without a batched evaluation is an
error naming it (:func:`batched_evaluation_support` says why a problem does not qualify). The
terminal node, any model, is evaluated node-wise.

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
from wbmpc.ocp.dynamics import DERIVATIVE_DYNAMICS, ROLLOUT_DYNAMICS, DifferentialActionModelContactFwdDynamics
from wbmpc.ocp.integrator import IntegratedActionModelEuler
from wbmpc.ocp.kernels.costs import (
    add_gauss_newton_rows,
    clear_hessian_entries,
    cost_rows_value,
    hessian_entries,
    scale_cost_derivatives,
)
from wbmpc.ocp.kernels.derivative_pass import KKTDerivativePass
from wbmpc.ocp.kernels.feedback import rollout_node_start
from wbmpc.ocp.kernels.frames import FrameKinematics
from wbmpc.ocp.kernels.horizon_contacts import HorizonContactSets
from wbmpc.ocp.kernels.integration import euler_transition_jacobians, free_flyer_euler_step
from wbmpc.ocp.kernels.lie import free_flyer_dintegrate
from wbmpc.ocp.kernels.rollout import KKTRollout
from wbmpc.ocp.kernels.tree import tree_support
from wbmpc.ocp.problem import RolloutError, ShootingProblem
from wbmpc.ocp.residuals.base import BatchedResidual, HorizonData


def _unbatched_term(name: str, residual) -> str | None:
    """Why the cost term ``name`` cannot be batched, or None."""
    if isinstance(residual, BatchedResidual):
        return None
    why = getattr(residual, "batch_unsupported", "it declares no batched evaluation")
    return f"cost {name!r} ({type(residual).__name__}) cannot be batched: {why}"


def batched_evaluation_support(problem: ShootingProblem) -> str | None:
    """None if ``problem`` can be evaluated by :class:`BatchedShootingProblem`, else the reason."""
    state = problem.state
    if not state._compiled_difference:
        return "the robot is not a free-flyer root followed by 1-dof joints"
    reason = tree_support(state.pinocchio)
    if reason is not None:
        return reason
    signatures = None
    for k, model in enumerate(problem.running_models):
        if type(model) is not IntegratedActionModelEuler:
            return f"running node {k} is a {type(model).__name__}, not an IntegratedActionModelEuler"
        dam = model.differential
        if type(dam) is not DifferentialActionModelContactFwdDynamics:
            return f"running node {k} is not contact forward dynamics"
        items = dam.costs.costs
        if signatures is None:
            for name, item in items.items():
                reason = _unbatched_term(name, item.cost.residual)
                if reason is not None:
                    return reason
            names = list(items)
            signatures = [item.cost.residual.batch_signature() for item in items.values()]
        elif list(items) != names:
            return f"running node {k} has the cost terms {list(items)}, node 0 has {names}"
        else:
            for (name, item), signature in zip(items.items(), signatures):
                reason = _unbatched_term(name, item.cost.residual)
                if reason is not None:
                    return reason
                if item.cost.residual.batch_signature() != signature:
                    return f"cost {name!r} differs at running node {k} from node 0 (residual type, size or frame)"
    return None


class BatchedShootingProblem(ShootingProblem):
    """Drop-in :class:`~wbmpc.ocp.problem.ShootingProblem` with horizon-batched evaluation.

    Same constructor, and ``rollout_dynamics``: the dynamics of the "kkt" backend's nodes with contacts
    in :meth:`calc` and the rollouts (:meth:`forward_rollout`), one of
    :data:`~wbmpc.ocp.dynamics.ROLLOUT_DYNAMICS`:

    - "pinocchio" (default): each node's ``calc_dynamics`` as in its derivatives (Pinocchio's ``crba``
      and ``nonLinearEffects``, the explicit-inverse KKT solve), node by node from Python;
    - "compiled": M and b compiled on the contacts' tree and the KKT solve by triangular solves
      (``calc_dynamics(..., rollout_dynamics="compiled")``), the rollout's run of such nodes in one
      compiled call (:mod:`wbmpc.ocp.kernels.rollout`; ``use_compiled_rollout = False``: node by node,
      the same kernels, the same numbers to the bit). A cheaper rollout (docs/benchmarks.md), the
      same numbers as "pinocchio" to rounding (~1e-15), not to the bit: a closed loop's trajectory
      changes.

    The derivative pass (:meth:`calcDiff`, :meth:`prepare_dynamics`) is the same under both; it takes
    ``derivative_dynamics`` instead, one of :data:`~wbmpc.ocp.dynamics.DERIVATIVE_DYNAMICS`, for the same nodes:

    - "pinocchio" (default): each node's ``calc_dynamics`` with Pinocchio's ``crba`` and ``nonLinearEffects``,
      then ``calc_diff_dynamics`` with Pinocchio's ``computeRNEADerivatives``;
    - "compiled": M and b compiled on the contacts' tree (the same explicit-inverse KKT solve), then the contacts',
      RNEA and KKT derivatives in one compiled call (``calc_dynamics``/``calc_diff_dynamics(...,
      derivative_dynamics="compiled")``): no binding call at such a node; the same values and derivatives as
      "pinocchio" to rounding (~1e-15), not to the bit. The pass runs such nodes in one compiled call over the
      horizon (:mod:`wbmpc.ocp.kernels.derivative_pass`; ``use_compiled_derivatives = False``: node by node, the
      same kernels, the same numbers to the bit).

    Raises :class:`~wbmpc.errors.ParameterError` when the nodes are not supported (see
    :func:`batched_evaluation_support`) or ``rollout_dynamics`` or ``derivative_dynamics`` is not one of the
    choices. References
    written into the node residuals and the weights and activity set on the node cost items are seen at
    once; call :meth:`sync` after changing the node models' contact sets, before the next evaluation
    (:meth:`~wbmpc.walking.WalkingOCP.update` does).
    """

    def __init__(self, x0: np.ndarray, running_models: list, terminal_model, rollout_dynamics: str = "pinocchio",
                 derivative_dynamics: str = "pinocchio"):
        if rollout_dynamics not in ROLLOUT_DYNAMICS:
            raise ParameterError(f"rollout_dynamics={rollout_dynamics!r} must be one of {ROLLOUT_DYNAMICS}")
        if derivative_dynamics not in DERIVATIVE_DYNAMICS:
            raise ParameterError(f"derivative_dynamics={derivative_dynamics!r} must be one of {DERIVATIVE_DYNAMICS}")
        super().__init__(x0, running_models, terminal_model)
        reason = batched_evaluation_support(self)
        if reason is not None:
            raise ParameterError(f"running_models cannot be evaluated batched: {reason}")
        self._rollout_dynamics = rollout_dynamics
        self._derivative_dynamics = derivative_dynamics
        state = self.state
        N, nv, nx, ndx, nu = self.T, state.nv, state.nx, state.ndx, self.nu
        self._pin_model = state.pinocchio
        first = self.running_models[0].differential.costs
        first_data = self.running_datas[0].differential.costs
        self._term_names = list(first.costs)
        self._terms = [item.cost.residual for item in first.costs.values()]  # each term's batched evaluation
        n_terms = len(self._terms)
        nr = first_data.r.size
        self._row_term = first_data.row_term.copy()
        self._term_rows = [first_data.rows[name] for name in self._term_names]
        # Jacobian nonzeros of all terms, row-major (the pattern of cost_rows_derivatives)
        rows, cols, self._term_values = [], [], []
        for residual, term_rows in zip(self._terms, self._term_rows):
            r_rows, r_cols = residual.jacobian_pattern()
            start = sum(len(c) for c in cols)
            rows.append(r_rows + term_rows.start)
            cols.append(r_cols)
            self._term_values.append(slice(start, start + r_cols.size))
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        if np.any(np.diff(rows) < 0) or np.any((np.diff(rows) == 0) & (np.diff(cols) <= 0)):
            raise ParameterError("a residual's jacobian_pattern() is not row-major with increasing columns")
        self._cols = cols
        self._row_start = np.searchsorted(rows, np.arange(nr + 1)).astype(np.int64)
        # the Hessian entries the pattern can fill: the only ones of Lxx, Lxu, Luu (rows < N) ever written
        self._hessian_entries = hessian_entries(self._row_start, cols, ndx)
        self._values = np.zeros((N, cols.size))
        self._r = np.zeros((N, nr))
        # every term's per-node references: rows of one array, shared with the node residuals
        self._references = []
        for j, residual in enumerate(self._terms):
            storage = np.zeros((N, np.size(residual.reference)))
            for k, model in enumerate(self.running_models):
                model.differential.costs.costs[self._term_names[j]].cost.residual.bind_reference(storage[k], self)
            self._references.append(storage)
        frame_ids: list[int] = []
        for residual in self._terms:
            for frame_id in residual.batch_frames:
                if frame_id not in frame_ids:
                    frame_ids.append(frame_id)
        # (n_frames, n_terms): the terms reading each frame's kinematics
        self._frame_terms = np.array([[frame_id in residual.batch_frames for residual in self._terms]
                                      for frame_id in frame_ids], dtype=np.bool_).reshape(len(frame_ids), n_terms)
        # the centre of mass (and its Jacobian) where a term reading it is active
        self._com_terms = np.array([residual.batch_com for residual in self._terms], dtype=np.bool_)
        self._com = bool(self._com_terms.any())
        self._com_needed = np.zeros(N, dtype=np.bool_)
        self._kinematics = FrameKinematics(self._pin_model, frame_ids) if frame_ids or self._com else None
        n_frames = max(len(frame_ids), 1)
        # the contact forces and their derivatives of every node, kept when a term reads them
        self._keep_forces = any(getattr(residual, "uses_contact_forces", False) for residual in self._terms)
        contact_names = sorted({name for model in self.running_models for name in model.differential.contacts})
        nc_max = max((sum(c.nc for c in model.differential.contacts.values()) for model in self.running_models),
                      default=0)
        nf, nfj = (N, nc_max) if self._keep_forces else (0, 0), (N, nc_max, ndx + nu) if self._keep_forces else (0, 0, 0)
        # rotations and angular Jacobian rows only for terms reading them (frame rotations)
        self._rotations = any(residual.batch_frame_rotations for residual in self._terms)
        self._horizon = HorizonData(xs=np.zeros((N, nx)), us=np.zeros((N, nu)),
                                    frame_slot={f: s for s, f in enumerate(frame_ids)},
                                    frame_position=np.zeros((N, n_frames, 3)),
                                    frame_jacobian=np.zeros((N, n_frames, 6 if self._rotations else 3, nv)),
                                    frame_rotation=np.zeros((N, n_frames, 3, 3) if self._rotations else (N, 0, 3, 3)),
                                    com=np.zeros((N, 3 if self._com else 0)),
                                    com_jacobian=np.zeros((N, 3 if self._com else 0, nv)),
                                    contact_force=np.zeros(nf), contact_force_jacobian=np.zeros(nfj),
                                    contact_row={name: np.full(N, -1, dtype=np.int64) for name in contact_names},
                                    contact_sets=[()] * N)
        self._forces, self._force_jacobians = self._horizon.contact_force, self._horizon.contact_force_jacobian
        self._w = np.stack([d.differential.costs.w for d in self.running_datas])
        self._lb = np.stack([d.differential.costs.lb for d in self.running_datas])
        self._ub = np.stack([d.differential.costs.ub for d in self.running_datas])
        self._dt = np.array([m.dt for m in self.running_models])
        # per-node configuration: term factors written by the cost items (set_term_scale), the
        # activity and needed frames derived from them before the next evaluation
        self._term_scale = np.zeros((N, n_terms))
        self._term_scale_slots = memoryview(self._term_scale.reshape(-1))  # flat, fast scalar writes
        self._term_active = np.zeros((N, n_terms), dtype=np.bool_)
        self._frame_needed = np.zeros((N, n_frames), dtype=np.bool_)  # frames of active terms
        self._activity_stale = True
        # per node: (constraint models or None, Pinocchio data, constraint datas, proximal settings)
        self._node_dynamics: list = [None] * N
        self._node_contact_keys: list = [None] * N
        self._contact_sets: dict = {}
        self._kkt_datas: dict = {}  # contact set -> dynamics data of the "kkt" backend's nodes
        # evaluation buffers
        self._tau = np.zeros(nv)
        self._euler_dx = np.zeros((N, ndx))
        self._da_dx = np.zeros((N, nv, ndx))
        self._da_du = np.zeros((N, nv, nu))
        self._J_q = np.zeros((nv, nv))  # scratch of the compiled pass
        self._J_dq = np.zeros((nv, nv))
        self._gradient = np.zeros(ndx + nu)
        self._hessian = np.zeros((ndx + nu, ndx + nu))
        self._node_cost = np.zeros(N)
        self._term_cost = np.zeros((N, n_terms))
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
        self._prepared_forces = np.zeros_like(self._forces)
        self._prepared_force_jacobians = np.zeros_like(self._force_jacobians)
        # "compiled": the rollout (kernels/rollout.py) and the derivative pass (kernels/derivative_pass.py) of the
        # "kkt" nodes in one compiled call each, when a node may take it, over the nodes' contact sets as padded
        # arrays (one copy, set by sync)
        kkt = [model.differential for model in self.running_models
               if model.differential.backend == "kkt" and model.differential.contacts]
        compiled = kkt and "compiled" in (rollout_dynamics, derivative_dynamics)
        self._horizon_contacts = (HorizonContactSets(N, max(len(dam.contacts) for dam in kkt), nc_max) if compiled
                                  else None)
        self._kkt_rollout = (KKTRollout(self._pin_model, self._horizon_contacts)
                             if compiled and rollout_dynamics == "compiled" else None)
        self._kkt_derivatives = (KKTDerivativePass(self._pin_model, self._horizon_contacts, nu)
                                 if compiled and derivative_dynamics == "compiled" else None)
        #: with rollout_dynamics="compiled": the rollouts run their "kkt" nodes in one compiled call
        #: (:mod:`wbmpc.ocp.kernels.rollout`); False: node by node from Python (the same kernels, the same
        #: numbers to the bit). No effect with "pinocchio".
        self.use_compiled_rollout = True
        #: with derivative_dynamics="compiled": :meth:`calcDiff` and :meth:`prepare_dynamics` (without a deadline)
        #: run their "kkt" nodes' dynamics and derivatives in one compiled call
        #: (:mod:`wbmpc.ocp.kernels.derivative_pass`); False: node by node from Python (the same kernels, the same
        #: numbers to the bit). No effect with "pinocchio".
        self.use_compiled_derivatives = True
        self.prepared_used = 0  # nodes the last calcDiff took from the preparation
        self._detached = False
        # (residual, active mask (N,), references, residual rows (N, nr), Jacobian nonzeros) of
        # each term: views of the stacked arrays, written in place
        self._term_arguments = [(residual, self._term_active[:, j], self._references[j], self._r[:, self._term_rows[j]],
                                 self._values[:, self._term_values[j]]) for j, residual in enumerate(self._terms)]
        for k, model in enumerate(self.running_models):
            for j, item in enumerate(model.differential.costs.costs.values()):
                item.bind_scale(self, k * n_terms + j)
        self.sync()

    @property
    def rollout_dynamics(self) -> str:
        """The dynamics of the "kkt" nodes in :meth:`calc` and the rollouts, "pinocchio" or "compiled"
        (fixed at construction, see the class)."""
        return self._rollout_dynamics

    @property
    def derivative_dynamics(self) -> str:
        """The dynamics of the "kkt" nodes in :meth:`calcDiff` and :meth:`prepare_dynamics`, "pinocchio" or
        "compiled" (fixed at construction, see the class)."""
        return self._derivative_dynamics

    def detach(self) -> None:
        """Called when another batched problem took over these node models' references and cost
        items: every later evaluation of this one raises (it would read stale configuration)."""
        self._detached = True

    def _check_attached(self) -> None:
        if self._detached:
            raise ParameterError("this BatchedShootingProblem's node models were bound by a newer "
                                 "BatchedShootingProblem: evaluate that one (or build the models anew)")

    # ----------------------------------------------------------------- configuration
    def sync(self) -> None:
        """Read the node models' contact sets (nodes whose set is unchanged are skipped). The
        references, weights and activity of the cost terms need no sync: the node residuals and
        cost items write them into the batched arrays."""
        keys = self._node_contact_keys
        h = self._horizon
        for k, model in enumerate(self.running_models):
            dam = model.differential
            if dam.active_key != keys[k] or dam._moving_references:
                self._node_dynamics[k] = self._dynamics_of(dam)
                if self._horizon_contacts is not None:
                    self._horizon_contacts.set_node(k, dam)
                if dam.active_key != keys[k]:
                    for rows in h.contact_row.values():
                        rows[k] = -1
                    for name, rows in dam._active_rows:
                        h.contact_row[name][k] = rows.start
                    h.contact_sets[k] = dam.active_key
                keys[k] = dam.active_key

    def set_term_scale(self, index: int, scale: float) -> None:
        """The factor of running cost term j at node k changed (called by the bound
        :class:`~wbmpc.ocp.costs.CostItem`): index = k · n_terms + j, scale = its weight when
        active, 0 otherwise."""
        self._term_scale_slots[index] = scale
        self._activity_stale = True

    def term_index(self, name: str) -> int:
        """Column of the running cost term ``name`` in the batched arrays."""
        try:
            return self._term_names.index(name)
        except ValueError:
            raise ParameterError(f"no running cost term {name!r}; terms: {self._term_names}") from None

    def _dynamics_of(self, dam) -> tuple:
        """(constraint models or None without contacts, Pinocchio data, constraint datas, proximal
        settings, force map, KKT) of a node's contact set; the data is shared by every node with that
        set (one per set keeps it in cache). The force map (``dam.force_map``, or None) turns
        Pinocchio's ``lambda_c`` into the stacked contact forces (a sole's four corners into its
        wrench). KKT is None, or for a node with contacts on the "kkt" backend (dam, its dynamics
        data shared by the set): then the node's own dynamics compute it (``calc_dynamics``,
        ``calc_diff_dynamics``) and the other entries are None."""
        dam.update_moving_references()
        key = dam.active_key
        if dam.nc and dam.backend == "kkt":
            data = self._kkt_datas.get(key)
            if data is None:
                data = self._kkt_datas[key] = dam.createData()
                data.kinematics_for_costs = False  # the costs read the compiled horizon kinematics
            return (None, None, None, None, None, (dam, data))
        entry = self._contact_sets.get(key)
        if entry is not None and not dam.nc:
            return (None,) + entry + (None,)
        if entry is None:
            pdata = self._pin_model.createData()
            entry = self._contact_sets[key] = (pdata, dam.create_constraint_datas(pdata), dam.proximal_settings,
                                               dam.force_map)
        return (dam.active_constraints if dam.nc else None, *entry, None)

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

        With derivative_dynamics="compiled" and no ``deadline`` the "kkt" nodes are computed in one compiled
        call (:mod:`wbmpc.ocp.kernels.derivative_pass`, the same numbers); with a deadline, node by node.

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
        entries, sources = {}, {}  # contact set -> the dynamics of the first node with it, that node
        for k, model in enumerate(self.running_models):
            if not model.differential._moving_references:
                entries.setdefault(self._node_contact_keys[k], self._node_dynamics[k])
                sources.setdefault(self._node_contact_keys[k], k)
        # without a deadline, the "kkt" nodes in one compiled call after the loop (the same numbers)
        compiled = (self._kkt_derivatives if self.use_compiled_derivatives and deadline is None else None)
        nodes, rows = [], []
        self._prepared[:] = False
        count = 0
        for k in range(N):
            if deadline is not None and time.perf_counter() >= deadline:
                break
            entry = None if keys[k] is None else entries.get(keys[k])
            if entry is None:
                continue
            if compiled is not None and self._horizon_contacts.compiled(sources[keys[k]]):
                nodes.append(k)
                rows.append(sources[keys[k]])
            else:
                self._dynamics_and_derivatives(entry, self._dt[k], xs[k], us[k], self._prepared_xnext[k],
                                               self._prepared_euler_dx[k], self._prepared_da_dx[k],
                                               self._prepared_da_du[k], *self._force_buffers(k, prepared=True))
            self._prepared_x[k] = xs[k]
            self._prepared_u[k] = us[k]
            self._prepared_key[k] = keys[k]
            self._prepared[k] = True
            count += 1
        if nodes:
            compiled.run(np.array(nodes, dtype=np.int64), np.array(rows, dtype=np.int64), xs, us, self._dt,
                         self._prepared_xnext, self._prepared_euler_dx, self._prepared_da_dx, self._prepared_da_du,
                         self._keep_forces, self._prepared_forces, self._prepared_force_jacobians)
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
        if self._keep_forces:
            self._forces[nodes] = self._prepared_forces[nodes]
            self._force_jacobians[nodes] = self._prepared_force_jacobians[nodes]
        return match

    def _force_buffers(self, k: int, prepared: bool = False) -> tuple:
        """(forces (nc_max,), force Jacobians (nc_max, ndx + nu)) of node k to fill, evaluation
        or preparation buffers; (None, None) when no term reads contact forces."""
        if not self._keep_forces:
            return None, None
        if prepared:
            return self._prepared_forces[k], self._prepared_force_jacobians[k]
        return self._forces[k], self._force_jacobians[k]

    # ----------------------------------------------------------------- evaluation
    def _node_dynamics_calc(self, k: int, x: np.ndarray, u: np.ndarray) -> None:
        """Accelerations of node k by contact-constrained dynamics, then x⁺ by the Euler step.
        The rollout inlines this for speed; it serves the nodes without contact and :meth:`calc`."""
        model, nq = self._pin_model, self.state.nq
        constraints, pdata, constraint_datas, settings, force_map, kkt = self._node_dynamics[k]
        q, v = x[:nq], x[nq:]
        tau = self._tau
        tau[6:] = u
        if kkt is not None:
            a = self._kkt_dynamics(kkt, x, u, self._forces[k] if self._keep_forces else None, self._rollout_dynamics)
        elif constraints is not None:
            a = pin.constraintDynamics(model, pdata, q, v, tau, constraints, constraint_datas, settings)
            if self._keep_forces:
                _copy_forces(pdata.lambda_c, force_map, self._forces[k])
        else:
            a = pin.aba(model, pdata, q, v, tau)
        free_flyer_euler_step(x, a, self._dt[k], self._euler_dx[k], self.xnext[k])

    def _dynamics_and_derivatives(self, entry: tuple, dt: float, x: np.ndarray, u: np.ndarray, xnext: np.ndarray,
                                  euler_dx: np.ndarray, da_dx: np.ndarray, da_du: np.ndarray,
                                  forces: np.ndarray | None = None, force_jacobians: np.ndarray | None = None) -> None:
        """The Pinocchio work of one node in :meth:`calcDiff` and :meth:`prepare_dynamics`.

        Contact dynamics of the contact set ``entry`` (an item of ``_node_dynamics``) at the state
        x (nx,) and joint torques u (nu,) [N·m] (ABA without contact), the Euler step of dt [s]
        into xnext (nx,) and euler_dx (ndx,), then ∂a/∂x into da_dx (nv, ndx) and ∂a/∂u into
        da_du (nv, nu). With ``forces`` (nc_max,) and ``force_jacobians`` (nc_max, ndx + nu): the
        stacked contact forces λ of the set (Pinocchio's ``lambda_c``, each contact in its
        constraint's frame, as the node-wise dynamics reads them) into forces[:nc] and
        [∂λ/∂x, ∂λ/∂u] into force_jacobians[:nc].
        """
        model, nq, nv = self._pin_model, self.state.nq, self.state.nv
        constraints, pdata, constraint_datas, settings, force_map, kkt = entry
        q, v = x[:nq], x[nq:]
        tau = self._tau
        tau[6:] = u
        if kkt is not None:
            dam, data = kkt
            # the solve the derivatives read, then the derivatives (one compiled call with "compiled")
            dam.calc_and_diff_dynamics(data, x, u, self._derivative_dynamics)
            if forces is not None:  # the active contacts' rows, stacked in order
                forces[:dam.nc] = data.force_all[:dam.nc]
            free_flyer_euler_step(x, data.xout, dt, euler_dx, xnext)
            da_dx[:] = data.Fx
            da_du[:] = data.Fu
            if forces is not None:
                ndx = self.state.ndx
                for name, rows in dam._active_rows:
                    force_jacobians[rows, :ndx] = data.contacts[name].df_dx
                    force_jacobians[rows, ndx:] = data.contacts[name].df_du
            return
        if constraints is None:
            a = pin.aba(model, pdata, q, v, tau)
            free_flyer_euler_step(x, a, dt, euler_dx, xnext)
            da_dq, da_dv, da_dtau = pin.computeABADerivatives(model, pdata, q, v, tau)
        else:
            a = pin.constraintDynamics(model, pdata, q, v, tau, constraints, constraint_datas, settings)
            free_flyer_euler_step(x, a, dt, euler_dx, xnext)
            da_dq, da_dv, da_dtau, dl_dq, dl_dv, dl_dtau = pin.computeConstraintDynamicsDerivatives(
                model, pdata, constraints, constraint_datas, settings)
            if forces is not None and force_map is None:
                nc = dl_dq.shape[0]
                forces[:nc] = pdata.lambda_c
                force_jacobians[:nc, :nv] = dl_dq
                force_jacobians[:nc, nv:2 * nv] = dl_dv
                force_jacobians[:nc, 2 * nv:] = dl_dtau[:, 6:]
            elif forces is not None:  # the stacked forces from the constraints' rows (sole corners)
                nc = force_map.shape[0]
                np.matmul(force_map, pdata.lambda_c, out=forces[:nc])
                np.matmul(force_map, dl_dq, out=force_jacobians[:nc, :nv])
                np.matmul(force_map, dl_dv, out=force_jacobians[:nc, nv:2 * nv])
                np.matmul(force_map, dl_dtau[:, 6:], out=force_jacobians[:nc, 2 * nv:])
        da_dx[:, :nv] = da_dq
        da_dx[:, nv:] = da_dv
        da_du[:] = da_dtau[:, 6:]

    @staticmethod
    def _kkt_dynamics(kkt: tuple, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                      rollout_dynamics: str, derivative_dynamics: str = "pinocchio") -> np.ndarray:
        """Accelerations (nv,) of a "kkt" backend node, kkt = (dam, data), and its stacked contact
        forces into ``forces`` (nc_max,) unless None; ``rollout_dynamics``: "pinocchio" (the solve that
        leaves the KKT factors for ``calc_diff_dynamics``, its M and b by ``derivative_dynamics``) or
        "compiled" (:meth:`calc` and the rollouts under that choice: see ``calc_dynamics``)."""
        dam, data = kkt
        dam.calc_dynamics(data, x, u, rollout_dynamics, derivative_dynamics)
        if forces is not None:  # the active contacts' rows, stacked in order
            forces[:dam.nc] = data.force_all[:dam.nc]
        return data.xout

    def _frame_kinematics(self, xs: np.ndarray, jacobians: bool) -> None:
        """Positions, rotations (and LOCAL_WORLD_ALIGNED Jacobians) of the frames of the active
        frame terms, the centre of mass (and its Jacobian) where a centre-of-mass term is active."""
        if self._kinematics is not None:
            h = self._horizon
            com = self._com
            self._kinematics.evaluate(xs[:self.T, :self.state.nq], self._frame_needed, h.frame_position,
                                      h.frame_jacobian if jacobians else None,
                                      h.frame_rotation if self._rotations else None,
                                      self._com_needed if com else None, h.com if com else None,
                                      h.com_jacobian if com and jacobians else None)

    def _residuals(self, xs: np.ndarray, us: np.ndarray, jacobians: bool) -> None:
        """Every term's residual rows (and Jacobian nonzeros) at the nodes where it is active."""
        N = self.T
        if self._activity_stale:
            term_activity(self._term_scale, self._frame_terms, self._term_active, self._frame_needed)
            if self._com:
                np.any(self._term_active[:, self._com_terms], axis=1, out=self._com_needed)
            self._activity_stale = False
        h = self._horizon
        h.xs, h.us = xs[:N], us
        self._frame_kinematics(xs, jacobians)
        for residual, mask, references, r, values in self._term_arguments:
            residual.batch_calc(h, mask, references, r)
            if jacobians:
                residual.batch_calc_diff(h, mask, references, values)

    def _running_cost(self, xs, us) -> float:
        self._residuals(xs, us, jacobians=False)
        return horizon_costs(self._dt, self._r, self._row_term, self._term_scale, self._w, self._lb, self._ub,
                             self._node_cost, self._term_cost)

    def calc(self, xs, us) -> float:
        """Next states (``xnext``) and costs of every node; returns the total cost."""
        self._check_attached()
        xs, us = np.asarray(xs, dtype=float), np.asarray(us, dtype=float)
        for k in range(self.T):
            self._node_dynamics_calc(k, xs[k], us[k])
        cost = self._running_cost(xs, us)
        self.terminal_model.calc(self.terminal_data, xs[-1])
        self.cost = cost + self.terminal_data.cost
        return self.cost

    def calcDiff(self, xs, us) -> float:
        """Derivatives of every node (values too: calc is not needed first); returns the total
        cost. Nodes prepared by :meth:`prepare_dynamics` at these (x, u, contact set) take the
        prepared dynamics."""
        self._check_attached()
        xs, us = np.asarray(xs, dtype=float), np.asarray(us, dtype=float)
        dynamics, dts, euler_dx, xnext, da_dx, da_du = (self._node_dynamics, self._dt, self._euler_dx, self.xnext,
                                                         self._da_dx, self._da_du)
        prepared = self._take_prepared(xs, us)
        todo = np.ones(self.T, dtype=np.bool_) if prepared is None else ~prepared
        if self._kkt_derivatives is not None and self.use_compiled_derivatives:  # the "kkt" nodes in one call
            compiled = todo & (self._horizon_contacts.contacts >= 0)
            nodes = np.flatnonzero(compiled)
            if nodes.size:
                self._kkt_derivatives.run(nodes, nodes, xs, us, dts, xnext, euler_dx, da_dx, da_du, self._keep_forces,
                                          self._forces, self._force_jacobians)
                todo &= ~compiled
        for k in np.flatnonzero(todo).tolist():
            self._dynamics_and_derivatives(dynamics[k], dts[k], xs[k], us[k], xnext[k], euler_dx[k], da_dx[k], da_du[k],
                                           *self._force_buffers(k))
        self._residuals(xs, us, jacobians=True)
        cost = horizon_derivatives(
            xs, self._dt, self._euler_dx, self._da_dx, self._da_du, self._J_q, self._J_dq, self._r, self._values,
            self._row_start, self._cols, self._row_term, self._term_scale, self._w, self._lb, self._ub,
            self._gradient, self._hessian, *self._hessian_entries, self._node_cost, self._term_cost,
            self.Fx, self.Fu, self.Lx, self.Lu, self.Lxx, self.Lxu, self.Luu)
        self.terminal_model.calc(self.terminal_data, xs[-1])
        self.terminal_model.calcDiff(self.terminal_data, xs[-1])
        self.cost = cost + self.terminal_data.cost
        return self.cost

    def calc_and_diff(self, xs, us) -> float:
        return self.calcDiff(xs, us)

    def forward_rollout(self, xs, us, k, K, fs, alpha, xs_try, us_try, dx) -> float:
        """The FDDP rollout of :meth:`ShootingProblem.forward_rollout`, node costs batched, node by node; with
        rollout_dynamics="compiled" the "kkt" nodes with contacts (but positioned soles) in one compiled call
        (:mod:`wbmpc.ocp.kernels.rollout`), the others, and a node the compiled call hands back (a half
        turn), node by node."""
        self._check_attached()
        N = self.T
        closing = not (alpha == 1.0 or fs is None)
        gaps = self._no_gaps if fs is None else fs
        model, nq = self._pin_model, self.state.nq
        constraint_dynamics = pin.constraintDynamics
        dynamics, dts, euler_dx, xnexts, tau = self._node_dynamics, self._dt, self._euler_dx, self.xnext, self._tau
        forces = self._forces if self._keep_forces else None
        compiled = self._kkt_rollout if self.use_compiled_rollout else None  # None: "pinocchio"
        rollout_dynamics = self._rollout_dynamics
        xnext = self.x0
        t = 0
        while t < N:
            if compiled is not None and compiled.compiled(t):  # from node t, as far as the compiled nodes go
                t = compiled.run(t, self.x0, gaps, alpha, closing, xs, us, k, K, xs_try, us_try, dx, tau, dts, euler_dx,
                                 xnexts, self._keep_forces, self._forces)
                if t == N:
                    xnext = xnexts[N - 1]
                    break
                xnext = self.x0 if t == 0 else xnexts[t - 1]
            x_try = xs_try[t]
            code = rollout_node_start(t, xnext, gaps, alpha, closing, xs, us, k, K, x_try, dx, us_try, tau)
            if code == 1:  # relative half turn: Pinocchio's difference
                self._feedback(t, xs, us, k, K, alpha, x_try, dx, us_try)
                tau[6:] = us_try[t]
            elif code == 2:
                raise RolloutError(f"control not finite at node {t}")
            constraints, pdata, constraint_datas, settings, force_map, kkt = dynamics[t]
            if kkt is not None:  # the node's own KKT dynamics (torques from us_try[t])
                a = self._kkt_dynamics(kkt, x_try, us_try[t], None if forces is None else forces[t], rollout_dynamics)
                free_flyer_euler_step(x_try, a, dts[t], euler_dx[t], xnexts[t])
            elif constraints is None:
                self._node_dynamics_calc(t, x_try, us_try[t])
            else:
                a = constraint_dynamics(model, pdata, x_try[:nq], x_try[nq:], tau, constraints, constraint_datas,
                                        settings)
                if forces is not None:
                    _copy_forces(pdata.lambda_c, force_map, forces[t])
                free_flyer_euler_step(x_try, a, dts[t], euler_dx[t], xnexts[t])
            xnext = xnexts[t]
            t += 1
        if closing:
            self.state.integrate(xnext, fs[N] * (alpha - 1.0), out=xs_try[N])
        else:
            xs_try[N] = xnext
        if not np.isfinite(xs_try).all():
            raise RolloutError("rollout diverged (state not finite)")
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


def _copy_forces(lambda_c: np.ndarray, force_map: np.ndarray | None, out: np.ndarray) -> None:
    """The stacked contact forces of a node into out[:nc]: Pinocchio's ``lambda_c`` itself, or
    ``force_map`` (nc, rows of lambda_c) applied to it."""
    if force_map is None:
        out[:lambda_c.size] = lambda_c
    else:
        np.matmul(force_map, lambda_c, out=out[:force_map.shape[0]])


@njit(cache=True)
def term_activity(term_scale, frame_terms, term_active, frame_needed):
    """term_active (N, n_terms): term_scale (N, n_terms) != 0; frame_needed (N, n_frames): some
    active term of the node reads the frame (frame_terms (n_frames, n_terms) says which do)."""
    for k in range(term_scale.shape[0]):
        for j in range(term_scale.shape[1]):
            term_active[k, j] = term_scale[k, j] != 0.0
        for s in range(frame_terms.shape[0]):
            needed = False
            for j in range(frame_terms.shape[1]):
                needed |= frame_terms[s, j] and term_active[k, j]
            frame_needed[k, s] = needed


@njit(cache=True)
def horizon_costs(dt, r, row_term, term_scale, w, lb, ub, node_cost, term_cost):
    """The cost of every running node from its residual rows r (N, nr), as the node-wise cost sum
    and Euler model compute it: node_cost (N,) dt-scaled, term_cost (N, n_terms) unscaled;
    returns the total running cost."""
    total = 0.0
    for k in range(dt.size):
        node_cost[k] = dt[k] * cost_rows_value(r[k], row_term, term_scale[k], w[k], lb[k], ub[k], term_cost[k])
        total += node_cost[k]
    return total


@njit(cache=True)
def horizon_derivatives(xs, dt, euler_dx, da_dx, da_du, J_q, J_dq, r, values, row_start, cols, row_term, term_scale,
                        w, lb, ub, gradient, hessian, xx, xu, uu, node_cost, term_cost, Fx, Fu, Lx, Lu, Lxx, Lxu, Luu):
    """Per running node, what :meth:`IntegratedActionModelEuler.calcDiff` runs after the dynamics:
    the Euler transition Jacobians Fx (N, ndx, ndx), Fu (N, ndx, nu), the cost value and its
    Gauss-Newton derivatives from the residual rows r (N, nr) and Jacobian nonzeros values
    (N, nnz), dt-scaled; returns the total running cost. Only the Hessian entries (xx, xu, uu)
    the pattern can fill (:func:`~wbmpc.ocp.kernels.costs.hessian_entries`) are computed, in the
    scratch gradient (ndx + nu,) and hessian (ndx + nu, ndx + nu), and written."""
    nv = da_dx.shape[1]
    nq = xs.shape[1] - nv
    total = 0.0
    for k in range(dt.size):
        free_flyer_dintegrate(xs[k, :nq], euler_dx[k, :nv], J_q, J_dq)
        euler_transition_jacobians(da_dx[k], da_du[k], J_q, J_dq, dt[k], 6, Fx[k], Fu[k])
        node_cost[k] = dt[k] * cost_rows_value(r[k], row_term, term_scale[k], w[k], lb[k], ub[k], term_cost[k])
        total += node_cost[k]
        gradient[:] = 0.0
        clear_hessian_entries(hessian, xx, xu, uu)
        add_gauss_newton_rows(r[k], values[k], row_start, cols, row_term, term_scale[k], w[k], lb[k], ub[k],
                              gradient, hessian)
        scale_cost_derivatives(dt[k], gradient, hessian, xx, xu, uu, Lx[k], Lu[k], Lxx[k], Lxu[k], Luu[k])
    return total
