"""Feasibility-driven DDP (Mastalli et al. 2020), the algorithm of Crocoddyl's SolverFDDP.

Each iteration: derivatives of every node at the current guess (xs, us) with its gaps
f_k = f(x_{k-1}, u_{k-1}) ⊖ x_k; a Riccati backward pass with Levenberg-Marquardt
regularisation μ on Quu and Vxx; a nonlinear forward rollout along the step α that closes the
gaps by a factor (1 − α), tried with α = 1, ½, ¼, ... until the cost decrease matches the
expected one (Armijo-like test).

Gain convention (the paper's eqs. 25-26, used everywhere in this library): ``K[k]`` is
∂u_k*/∂x_k (plus sign) and the feedback law is

    u = us[k] + K[k] (x ⊖ xs[k])

with ⊖ the state difference (tangent vector of size ndx = 2 nv). Crocoddyl's ``K`` is the
negative of this one; its feedforward ``k`` likewise (here the search direction is δu = α k).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.linalg import sum_quadratic_forms
from wbmpc.ocp.problem import RolloutError, ShootingProblem
from wbmpc.ocp.solvers.riccati import riccati_backward


@dataclass(frozen=True)
class IterationLog:
    """One FDDP iteration: cost after the iteration, stopping value, accepted step, regularisation,
    dynamic infeasibility (max-norm of the gaps before the step) and the expected improvement."""

    iteration: int
    cost: float
    stop: float
    step_length: float
    regularization: float
    infeasibility: float
    expected_improvement: tuple[float, float]
    feasible: bool


class BackwardPassError(ArithmeticError):
    """Quu not positive definite or NaN in the value function."""


class ForwardPassError(ArithmeticError):
    """NaN in the rollout (raised by the problem's rollout as RolloutError)."""


class SolverFDDP:
    """FDDP solver of a :class:`~wbmpc.ocp.problem.ShootingProblem` (same algorithm and defaults as
    Crocoddyl 3.2's SolverFDDP, so both take the same iterates).

    Args:
        problem: the shooting problem.

    The constructor has no process-wide effect: to solve with single-threaded BLAS (3x faster
    on a shared machine), wrap the solve in :func:`wbmpc.ocp.blas.limit_blas_threads`
    (:class:`~wbmpc.ocp.mpc.RecedingHorizonMPC` does).

    Attributes (after :meth:`solve`):
        xs (N + 1, nx), us (N, nu): current solution.
        K (N, nu, ndx): feedback gains, library sign (u = us[k] + K[k] (x ⊖ xs[k])).
        k (N, nu): feedforward search direction, library sign.
        cost, stop, is_feasible, preg, steplength, log (list of :class:`IterationLog`, one per
        iteration run), iter (Crocoddyl's meaning: index of the converging iteration, or maxiter),
        deadline_hit (the last solve stopped early to meet its ``deadline``), rollouts (number of
        line-search trials, i.e. nonlinear rollouts of the dynamics, the last solve ran).

    Options (attributes): reg_min=1e-9, reg_max=1e9, reg_incfactor=10, reg_decfactor=10,
        th_stop=1e-9, th_grad=1e-12, th_acceptstep=0.1, th_acceptnegstep=2, th_stepdec=0.5,
        th_stepinc=0.01, alphas (line-search trials 1, ½, …, 2⁻⁹; see ``set_max_line_search_trials``).
    """

    def __init__(self, problem: ShootingProblem):
        self.problem = problem
        N, nx, ndx, nu = problem.T, problem.nx, problem.ndx, problem.nu
        self.reg_incfactor = 10.0
        self.reg_decfactor = 10.0
        self.reg_min = 1e-9
        self.reg_max = 1e9
        self.th_grad = 1e-12
        self.th_stepdec = 0.5
        self.th_stepinc = 0.01
        self.th_acceptstep = 0.1
        self.th_acceptnegstep = 2.0
        self.th_stop = 1e-9
        self.alphas = [2.0 ** -n for n in range(10)]
        self.callbacks: list[Callable[["SolverFDDP"], None]] = []
        self.log: list[IterationLog] = []
        self.xs = np.zeros((N + 1, nx))
        self.us = np.zeros((N, nu))
        self.xs_try = np.zeros((N + 1, nx))
        self.us_try = np.zeros((N, nu))
        self.fs = np.zeros((N + 1, ndx))
        self.dx = np.zeros((N, ndx))
        self.Vx = np.zeros((N + 1, ndx))
        self.Vxx = np.zeros((N + 1, ndx, ndx))
        self.Qu = np.zeros((N, nu))
        self.Quu = np.zeros((N, nu, nu))
        self.Quuk = np.zeros((N, nu))
        self._k = np.zeros((N, nu))
        self._K = np.zeros((N, nu, ndx))
        self.cost = 0.0
        self.cost_try = 0.0
        self.stop = 0.0
        self.iter = 0
        self.preg = 0.0
        self.steplength = 1.0
        self.is_feasible = False
        self.was_feasible = False
        self.ffeas = 0.0
        self.d = np.zeros(2)
        self.dg = self.dq = self.dv = 0.0
        self.dV = self.dVexp = 0.0
        self.deadline_hit = False
        self.rollouts = 0
        self._rollout_seconds = 0.0  # duration of the last rollout (deadline estimates)

    # ----------------------------------------------------------------- public API
    @property
    def K(self) -> np.ndarray:
        """Feedback gains ∂u*/∂x, shape (N, nu, ndx), library sign (the negative of Crocoddyl's)."""
        return -self._K

    @property
    def k(self) -> np.ndarray:
        """Feedforward direction, shape (N, nu), library sign (the negative of Crocoddyl's)."""
        return -self._k

    def set_max_line_search_trials(self, n_trials: int) -> None:
        """Use the step lengths 1, ½, …, 2^−(n_trials−1) (Crocoddyl uses 10)."""
        if int(n_trials) != n_trials or n_trials < 1:
            raise ParameterError(f"n_trials={n_trials} must be an integer >= 1")
        self.alphas = [2.0 ** -n for n in range(int(n_trials))]
        self.th_stepinc = max(self.th_stepinc, self.alphas[-1])

    def solve(self, init_xs=None, init_us=None, maxiter: int = 100, is_feasible: bool = False,
              init_reg: float | None = None, deadline: float | None = None) -> bool:
        """Run at most ``maxiter`` iterations from the guess (init_xs, init_us); True if converged.

        Args:
            init_xs: (N + 1, nx) state guess (default: x0 repeated); init_xs[0] may differ from x0.
            init_us: (N, nu) control guess (default: zeros).
            maxiter: iteration cap.
            is_feasible: declare the guess dynamically feasible (xs is the rollout of us).
            init_reg: initial regularisation (default reg_min).
            deadline: ``time.perf_counter()`` value [s] by which to return (a real-time tick), or
                None. Work that would end after it is not started: a further iteration when the
                previous one took longer than the time left, a further line-search trial when the
                previous rollout did. The first trial of the first iteration always runs, so the
                gains always come from a backward pass at the returned iterate. A line search cut
                short keeps the iterate (no step, like a rejected one). ``deadline_hit`` tells.
        """
        problem = self.problem
        if int(maxiter) != maxiter or maxiter < 0:
            raise ParameterError(f"maxiter={maxiter} must be an integer >= 0")
        if deadline is not None and not math.isfinite(deadline):
            raise ParameterError(f"deadline={deadline} must be a finite time.perf_counter() value or None")
        self.xs_try[0] = problem.x0
        self._set_candidate(init_xs, init_us, is_feasible)
        self.preg = self.reg_min if init_reg is None or math.isnan(init_reg) else float(init_reg)
        self.was_feasible = False
        self.log = []
        self.deadline_hit = False
        self.rollouts = 0
        recalc_diff = True
        self.iter = 0
        iteration_start = time.perf_counter()
        iteration_seconds = 0.0
        while self.iter < maxiter:
            if deadline is not None and self.iter > 0:
                now = time.perf_counter()
                iteration_seconds, iteration_start = now - iteration_start, now
                if now + iteration_seconds > deadline:
                    self.deadline_hit = True
                    return False
            while True:
                try:
                    self._compute_direction(recalc_diff)
                except BackwardPassError:
                    recalc_diff = False
                    self._increase_regularization()
                    if self.preg == self.reg_max:
                        return False
                    continue
                break
            infeasibility = self.ffeas
            self._update_expected_improvement()
            recalc_diff = False
            for trial, alpha in enumerate(self.alphas):
                if (deadline is not None and (trial > 0 or self.iter > 0)
                        and time.perf_counter() + self._rollout_seconds > deadline):
                    self.deadline_hit = True
                    break
                self.steplength = alpha
                try:
                    self.dV = self._try_step(alpha)
                except ForwardPassError:
                    continue
                self._expected_improvement()
                self.dVexp = alpha * (self.d[0] + 0.5 * alpha * self.d[1])
                if self.dVexp >= 0:
                    if abs(self.d[0]) < self.th_grad or self.dV > self.th_acceptstep * self.dVexp:
                        self._accept(alpha)
                        recalc_diff = True
                        break
                elif not self.is_feasible and self.dV > self.th_acceptnegstep * self.dVexp:
                    self._accept(alpha)
                    recalc_diff = True
                    break
            if self.deadline_hit:  # the line search was cut short: keep the iterate, report, stop
                self.steplength = 0.0
                self._record_iteration(infeasibility)
                return False
            if self.steplength > self.th_stepdec:
                self._decrease_regularization()
            if self.steplength <= self.th_stepinc:
                self._increase_regularization()
                if self.preg == self.reg_max:
                    return False
            self._record_iteration(infeasibility)
            if self.was_feasible and self.stop < self.th_stop:
                return True  # like Crocoddyl, iter stays the index of the converged iteration
            self.iter += 1
        return False

    def _record_iteration(self, infeasibility: float) -> None:
        """Stopping value, log entry and callbacks of the iteration that just ended."""
        self.stop = abs(self.d[0] + 0.5 * self.d[1])
        self.log.append(IterationLog(self.iter, self.cost, self.stop, self.steplength, self.preg,
                                     infeasibility, (float(self.d[0]), float(self.d[1])), self.is_feasible))
        for callback in self.callbacks:
            callback(self)

    # ----------------------------------------------------------------- algorithm
    def _set_candidate(self, xs, us, is_feasible: bool) -> None:
        problem = self.problem
        N, nx, nu = problem.T, problem.nx, problem.nu
        if xs is None or len(xs) == 0:
            self.xs[:] = problem.state.zero()
        else:
            xs = np.asarray(xs, dtype=float)
            if xs.shape != (N + 1, nx):
                raise ParameterError(f"init_xs has shape {xs.shape}, expected ({N + 1}, {nx})")
            self.xs[:] = xs
        if us is None or len(us) == 0:
            self.us[:] = 0.0
        else:
            us = np.asarray(us, dtype=float)
            if us.shape != (N, nu):
                raise ParameterError(f"init_us has shape {us.shape}, expected ({N}, {nu})")
            self.us[:] = us
        self.is_feasible = bool(is_feasible)

    def _compute_direction(self, recalc_diff: bool) -> None:
        if recalc_diff:
            self._calc_diff()
        self._backward_pass()

    def _calc_diff(self) -> None:
        problem = self.problem
        if self.iter == 0:  # the guess was never evaluated: calc and calcDiff in one pass
            self.cost = problem.calc_and_diff(self.xs, self.us)
        else:  # the accepted rollout already ran calc at (xs, us)
            self.cost = problem.calcDiff(self.xs, self.us)
        self._compute_gaps()

    def _compute_gaps(self) -> None:
        problem = self.problem
        state = problem.state
        state.diff(self.xs[0], problem.x0, out=self.fs[0])
        state.diff_many(self.xs[1:], problem.xnext, out=self.fs[1:])
        self.ffeas = float(np.max(np.abs(self.fs)))

    def _backward_pass(self) -> None:
        p = self.problem
        failed_node = riccati_backward(p.Fx, p.Fu, p.Lx, p.Lu, p.Lxx, p.Lxu, p.Luu, self.fs, self.preg,
                                       self.is_feasible, self.Vx, self.Vxx, self.Qu, self.Quu, self.Quuk,
                                       self._k, self._K)
        if failed_node >= 0:
            raise BackwardPassError(f"Quu not positive definite or value function not finite at node {failed_node}")

    def _update_expected_improvement(self) -> None:
        dg = 0.0
        dq = 0.0
        if not self.is_feasible:
            dg -= float(self.Vx[-1] @ self.fs[-1])
            dq += float(self.fs[-1] @ (self.Vxx[-1] @ self.fs[-1]))
        dg += float(np.einsum("ti,ti->", self.Qu, self._k))
        dq -= float(np.einsum("ti,ti->", self._k, self.Quuk))
        if not self.is_feasible:
            N = self.problem.T
            dg -= float(np.einsum("ti,ti->", self.Vx[:N], self.fs[:N]))
            dq += sum_quadratic_forms(self.fs[:N], self.Vxx[:N], self.fs[:N])
        self.dg, self.dq = dg, dq

    def _expected_improvement(self) -> None:
        dv = 0.0
        if not self.is_feasible:
            state = self.problem.state
            N = self.problem.T
            dx_T = state.diff(self.xs_try[N], self.xs[N])
            dv -= float(self.fs[N] @ (self.Vxx[N] @ dx_T))
            state.diff_many(self.xs_try[:N], self.xs[:N], out=self.dx)
            dv -= sum_quadratic_forms(self.fs[:N], self.Vxx[:N], self.dx)
        self.dv = dv
        self.d[0] = self.dg + dv
        self.d[1] = self.dq - 2.0 * dv

    def _try_step(self, alpha: float) -> float:
        self.rollouts += 1
        tic = time.perf_counter()
        try:
            self._forward_pass(alpha)
        finally:
            self._rollout_seconds = time.perf_counter() - tic
        return self.cost - self.cost_try

    def _forward_pass(self, alpha: float) -> None:
        try:
            self.cost_try = self.problem.forward_rollout(
                self.xs, self.us, self._k, self._K, None if self.is_feasible else self.fs, alpha,
                self.xs_try, self.us_try, self.dx)
        except RolloutError as err:
            raise ForwardPassError(str(err)) from err

    def _accept(self, alpha: float) -> None:
        self.was_feasible = self.is_feasible
        self.xs[:] = self.xs_try
        self.us[:] = self.us_try
        self.is_feasible = self.was_feasible or alpha == 1.0
        self.cost = self.cost_try

    def _increase_regularization(self) -> None:
        self.preg = min(self.preg * self.reg_incfactor, self.reg_max)

    def _decrease_regularization(self) -> None:
        self.preg = max(self.preg / self.reg_decfactor, self.reg_min)
