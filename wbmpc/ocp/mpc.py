"""Receding-horizon MPC over a shooting problem: shift, warm start, a few solver iterations,
keep the last good plan.

The caller owns the problem's models and updates them (contact sets, references) before each
:meth:`RecedingHorizonMPC.update`; the MPC knows nothing of what the problem means (walking,
manipulation). The solver is injected through the constructor (ours, or Crocoddyl's behind an
adapter in the benchmarks): anything with :class:`MPCSolver`'s interface.

    mpc = RecedingHorizonMPC(problem, dt=0.01, initial_controls=lambda x: u_static)
    sol = mpc.update(t, x_measured)                                     # never raises
    tau = sol.u(1) + sol.K(1) @ state_difference(sol.x(1), x_hat)       # eq. (25), node 1

Gain convention: ``K`` is ∂u*/∂x (the paper's eq. 26, plus sign); apply it to x̂ ⊖ x_k, the
tangent-space difference (pin.difference on q, plain on v), size ndx = 2 nv.
"""

from __future__ import annotations

import math
import time
from contextlib import nullcontext
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.blas import limit_blas_threads
from wbmpc.ocp.solvers.fddp import SolverFDDP


class MPCSolver(Protocol):
    """What :class:`RecedingHorizonMPC` needs of a solver (``SolverFDDP`` has it).

    Attributes after a solve: ``xs`` (N + 1, nx), ``us`` (N, nu), ``K`` (N, nu, ndx) with the
    library's sign (u = u_k + K_k (x ⊖ x_k)), ``cost``, ``preg`` (regularisation reached),
    ``reg_max``, ``deadline_hit`` (the deadline cut the solve), ``log`` (one entry per
    iteration), optionally ``rollouts`` (nonlinear rollouts of the last solve).
    """

    reg_max: float
    deadline_hit: bool

    def solve(self, init_xs, init_us, maxiter: int = 100, is_feasible: bool = False,
              deadline: float | None = None) -> bool:
        """Solve from the guess; True when converged."""

class GainSequence(np.ndarray):
    """Feedback gains (N, nu, ndx), an ndarray that is also callable: ``K(k)`` is ``K[k]``."""

    def __call__(self, k: int) -> np.ndarray:
        return np.asarray(self[k])


@dataclass(frozen=True)
class MPCSolution:
    """One MPC update.

    Attributes:
        ok: False when this update failed (then xs, us, K are the last good solution shifted to t).
        status: "converged", "max_iter", "deadline" (the time budget stopped the iterations; xs,
            us, K are a valid iterate and its gains) or "failed: <reason>".
        iterations: FDDP iterations run by this update.
        cost: total cost of the returned trajectory (NaN if there is none).
        solve_time: wall time of the update [s].
        t: time of node 0 [s].
        xs: (N + 1, nx) predicted states, Pinocchio convention.
        us: (N, nu) torques [N·m].
        K: (N, nu, ndx) feedback gains ∂u/∂x, library sign (u = u_k + K_k (x̂ ⊖ x_k)); also
            callable, ``K(k)`` = ``K[k]``, like the accessors ``u(k)`` and ``x(k)``.
        restart: this update was a cold restart after failures (``RecedingHorizonMPC(
            restart_after_failures=)``): its guess was the quasi-static one, not the last good
            solution shifted (a failed restart still returns that solution, with ok=False).
    """

    ok: bool
    status: str
    iterations: int
    cost: float
    solve_time: float
    t: float
    xs: np.ndarray
    us: np.ndarray
    K: np.ndarray
    restart: bool = False

    def u(self, k: int) -> np.ndarray:
        """Torque of node k (nu,) [N·m]."""
        return self.us[k]

    def x(self, k: int) -> np.ndarray:
        """Predicted state of node k (nx,)."""
        return self.xs[k]

    def __post_init__(self) -> None:
        object.__setattr__(self, "K", np.asarray(self.K, dtype=float).view(GainSequence))


