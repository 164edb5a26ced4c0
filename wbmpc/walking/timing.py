"""The walking OCP with continuous contact timings, and the sensitivity of its solution to them.

The touchdown times τ (m,) inside the horizon are parameters of the OCP: every contact phase
(single support, the double support after each touchdown, which keeps its duration d, so its
lift-off τ_i + d moves with τ_i) keeps its number of nodes and the node spacing is the phase's
duration over that number (:func:`sequencer.schedule.timed_contact_schedule`). A running node k of
phase i then depends on τ through its spacing h_k = (b_{i+1} − b_i)/n_i only (b the phase's ends:
τ_i, τ_i + d or fixed; the dynamics x⁺ = x ⊕ f(x, u; h) and the cost h · l_c(x, u)) and, for the
swing in progress at t0 and the swing still running at t_end, through the swing phase s_k(τ) of
the height reference z*(s) (eq. 19); inside the horizon s = j/n_i does not depend on τ. So

    ∂x⁺/∂τ = ∂x⁺/∂h ∂h/∂τ,   ∂Lx/∂τ = ∂l_c/∂x ∂h/∂τ − h w Rxᵀ z*'(s) ∂s/∂τ,   ∂Lu/∂τ = ∂l_c/∂u ∂h/∂τ,

all analytic (:meth:`ContactTimingOCP.parameter_derivatives`, checked against differences of the
model in the tests). The terminal CoM reference c* (3,) can be added as three more parameters
(∂Lx_N/∂c* = −w_CoM Jcomᵀ), the second channel through which a DCM disturbance reaches the OCP.
:func:`contact_timing_sensitivity` gives the derivatives of the solution by the three routes of
:mod:`sensitivity` (Riccati sweep, re-solved finite differences, full KKT), and of the solver's
feedback gains K (:mod:`sensitivity.ocp_gains`: the Gauss-Newton backward pass differentiated,
against differences of re-solved gains). The swing path terms (``WalkingOCPConfig.swing_path_weight``, a
reference that also moves with s) are not part of this problem: it is updated without the swings' lift-off
points, so they stay off whatever the preset's weight.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from sensitivity.ocp_finite_differences import check_fd_step, finite_difference_sensitivity
from sensitivity.ocp_gains import block_derivatives, gain_derivatives, solver_gains, time_gain_recursion
from sensitivity.ocp_kkt import kkt_sensitivity
from sensitivity.ocp_parametric import (
    ParameterDerivatives,
    check_converged,
    costates,
    linear_quadratic,
    stationarity_residual,
)
from sensitivity.ocp_riccati import riccati_sensitivity, time_sweep_against_riccati
from sequencer.schedule import timed_contact_schedule
from wbmpc.errors import ParameterError, SolverError
from wbmpc.ocp.blas import limit_blas_threads
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.walking.ocp import WalkingOCP, quasi_static_controls, swing_height_reference_derivative

#: the routes of :func:`contact_timing_sensitivity`
ROUTES = ("riccati", "finite_differences", "kkt")


class ContactTimingOCP:
    """A :class:`WalkingOCP` whose touchdown times are continuous parameters.

    Args:
        ocp: the walking OCP (``evaluation="nodes"``: the batched problem fixes its node spacings).
        plan: the ``sequencer.horizon.FootstepPlan``; its touchdowns inside the horizon are the
            parameters, their nominal values the plan's; with double support (the G1's) each lift-off
            stays ``plan.double_support`` after its touchdown (:func:`sequencer.timed_contact_schedule`).
        t0: time of node 0 [s].
        x0: initial state (nx,).
        com_terminal_reference: terminal CoM reference (3,) [m], world.
    """

    def __init__(self, ocp: WalkingOCP, plan, t0: float, x0: np.ndarray, com_terminal_reference: np.ndarray):
        if ocp.evaluation != "nodes":
            raise ParameterError(f"ocp.evaluation={ocp.evaluation!r}: a timed OCP needs evaluation='nodes'")
        self.ocp = ocp
        self.plan = plan
        self.t0 = float(t0)
        self.x0 = np.asarray(x0, dtype=float).copy()
        self.com_terminal_reference = np.asarray(com_terminal_reference, dtype=float).copy()
        self.schedule = timed_contact_schedule(plan, self.t0, ocp.dt, ocp.n_nodes)
        self.nominal_touchdown_times = self.schedule.touchdown_times.copy()
        self._landing_feet = [step.foot for step in plan.steps[: self.nominal_touchdown_times.size]]
        ocp.update(self.x0, self.schedule, self.com_terminal_reference)

    @property
    def problem(self):
        return self.ocp.problem

    @property
    def touchdown_times(self) -> np.ndarray:
        """The current touchdown times τ (m,) [s]."""
        return self.schedule.touchdown_times.copy()

    @property
    def parameter_names(self) -> list[str]:
        """``"touchdown_1_right"`` … in time order (the foot that lands)."""
        return [f"touchdown_{i + 1}_{foot}" for i, foot in enumerate(self._landing_feet)]

    def set_parameters(self, touchdown_times=None, com_terminal_reference=None, next_touchdown=None) -> None:
        """Re-time the OCP (None: the plan's touchdowns), optionally move the terminal CoM reference
        and the touchdown ending the last swing (after the horizon; None: the plan's).

        Raises:
            ParameterError: touchdown_times of the wrong shape, unordered or outside the horizon.
        """
        self.schedule = timed_contact_schedule(self.plan, self.t0, self.ocp.dt, self.ocp.n_nodes, touchdown_times,
                                               next_touchdown)
        if com_terminal_reference is not None:
            self.com_terminal_reference = np.asarray(com_terminal_reference, dtype=float).copy()
        self.ocp.update(self.x0, self.schedule, self.com_terminal_reference)

    # ------------------------------------------------------------------ derivatives
    def parameter_derivatives(self, xs, us, com_reference: bool = False,
                              next_touchdown: bool = False) -> ParameterDerivatives:
        """Analytic ∂(x⁺, Lx, Lu)/∂p at (xs, us) (module docstring) for p = τ, then the touchdown
        ending the last swing (after t_end) if ``next_touchdown``, then c* (3,) if ``com_reference``.

        Evaluates the problem (calc and calcDiff) at (xs, us) first.
        """
        problem = self.problem
        problem.calc_and_diff(xs, us)
        schedule = self.schedule
        N, ndx, nu = problem.T, problem.ndx, problem.nu
        m_tau = schedule.touchdown_times.size
        m_next = m_tau + (1 if next_touchdown else 0)
        m = m_next + (3 if com_reference else 0)
        dxnext = np.zeros((N, ndx, m))
        dLx = np.zeros((N + 1, ndx, m))
        dLu = np.zeros((N, nu, m))
        ddt = np.zeros((N, m))
        ddt[:, :m_tau] = schedule.node_spacing_jacobian
        apex = self.ocp.config.swing_apex_height
        for k, (model, data) in enumerate(zip(problem.running_models, problem.running_datas)):
            dx_dh, dLx_dh, dLu_dh = model.calcDiffDt(data, xs[k], us[k])
            column = ddt[k, :m_tau]
            dxnext[k, :, :m_tau] = np.outer(dx_dh, column)
            dLx[k, :, :m_tau] = np.outer(dLx_dh, column)
            dLu[k, :, :m_tau] = np.outer(dLu_dh, column)
        for k in range(N + 1):
            terminal = k == N
            model = problem.terminal_model if terminal else problem.running_models[k]
            data = problem.terminal_data if terminal else problem.running_datas[k]
            scale = 1.0 if terminal else model.dt
            costs, cdata = model.differential.costs, data.differential.costs
            for foot in self.ocp.feet:
                column = schedule.feet.index(foot)
                ds = schedule.swing_phase_jacobian[k, column]
                if next_touchdown:
                    ds = np.append(ds, schedule.swing_phase_next_jacobian[k, column])
                if not np.any(ds):
                    continue
                s = schedule.swing_phase[k, column]
                gradient = costs.reference_gradient(cdata, f"{foot}_height")[:, 0]  # ∂[Lx; Lu]/∂z*
                dz = swing_height_reference_derivative(s, apex)
                dLx[k, :, :m_next] += scale * np.outer(gradient[:ndx], dz * ds)
                if not terminal:
                    dLu[k, :, :m_next] += scale * np.outer(gradient[ndx:], dz * ds)
        if com_reference:
            costs = problem.terminal_model.differential.costs
            dLx[N, :, m_next:] = costs.reference_gradient(problem.terminal_data.differential.costs, "com_position")[:ndx]
        return ParameterDerivatives(dxnext, dLx, dLu, ddt)

    # ------------------------------------------------------------------ outputs
    def outputs(self, xs, us) -> dict:
        """u0 (nu,) [N·m], the node-0 contact forces (stacked over the stance feet, 3 each) [N], the
        terminal CoM (3,) [m] and the CoM trajectory (N + 1, 3) [m]. Evaluates the problem at (xs, us)."""
        problem = self.problem
        problem.calc(xs, us)
        dam = problem.running_models[0].differential
        ddata = problem.running_datas[0].differential
        forces = np.concatenate([ddata.contacts[name].force for name in dam.active_contacts])
        model = self.ocp.state.pinocchio
        pdata = model.createData()
        coms = np.array([pin.centerOfMass(model, pdata, x[: model.nq]) for x in xs])
        return {"u0": np.array(us[0]), "forces0": forces, "com_terminal": coms[-1].copy(), "com": coms}

    def output_derivatives(self, xs, us, dxs: np.ndarray, dus: np.ndarray) -> dict:
        """Derivatives of :meth:`outputs` (output shape + (m,)) from dxs (N + 1, ndx, m), dus (N, nu, m)."""
        problem = self.problem
        problem.calc(xs, us)
        problem.calcDiff(xs, us)
        dam = problem.running_models[0].differential
        jacobians = dam.contact_force_jacobians(problem.running_datas[0].differential)
        dforces = np.concatenate([jacobians[name][0] @ dxs[0] + jacobians[name][1] @ dus[0]
                                  for name in dam.active_contacts])
        model = self.ocp.state.pinocchio
        pdata = model.createData()
        nv = model.nv
        dcom = np.array([pin.jacobianCenterOfMass(model, pdata, x[: model.nq]) @ dx[:nv] for x, dx in zip(xs, dxs)])
        return {"u0": dus[0].copy(), "forces0": dforces, "com_terminal": dcom[-1].copy(), "com": dcom}

    # ------------------------------------------------------------------ solving
    def solve(self, init_xs=None, init_us=None, th_stop: float = 1e-16, maxiter: int = 400) -> SolverFDDP:
        """Solve the current OCP with FDDP to ``th_stop`` (default guess: standing still, the
        quasi-static torques); returns the solver.

        Raises:
            SolverError: not converged within ``maxiter`` iterations (the message gives the stop).
        """
        problem = self.problem
        N = problem.T
        solver = SolverFDDP(problem)
        solver.th_stop = float(th_stop)
        solver.reg_min, solver.reg_max = self.ocp.config.reg_min, self.ocp.config.reg_max
        if init_xs is None:
            init_xs = [self.x0] * (N + 1)
            init_us = [quasi_static_controls(self.ocp, self.x0)] * N
        with limit_blas_threads(1):
            converged = solver.solve(init_xs, init_us, maxiter=maxiter)
        if not converged:
            raise SolverError(f"FDDP did not converge in maxiter={maxiter} iterations: stop={solver.stop:.3g} "
                              f"(th_stop={th_stop:.3g})")
        return solver


@dataclass(frozen=True)
class TimingSensitivity:
    """The derivatives of the walking OCP's solution with respect to p (touchdown times [, c*]).

    Attributes:
        parameter_names: (m,) names; touchdown_times: τ (m_τ,) [s].
        routes: route name -> outputs name -> derivative (u0 (nu, m) [N·m/s], forces0 (nc, m) [N/s],
            com_terminal (3, m) [m/s], com (N + 1, 3, m); per metre for the c* columns), plus
            "us" (N, nu, m) and "xs" (N + 1, ndx, m); with ``gains``, the routes "riccati" (the
            recursion's derivative, :mod:`sensitivity.ocp_gains`) and "finite_differences" (re-solved
            gains) also have "K" (N, nu, ndx, m) and "K0" (nu, ndx, m): dK/dp of the solver's gains
            [gain unit/s: N·m/rad/s, N·m·s/rad/s, N·m/m/s …, the unit of the state component].
        disagreement: "<route> vs riccati" -> output -> max |J_route − J_riccati| / max |J_riccati|.
        max_relative_disagreement: the largest of them over the routes and :data:`COMPARED_OUTPUTS`.
        gauss_newton: the same outputs from the Riccati sweep with FDDP's Gauss-Newton Hessian (its
            own factorisation) and their relative gap to the finite differences (None if not asked).
        gains: the solver's first gains "K0" (nu, ndx) (``SolverFDDP.K[0]``, u = u* + K (x ⊖ x*)), the regularisation ρ
            they carry, the steps of the blocks' differences per parameter ("block_steps") and the
            gap between the solver's own K0 and K0 recomputed at the solution ("solver_K0_gap", the
            solver's K comes from the pass before its last step); None if not asked.
        cost: wall times [s] (Hessian, factorisation, sweep, one Riccati pass, re-solves, KKT, the
            gains' block differences and recursion).
        settings: fd_step [s], th_stop, hessian_step, gain_step, stationarity residual of the base solution.
    """

    parameter_names: list
    touchdown_times: np.ndarray
    routes: dict
    disagreement: dict
    max_relative_disagreement: float
    gauss_newton: dict | None
    cost: dict
    settings: dict
    gains: dict | None = None

    @property
    def dK_dtouchdown(self) -> np.ndarray:
        """dK_0/dτ (nu, ndx, m_τ) [gain unit/s] of the first node's gains (Riccati route)."""
        if self.gains is None:
            raise ParameterError("gains=False: the gains' derivative was not computed")
        return self.routes["riccati"]["K0"][..., : self.touchdown_times.size]


#: the outputs whose route gaps make :attr:`TimingSensitivity.max_relative_disagreement` (when both
#: routes have them): first torques, first gains, node-0 contact forces, CoM trajectory and terminal CoM
COMPARED_OUTPUTS = ("u0", "K0", "forces0", "com", "com_terminal")


def relative_gap(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| / max |b| (relative to the largest entry of the reference b; absolute if b = 0)."""
    scale = float(np.max(np.abs(b)))
    return float(np.max(np.abs(a - b))) / (scale if scale > 0 else 1.0)


def contact_timing_sensitivity(timed: ContactTimingOCP, solver: SolverFDDP, fd_step: float = 2e-5,
                               th_stop: float = 1e-12, com_reference: bool = False,
                               routes=ROUTES, gauss_newton: bool = True, hessian_step: float = 1e-6,
                               fd_th_stop: float = 1e-20, kkt_solver: str = "auto", gains: bool = True,
                               gain_step: float = 1e-6) -> TimingSensitivity:
    """d(xs*, us*, K, forces*, CoM*)/dτ at a converged solution by the routes asked.

    Args:
        timed: the timed OCP, at the parameters the solution was computed for.
        solver: the FDDP solver holding the converged base solution (``stop < th_stop``, feasible).
        fd_step: central-difference step h [s] of route (b) (and [m] for c*), > 0.
        th_stop: the largest base stop accepted.
        com_reference: add the terminal CoM reference c* (3,) as parameters after τ.
        routes: any of :data:`ROUTES`; "riccati" is always computed (the reference of the gaps).
        gauss_newton: also the Gauss-Newton sweep (FDDP's factorisation) and its gap to route (b).
        hessian_step: step of the exact Hessian's differences (tangent units).
        fd_th_stop: the stop the re-solves of route (b) are converged to.
        kkt_solver: "auto", "dense" or "sparse" (route c).
        gains: also dK/dp of the solver's gains (Gauss-Newton backward pass with the solver's
            regularisation ``solver.preg``, :mod:`sensitivity.ocp_gains`), and by route (b) the
            differences of the gains at the re-solved solutions.
        gain_step: the largest step [s] (and [m] for c*) of the blocks' directional differences, > 0.

    Raises:
        ParameterError: non-converged base solution (names its stop), fd_step <= 0 or not finite,
            an unknown route.
    """
    check_converged(solver.stop, th_stop, solver.is_feasible)
    fd_step = check_fd_step(fd_step)
    unknown = set(routes) - set(ROUTES)
    if unknown:
        raise ParameterError(f"routes={sorted(unknown)} are not among {ROUTES}")
    xs, us = solver.xs.copy(), solver.us.copy()
    problem = timed.problem
    regularization = float(solver.preg)
    base_tau = timed.touchdown_times
    base_com = timed.com_terminal_reference.copy()
    m_tau = base_tau.size
    p0 = np.concatenate([base_tau, base_com if com_reference else []])
    names = timed.parameter_names + (["com_reference_x", "com_reference_y", "com_reference_z"] if com_reference else [])

    def set_at(p):
        timed.set_parameters(p[:m_tau], base_com + (p[m_tau:] if com_reference else 0.0))

    cost = {}
    tic = time.perf_counter()
    derivatives = timed.parameter_derivatives(xs, us, com_reference)
    cost["parameter_derivatives_s"] = time.perf_counter() - tic
    tic = time.perf_counter()
    lq = linear_quadratic(problem, xs, us, derivatives, "exact", hessian_step)
    cost["exact_hessian_s"] = time.perf_counter() - tic
    stationarity = stationarity_residual(problem, costates(problem))
    with limit_blas_threads(1):
        riccati = riccati_sensitivity(lq)
        cost.update({f"riccati_{k}_s": v for k, v in riccati.seconds.items()})
        cost.update(time_sweep_against_riccati(lq))
    results = {"riccati": _route_outputs(timed, xs, us, riccati.dxs, riccati.dus)}
    lq_gn = linear_quadratic(problem, xs, us, derivatives, "gauss-newton") if gains or gauss_newton else None
    gain_report = None
    if gains:
        tic = time.perf_counter()
        blocks = block_derivatives(problem, set_at, p0, xs, us, riccati.dxs, riccati.dus, gain_step)
        cost["gain_block_derivatives_s"] = time.perf_counter() - tic
        with limit_blas_threads(1):
            gain_sens = gain_derivatives(lq_gn, blocks, regularization)
            cost.update(time_gain_recursion(lq_gn, blocks, regularization))
        results["riccati"].update(K=gain_sens.dK, K0=gain_sens.dK[0])
        K0 = gain_sens.K[0]
        gain_report = {"K0": K0.copy(), "regularization": regularization, "block_steps": blocks.steps,
                       "solver_K0_gap": relative_gap(np.asarray(solver.K[0]), K0)}
    if "kkt" in routes:
        kkt = kkt_sensitivity(lq, kkt_solver)
        cost.update({f"kkt_{k}_s": v for k, v in kkt.seconds.items()})
        results["kkt"] = _route_outputs(timed, xs, us, kkt.dxs, kkt.dus)
    if "finite_differences" in routes:
        def solve_at(p):
            set_at(p)
            re_solved = timed.solve(xs, us, th_stop=fd_th_stop)
            out = timed.outputs(re_solved.xs, re_solved.us)
            if gains:
                K = solver_gains(problem, re_solved.xs, re_solved.us, regularization)
                out.update(K=K, K0=K[0])
            return {"xs": re_solved.xs.copy(), "us": re_solved.us.copy(), **out}

        try:
            fd, fd_outputs = finite_difference_sensitivity(problem.state, solve_at, p0, fd_step)
        finally:
            set_at(p0)
        cost["finite_differences_s"] = fd.seconds["re-solves"]
        results["finite_differences"] = {**fd_outputs, "xs": fd.dxs, "us": fd.dus}
    problem.calc_and_diff(xs, us)
    disagreement = {}
    for name, out in results.items():
        if name != "riccati":
            disagreement[f"{name} vs riccati"] = {key: relative_gap(out[key], results["riccati"][key])
                                                  for key in COMPARED_OUTPUTS + ("K", "us")
                                                  if key in out and key in results["riccati"]}
    largest = max((gap for gaps in disagreement.values() for key, gap in gaps.items() if key in COMPARED_OUTPUTS),
                  default=0.0)
    gn = None
    if gauss_newton:
        gn_sens = riccati_sensitivity(lq_gn)
        gn = {"outputs": _route_outputs(timed, xs, us, gn_sens.dxs, gn_sens.dus)}
        reference = results.get("finite_differences", results["riccati"])
        gn["gap_to_" + ("finite_differences" if "finite_differences" in results else "riccati")] = {
            key: relative_gap(gn["outputs"][key], reference[key]) for key in ("u0", "forces0", "com_terminal", "us")}
    return TimingSensitivity(
        parameter_names=names, touchdown_times=base_tau, routes=results, disagreement=disagreement,
        max_relative_disagreement=largest, gauss_newton=gn, cost=cost,
        settings={"fd_step": fd_step, "th_stop": th_stop, "fd_th_stop": fd_th_stop, "hessian_step": hessian_step,
                  "gain_step": gain_step, "base_stop": float(solver.stop), "stationarity_residual": stationarity},
        gains=gain_report,
    )


def state_tangent_names(model) -> list[str]:
    """Names of the ndx state-tangent components of a free-flyer robot (Pinocchio's difference): the
    base translation and rotation (base frame), the joint angles, then the base twist and joint rates."""
    joints = list(model.names[2:])
    base = [f"base_{kind}_{axis}" for kind in ("linear", "angular") for axis in "xyz"]
    names = base + [f"q_{name}" for name in joints] + [f"v_{name}" for name in base] + [f"v_{name}" for name in joints]
    if len(names) != 2 * model.nv:
        raise ParameterError(f"model with nv={model.nv}: not a free-flyer robot with one-dof joints")
    return names


def gain_reaction_by_joint(K0: np.ndarray, dK0: np.ndarray, joints, columns) -> list[dict]:
    """Which actuated joints' gains move most with the touchdown times, largest first.

    Args:
        K0: the first gains (nu, ndx); dK0: dK0/dτ (nu, ndx, m) [per s]; joints: the nu joint names;
        columns: the ndx state-tangent names (:func:`state_tangent_names`).

    Returns:
        per joint i: "joint", "dK_norm_per_s" (m,) = ‖dK0[i, :, j]‖ (Euclidean over the state
        components, in the gains' mixed units per s), "relative_per_s" (m,) = that / ‖K0[i]‖ [1/s],
        "largest_column" the state-tangent component of its largest |dK0| entry; sorted by the largest
        relative change over the touchdowns.
    """
    norms = np.linalg.norm(dK0, axis=1)  # (nu, m)
    scale = np.maximum(np.linalg.norm(K0, axis=1), 1e-300)
    rows = [{"joint": name, "dK_norm_per_s": norms[i], "relative_per_s": norms[i] / scale[i],
             "largest_column": columns[int(np.argmax(np.abs(dK0[i]).max(axis=1)))]} for i, name in enumerate(joints)]
    return sorted(rows, key=lambda row: -float(np.max(row["relative_per_s"])))


def _route_outputs(timed: ContactTimingOCP, xs, us, dxs, dus) -> dict:
    return {**timed.output_derivatives(xs, us, dxs, dus), "xs": dxs, "us": dus}


# ---------------------------------------------------------------------- the default Bolt problem
def standing_start_timing_ocp(robot_name: str = "bolt", n_nodes: int = 100, dt: float = 0.01,
                              dcm_offset=(0.0, 0.0), foothold_weight: float = 0.0,
                              speed: float | None = None, start=None) -> ContactTimingOCP:
    """The timed walking OCP from a standing start (what ``wbmpc ocp`` solves, with timed phases):
    the preset's planner and OCP weights (footholds emerge: foothold_weight 0), the terminal CoM
    reference the plan's LIPM prediction at t_end; ``dcm_offset`` (2,) [m] disturbs the measured
    DCM the plan is made from; ``start``: the :class:`~wbmpc.walking.standing_start.StandingStart`
    of these arguments when the caller has it already (None: made here)."""
    from wbmpc.walking.standing_start import standing_start

    start = standing_start(robot_name, speed, dcm_offset) if start is None else start
    config = start.preset.ocp.node_wise(foothold_weight=foothold_weight)
    ocp = WalkingOCP(start.robot, config, n_nodes=n_nodes, dt=dt)
    com_terminal = start.com_terminal_reference(n_nodes * dt)
    return ContactTimingOCP(ocp, start.plan, 0.0, start.x0, com_terminal)


# ---------------------------------------------------------------------- end to end: DCM -> plan -> OCP
def touchdown_dcm_jacobian(sequencer, plan, n_touchdowns: int) -> np.ndarray:
    """dτ_i/dθ (n_touchdowns, 2) [s/m] of the plan's first touchdowns to a disturbance θ on the
    measured DCM, by chaining the step QP's Fiacco sensitivities (:func:`sensitivity.fiacco_sensitivity`).

    Step 0's QP sees θ directly: dT_0/dθ = dΓ_0/dθ / (ω Γ_0). Step i ≥ 1 starts at touchdown i
    (elapsed 0) from its foothold p_T,i−1 with the DCM p_T,i−1 + b_T,i−1: the QP is invariant to a
    common shift of the foothold and the DCM, so its disturbance is the change of b_T,i−1,
    dθ_i/dθ = (db_T,i−1/dθ_{i−1}) dθ_{i−1}/dθ, and τ_{i+1} = τ_i + T_i.

    Raises:
        sensitivity.DegenerateSensitivity: a step's QP has a weakly active bound (no derivative).
    """
    from sensitivity import fiacco_sensitivity

    omega = plan.omega
    jacobian = np.zeros((n_touchdowns, 2))
    chain = np.eye(2)  # dθ_i/dθ
    time_derivative = np.zeros(2)
    for i in range(n_touchdowns):
        if i == 0:
            problem = sequencer.problem(plan.stance_foot, plan.stance_position, plan.dcm_measured,
                                        plan.t0 - plan.t_stance_start)
        else:
            previous = plan.steps[i - 1]
            problem = sequencer.problem(previous.foot, previous.position, previous.dcm_at_touchdown, 0.0)
        step = fiacco_sensitivity(problem)
        gamma = step.x[2]
        time_derivative = time_derivative + (step.dx_dtheta[2] / (omega * gamma)) @ chain
        jacobian[i] = time_derivative
        chain = step.dx_dtheta[3:5] @ chain
    return jacobian


def dcm_sensitivity(robot_name: str = "bolt", n_nodes: int = 100, dt: float = 0.01, fd_step: float = 1e-4,
                    com_step: float = 1e-6, th_stop: float = 1e-17) -> dict:
    """End to end: du0/dθ [N·m/m] of the whole-body MPC's first torques to a disturbance θ (2,) on
    the measured DCM, from a standing start, and its check against the whole chain.

    du0/dθ = du0/dτ dτ/dθ + du0/dτ⁺ dτ⁺/dθ + du0/dc* dc*/dθ: the OCP's sensitivity (Riccati sweep) to
    the touchdown times τ in the horizon, to the touchdown τ⁺ ending the last swing and to the
    terminal CoM reference c* (the plan's LIPM CoM at t_end), times the step QP's chained Fiacco
    derivatives dτ/dθ, dτ⁺/dθ (:func:`touchdown_dcm_jacobian`) and dc*/dθ (central differences of the
    planner's closed-form LIPM prediction, step ``com_step`` [m]; the one numerical link). The
    footholds do not enter the OCP (foothold_weight 0, contacts without position feedback). The
    check: central differences (step ``fd_step`` [m]) of the whole chain, re-planning, rebuilding
    and re-solving the timed OCP for θ ± h e_j.

    Returns:
        dict with du0_dtheta (nu, 2), its channels (timing, com_reference), dtau_dtheta (m + 1, 2) by
        the chain and by differences of the planner, the finite-difference du0/dθ, their relative
        disagreement and the settings.
    """
    from wbmpc.walking.standing_start import standing_start

    fd_step = check_fd_step(fd_step)
    start = standing_start(robot_name)
    timed = standing_start_timing_ocp(robot_name, n_nodes, dt, start=start)
    solver = timed.solve(th_stop=th_stop)
    xs, us = solver.xs.copy(), solver.us.copy()
    m = timed.touchdown_times.size
    dtau = touchdown_dcm_jacobian(start.sequencer, start.plan, m + 1)
    t_end = n_nodes * dt

    def planned(theta):
        plan = standing_start(robot_name, dcm_offset=theta).plan
        return plan.touchdown_times[: m + 1], start.com_terminal_reference(t_end, plan)

    dtau_fd, dcom = np.zeros((m + 1, 2)), np.zeros((3, 2))
    for j in range(2):
        step = np.zeros(2)
        step[j] = com_step
        (tau_plus, com_plus), (tau_minus, com_minus) = planned(step), planned(-step)
        dtau_fd[:, j] = (tau_plus - tau_minus) / (2 * com_step)
        dcom[:, j] = (com_plus - com_minus) / (2 * com_step)
    check_converged(solver.stop, 1e-12, solver.is_feasible)
    derivatives = timed.parameter_derivatives(xs, us, com_reference=True, next_touchdown=True)
    lq = linear_quadratic(timed.problem, xs, us, derivatives, "exact")
    sens = riccati_sensitivity(lq)
    du0_dp = sens.dus[0]  # (nu, m + 1 + 3)
    timing = du0_dp[:, : m + 1] @ dtau
    com_channel = du0_dp[:, m + 1:] @ dcom
    du0 = timing + com_channel
    fd = np.zeros_like(du0)
    for j in range(2):
        u0 = []
        for sign in (1.0, -1.0):
            theta = np.zeros(2)
            theta[j] = sign * fd_step
            disturbed = standing_start_timing_ocp(robot_name, n_nodes, dt, dcm_offset=theta)
            u0.append(disturbed.solve(xs, us, th_stop=th_stop).us[0].copy())
        fd[:, j] = (u0[0] - u0[1]) / (2 * fd_step)
    return {
        "du0_dtheta": du0, "du0_dtheta_timing_channel": timing, "du0_dtheta_com_reference_channel": com_channel,
        "du0_dtheta_finite_differences": fd, "max_relative_disagreement": relative_gap(du0, fd),
        "disagreement": {"chain vs finite differences of the whole chain": relative_gap(du0, fd),
                         "dtau_dtheta: Fiacco chain vs planner differences": relative_gap(dtau, dtau_fd)},
        "dtau_dtheta": dtau, "dtau_dtheta_planner_differences": dtau_fd, "dcom_reference_dtheta": dcom,
        "du0_dtau": du0_dp[:, : m + 1], "touchdown_times": np.append(timed.touchdown_times, start.plan.touchdown_times[m]),
        "settings": {"fd_step_m": fd_step, "com_step_m": com_step, "th_stop": th_stop, "n_nodes": n_nodes, "dt": dt},
    }