def _phase_keys(contact_keys: list[tuple]) -> list[tuple]:
    """Each node's (contact set, the different contact set of the run of nodes before it); None for the
    horizon's first run, whose predecessor is not in the horizon."""
    keys, previous = [], None
    for j, key in enumerate(contact_keys):
        if j > 0 and key != contact_keys[j - 1]:
            previous = contact_keys[j - 1]
        keys.append((key, previous))
    return keys


def _same_phase(a: tuple, b: tuple) -> bool:
    """Whether two nodes' phase keys are the same phase of the gait (an unknown predecessor matches any)."""
    return a[0] == b[0] and (a[1] is None or b[1] is None or a[1] == b[1])


def _shift(array: np.ndarray, nodes: int) -> np.ndarray:
    """Drop the first ``nodes`` rows and repeat the last row to keep the shape."""
    if nodes <= 0:
        return array.copy()
    nodes = min(nodes, array.shape[0] - 1)
    return np.concatenate([array[nodes:], np.repeat(array[-1:], nodes, axis=0)])


HORIZON_ENDS = ("rollout", "repeat", "phase")
"""Warm-start fills of the nodes entering at the end of the horizon (``RecedingHorizonMPC(horizon_end=)``)."""


def _is_iteration_count(value) -> bool:
    """Whether ``value`` is a solver iteration count: an integer >= 1 (a bool is not one)."""
    return not isinstance(value, bool) and int(value) == value and value >= 1


class RecedingHorizonMPC:
    """Receding-horizon solves of a shooting problem whose models the caller keeps up to date.

    Args:
        problem: the shooting problem (``ShootingProblem`` or ``BatchedShootingProblem``); the
            caller updates its models before each :meth:`update`.
        dt: node spacing [s] (the shift of the warm start is round(elapsed / dt) nodes).
        initial_controls: callable x (nx,) -> u (nu,), the guess of the first (cold) update,
            held over the horizon with the state x; None = zero controls.
        solver: an :class:`MPCSolver` on ``problem``; None = ``SolverFDDP(problem)``.
        max_iterations: solver iterations per update (the paper runs 1).
        cold_start_iterations: iterations of the first update (no warm start yet) and of a restart.
        restart_after_failures: after this many consecutive failed updates, the next update
            starts cold (the quasi-static guess, ``cold_start_iterations``, no time budget)
            instead of warm from the last good solution, which then fails the same way again and
            again; the last good plan is kept until a restart succeeds. A failed restart is the
            first failure of a new count. None or 0 (default): never.
        horizon_end: how the warm start fills the node(s) entering at the end of the shifted
            horizon: "repeat" (default: the last state and control repeated, the usual shift;
            leaves a gap at the end) or "rollout" (the control of the latest node with the same
            contact set, the state rolled out through the node's dynamics: no gap, see
            :meth:`_extend_horizon_end`). "rollout" is what lets Bolt's closed loop run one
            iteration per update (its controller's default); it needs a plan whose end is
            stable: on the G1 benchmark problem, whose cold start ends on a diverging tail, each
            rolled-out node extended the divergence and the MPC failed after 13 ticks. "phase":
            "rollout" with the control of the latest node in the same phase of the gait (the same
            contact set entered from the same other one: a double support after the left foot's
            touchdown is not the one after the right foot's), or, when the horizon holds none,
            ``entering_controls`` (required) at the node's state.
        entering_controls: callable (x (nx,), node index) -> u (nu,), the control of a node entering
            the horizon whose gait phase the horizon does not hold ("phase"), e.g. the quasi-static
            torques of that node's contact set; None (the other fills).
        time_budget: wall time [s] an update may take, counted from its call (a real-time tick's
            deadline, e.g. 0.009 for a 100 Hz loop with 1 ms to spare), or None (no limit). The
            solver starts no iteration or line-search trial that would end after it (see
            ``SolverFDDP.solve``'s ``deadline``); such an update returns status "deadline". The
            cold start (first update) has no budget.
        blas_threads: OpenBLAS thread count within each :meth:`update` and :meth:`prepare`
            (:func:`~wbmpc.ocp.blas.limit_blas_threads`, restored after; 1 by default: the small
            products run 3x faster so on a shared machine), or None to leave it alone.
    """

    def __init__(self, problem, dt: float, initial_controls: Callable[[np.ndarray], np.ndarray] | None = None,
                 solver: MPCSolver | None = None, max_iterations: int = 1, cold_start_iterations: int = 20,
                 horizon_end: str = "repeat", time_budget: float | None = None, blas_threads: int | None = 1,
                 restart_after_failures: int | None = None,
                 entering_controls: Callable[[np.ndarray, int], np.ndarray] | None = None):
        if not _is_iteration_count(max_iterations):
            raise ParameterError(f"max_iterations={max_iterations!r} must be an integer >= 1")
        if int(cold_start_iterations) != cold_start_iterations or cold_start_iterations < 1:
            raise ParameterError(f"cold_start_iterations={cold_start_iterations!r} must be an integer >= 1")
        if horizon_end not in HORIZON_ENDS:
            raise ParameterError(f"horizon_end={horizon_end!r} must be one of {HORIZON_ENDS}")
        if horizon_end == "phase" and entering_controls is None:
            raise ParameterError("horizon_end='phase' needs entering_controls (x, node) -> u")
        self.entering_controls = entering_controls
        if time_budget is not None and (isinstance(time_budget, bool) or not isinstance(time_budget, (int, float))
                                        or not 0 < time_budget < 1e3):
            raise ParameterError(f"time_budget={time_budget!r} must be None or a number of seconds in (0, 1000)")
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt={dt!r} s must be a finite positive number")
        if blas_threads is not None and (isinstance(blas_threads, bool) or not isinstance(blas_threads, int)
                                         or blas_threads < 1):
            raise ParameterError(f"blas_threads={blas_threads!r} must be None or an integer >= 1")
        if restart_after_failures is not None and (
                isinstance(restart_after_failures, bool) or int(restart_after_failures) != restart_after_failures
                or restart_after_failures < 0):
            raise ParameterError(f"restart_after_failures={restart_after_failures!r} must be None, 0 (never) or an "
                                 "integer >= 1 (consecutive failed updates)")
        self.restart_after_failures = int(restart_after_failures or 0)
        self.failures = 0
        """Consecutive failed updates since the last good one or the last restart."""
        self.blas_threads = blas_threads
        self.problem = problem
        self.solver = SolverFDDP(problem) if solver is None else solver
        self.initial_controls = initial_controls
        self.max_iterations = int(max_iterations)
        self.cold_start_iterations = int(cold_start_iterations)
        self.horizon_end = horizon_end
        self.time_budget = None if time_budget is None else float(time_budget)
        self.n_nodes = problem.T
        self.dt = float(dt)
        self.nx, self.ndx, self.nu = problem.nx, problem.ndx, problem.nu
        self.last_good: MPCSolution | None = None

    def warm_start(self, t: float, x_measured: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
        """Initial guess at time t: the last good solution shifted by round((t − t_last)/dt)
        nodes, with x_measured as node 0, and the nodes that enter at the end filled as
        ``horizon_end`` says; a quasi-static guess if there is none. Call after the OCP's update
        (the "rollout" fill reads the new contact sets). Returns (xs_init, us_init, cold)."""
        return self._guess(t, x_measured, self.last_good)

    def _guess(self, t: float, x_measured: np.ndarray, last: MPCSolution | None):
        if last is None:
            xs = np.repeat(x_measured[None, :], self.n_nodes + 1, axis=0)
            u0 = np.zeros(self.nu) if self.initial_controls is None else self.initial_controls(x_measured)
            us = np.repeat(u0[None, :], self.n_nodes, axis=0)
            return xs, us, True
        nodes = int(round((t - last.t) / self.dt))
        xs = _shift(last.xs, nodes)
        us = _shift(last.us, nodes)
        xs[0] = x_measured
        if self.horizon_end in ("rollout", "phase"):
            self._extend_horizon_end(xs, us, min(nodes, self.n_nodes - 1))
        return xs, us, False

    def _contact_keys(self) -> list[tuple]:
        return [model.differential.active_key for model in self.problem.running_models]

    def _extend_horizon_end(self, xs: np.ndarray, us: np.ndarray, nodes: int) -> None:
        """Fill the last ``nodes`` running nodes of a shifted guess (in place): each takes the
        control of the latest earlier node with the same contact set (the last node's when there
        is none; with "phase" the same gait phase, :func:`_phase_keys`, else ``entering_controls``)
        and its successor state is rolled out through the node's dynamics.

        Repeating the last state and control instead leaves a gap at the end of the horizon (one
        step of motion, ~1-3 in velocity units on Bolt) and, when the new node's contact set
        differs (a stance torque on a swinging leg), a gap of ~30 rad/s; FDDP's full step then
        fails its line search: on the Bolt benchmark loop 23 of 300 first steps were rejected
        with repetition, 14 with this extension (docs/ocp.md). A rollout that does not stay
        finite keeps the repeated guess.
        """
        if nodes <= 0:
            return
        models, datas = self.problem.running_models, self.problem.running_datas
        phase = self.horizon_end == "phase"
        keys = _phase_keys(self._contact_keys()) if phase else self._contact_keys()
        match = _same_phase if phase else tuple.__eq__
        N = self.n_nodes
        for j in range(N - nodes, N):
            same = next((i for i in range(j - 1, -1, -1) if match(keys[i], keys[j])), None)
            if same is not None:
                u = us[same]
            else:
                u = self.entering_controls(xs[j], j) if phase else us[j]
            models[j].calc(datas[j], xs[j], u)
            if not np.all(np.isfinite(datas[j].xnext)):
                return
            us[j] = u
            xs[j + 1] = datas[j].xnext

    def prepare(self, deadline: float | None = None) -> int:
        """Between two updates: compute ahead what the next update's FDDP iteration needs and can
        know before the measurement, the contact dynamics and their derivatives at nodes 1..N−1
        of the guess it will make (the last good solution shifted by one node, the contact sets
        shifted with it). The next :meth:`update` takes them where its guess and contact sets
        match exactly (the same torques to the last bit, tested) and computes the rest: node 0
        (the measured state), re-timed contact switches, the entering node, or everything when
        the next update comes later than one node or after a failure.

        This moves about two thirds of the derivative work (~2 ms of a ~6 ms Bolt update,
        N = 100) out of the time between measurement and torque; the total work per cycle is
        unchanged. Call it after handing the solution over and before the next measurement.

        Args:
            deadline: ``time.perf_counter()`` value [s] at which to stop preparing (e.g. shortly
                before the next measurement is due), or None. Preparing fewer nodes is always
                valid: the next update computes the rest, so a real-time loop can give the
                preparation just the slack of its period.

        Returns:
            Nodes prepared (0 before the first good update, or when the problem is not batched).
        """
        if deadline is not None and not math.isfinite(deadline):
            raise ParameterError(f"deadline={deadline} must be a finite time.perf_counter() value or None")
        with self._blas():
            return self._prepare(deadline)

    def _blas(self):
        return nullcontext() if self.blas_threads is None else limit_blas_threads(self.blas_threads)

    def _prepare(self, deadline: float | None) -> int:
        last = self.last_good
        prepare = getattr(self.problem, "prepare_dynamics", None)
        if last is None or prepare is None:
            return 0
        N = self.n_nodes
        keys = self._contact_keys()
        xs = np.empty((N, self.nx))
        us = np.empty((N, self.nu))
        xs[0], us[0] = last.xs[0], last.us[0]  # node 0 will be the measurement: not prepared
        xs[1:] = last.xs[2:]
        us[1:N - 1] = last.us[2:]
        us[N - 1] = last.us[N - 1]  # the entering node as "repeat" fills it (a mismatch is recomputed)
        return prepare(xs, us, [None] + keys[2:] + [keys[N - 1]], deadline=deadline)

    def update(self, t: float, x_measured: np.ndarray,
               update_problem: Callable[[np.ndarray], None] | None = None,
               max_iterations: int | None = None) -> MPCSolution:
        """Re-solve from the measured state; a failing update never raises (it comes back with
        ok=False), a bad ``max_iterations`` is a ParameterError before anything runs.

        Args:
            t: time of the measurement, node 0 [s].
            x_measured: measured state (nx,).
            update_problem: called with the checked state before the warm start, to set the
                problem's models for this update (contacts, references); an exception it raises
                is a failed update like a solver failure (the last good plan is kept).
            max_iterations: FDDP iterations of this warm-started update, an integer >= 1; None =
                ``self.max_iterations`` (a cold start runs ``cold_start_iterations`` either way).
        """
        if max_iterations is not None and not _is_iteration_count(max_iterations):
            raise ParameterError(f"max_iterations={max_iterations!r} must be None or an integer >= 1")
        tic = time.perf_counter()
        with self._blas():
            return self._update(tic, t, x_measured, update_problem,
                                self.max_iterations if max_iterations is None else int(max_iterations))

    def _update(self, tic: float, t: float, x_measured: np.ndarray, update_problem,
                max_iterations: int) -> MPCSolution:
        restart = (self.restart_after_failures > 0 and self.last_good is not None
                   and self.failures >= self.restart_after_failures)
        if restart:
            self.failures = 0
        try:
            x = self.problem.state.check_state("x_measured", x_measured)
            if update_problem is not None:
                update_problem(x)
            else:
                self.problem.set_x0(x)
            xs_init, us_init, cold = self._guess(float(t), x, None if restart else self.last_good)
            iterations = self.cold_start_iterations if cold else max_iterations
            deadline = None if cold or self.time_budget is None else tic + self.time_budget
            converged = self.solver.solve(xs_init, us_init, maxiter=iterations, is_feasible=False, deadline=deadline)
            solver = self.solver
            K = solver.K
            finite = (np.isfinite(solver.cost) and np.all(np.isfinite(solver.xs)) and np.all(np.isfinite(solver.us))
                      and np.all(np.isfinite(K)))
            if not finite:
                raise FloatingPointError("the solution is not finite")
            if not converged and solver.preg >= solver.reg_max:
                raise FloatingPointError(f"regularisation reached reg_max={solver.reg_max} (no descent)")
            solution = MPCSolution(
                ok=True, status="converged" if converged else "deadline" if solver.deadline_hit else "max_iter",
                iterations=len(solver.log),
                cost=float(solver.cost), solve_time=time.perf_counter() - tic, t=float(t),
                xs=solver.xs.copy(), us=solver.us.copy(), K=K, restart=restart,
            )
            self.last_good = solution
            self.failures = 0
            return solution
        except Exception as err:  # the control loop must go on: report and keep the last good plan
            self.failures += 1
            return self._failed(float(t), x_measured, f"failed: {type(err).__name__}: {err}", tic, restart)

    def _failed(self, t: float, x_measured, status: str, tic: float, restart: bool = False) -> MPCSolution:
        last = self.last_good
        nx, ndx, nu, N = self.nx, self.ndx, self.nu, self.n_nodes
        if last is None:
            x = np.asarray(x_measured, dtype=float).reshape(-1)
            xs = np.repeat(x[None, :], N + 1, axis=0) if x.shape == (nx,) else np.full((N + 1, nx), np.nan)
            return MPCSolution(False, status, len(self.solver.log), float("nan"), time.perf_counter() - tic, t,
                               xs, np.zeros((N, nu)), np.zeros((N, nu, ndx)), restart)
        nodes = int(round((t - last.t) / self.dt))
        return MPCSolution(False, status, len(self.solver.log), last.cost, time.perf_counter() - tic,
                           last.t + max(nodes, 0) * self.dt,
                           _shift(last.xs, nodes), _shift(last.us, nodes), _shift(last.K, nodes), restart)
