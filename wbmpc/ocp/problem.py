"""Shooting problem: x0, N running nodes and a terminal node (paper eq. 17).

    min Σ_{k<N} l_k(x_k, u_k) + l_N(x_N)   s.t.  x_0 = x0,  x_{k+1} = f_k(x_k, u_k)
"""

from __future__ import annotations

import math

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.feedback import feedback_control, free_flyer_feedback_control


class RolloutError(ArithmeticError):
    """A forward rollout produced a non-finite control, state or cost."""


class ShootingProblem:
    """Nodes of an optimal control problem and their data (one data object per node).

    Args:
        x0: initial state (nx,), Pinocchio convention.
        running_models: N integrated action models (with a control).
        terminal_model: the terminal node (evaluated without control).
    """

    def __init__(self, x0: np.ndarray, running_models: list, terminal_model):
        if len(running_models) == 0:
            raise ParameterError("a shooting problem needs at least one running node (got 0)")
        self.running_models = list(running_models)
        self.terminal_model = terminal_model
        self.state = terminal_model.state
        self.nx = self.state.nx
        self.ndx = self.state.ndx
        self.x0 = self.state.check_state("x0", x0).copy()
        self.running_datas = [m.createData() for m in self.running_models]
        self.terminal_data = terminal_model.createData()
        self.cost = 0.0
        self._stack_derivatives()

    def _stack_derivatives(self) -> None:
        """Make every node's derivative buffers views of stacked arrays.

        ``xnext`` (N, nx) next states f(x_k, u_k), ``Fx`` (N, ndx, ndx), ``Fu`` (N, ndx, nu),
        ``Lx`` (N + 1, ndx), ``Lu`` (N, nu), ``Lxx`` (N + 1, ndx, ndx), ``Lxu`` (N, ndx, nu),
        ``Luu`` (N, nu, nu): the solver reads them without gathering (row N is the terminal node).
        """
        N, ndx = self.T, self.ndx
        nu = self.running_models[0].nu
        if any(m.nu != nu for m in self.running_models):
            raise ParameterError("every running node must have the same control dimension nu")
        self.nu = nu
        self.xnext = np.zeros((N, self.nx))
        self.Fx = np.zeros((N, ndx, ndx))
        self.Fu = np.zeros((N, ndx, nu))
        self.Lx = np.zeros((N + 1, ndx))
        self.Lu = np.zeros((N, nu))
        self.Lxx = np.zeros((N + 1, ndx, ndx))
        self.Lxu = np.zeros((N, ndx, nu))
        self.Luu = np.zeros((N, nu, nu))
        for k, d in enumerate(self.running_datas):
            self.xnext[k] = d.xnext
            d.xnext = self.xnext[k]
            d.Fx, d.Fu, d.Lx, d.Lu = self.Fx[k], self.Fu[k], self.Lx[k], self.Lu[k]
            d.Lxx, d.Lxu, d.Luu = self.Lxx[k], self.Lxu[k], self.Luu[k]
        self.terminal_data.Lx = self.Lx[N]
        self.terminal_data.Lxx = self.Lxx[N]

    @property
    def T(self) -> int:
        """Number of running nodes N."""
        return len(self.running_models)

    def set_x0(self, x0: np.ndarray) -> None:
        self.x0[:] = self.state.check_state("x0", x0)

    def calc(self, xs, us) -> float:
        """Evaluate every node (next states and costs); returns the total cost."""
        cost = 0.0
        for m, d, x, u in zip(self.running_models, self.running_datas, xs, us):
            m.calc(d, x, u)
            cost += d.cost
        self.terminal_model.calc(self.terminal_data, xs[-1])
        cost += self.terminal_data.cost
        self.cost = cost
        return cost

    def calcDiff(self, xs, us) -> float:
        """Derivatives of every node (needs calc at the same xs, us); returns the total cost."""
        cost = 0.0
        for m, d, x, u in zip(self.running_models, self.running_datas, xs, us):
            m.calcDiff(d, x, u)
            cost += d.cost
        self.terminal_model.calcDiff(self.terminal_data, xs[-1])
        cost += self.terminal_data.cost
        self.cost = cost
        return cost

    def calc_and_diff(self, xs, us) -> float:
        """calc then calcDiff node by node (one pass, the node's data still in cache); returns the
        total cost. Same results as :meth:`calc` followed by :meth:`calcDiff`."""
        cost = 0.0
        for m, d, x, u in zip(self.running_models, self.running_datas, xs, us):
            m.calc(d, x, u)
            m.calcDiff(d, x, u)
            cost += d.cost
        self.terminal_model.calc(self.terminal_data, xs[-1])
        self.terminal_model.calcDiff(self.terminal_data, xs[-1])
        cost += self.terminal_data.cost
        self.cost = cost
        return cost

    def rollout(self, us) -> list[np.ndarray]:
        """States obtained by integrating the controls from x0, list of N + 1 arrays (nx,)."""
        xs = [self.x0.copy()]
        for m, d, u in zip(self.running_models, self.running_datas, us):
            m.calc(d, xs[-1], u)
            xs.append(d.xnext.copy())
        return xs

    def forward_rollout(self, xs, us, k, K, fs, alpha: float, xs_try, us_try, dx) -> float:
        """FDDP rollout along the step α; returns its total cost.

        From x0, node by node: x_try[t] = f(x_try[t−1], u_try[t−1]) ⊕ (α − 1) fs[t] (gaps
        closed by 1 − α; plain rollout when α = 1 or ``fs`` is None) and
        u_try[t] = us[t] − α k[t] − K[t] (x_try[t] ⊖ xs[t]) (Crocoddyl's sign of k, K).

        Args:
            xs (N + 1, nx), us (N, nu): current trajectory; k (N, nu), K (N, nu, ndx): Riccati
            terms; fs (N + 1, ndx) gaps or None; outputs xs_try, us_try, dx (N, ndx) = x_try ⊖ xs.

        Raises:
            RolloutError: a control, state or the cost is not finite.
        """
        state = self.state
        N = self.T
        closing = not (alpha == 1.0 or fs is None)
        cost = 0.0
        xnext = self.x0
        for t, (m, d) in enumerate(zip(self.running_models, self.running_datas)):
            x_try = xs_try[t]
            if closing:
                state.integrate(xnext, fs[t] * (alpha - 1.0), out=x_try)
            else:
                x_try[:] = xnext
            self._feedback(t, xs, us, k, K, alpha, x_try, dx, us_try)
            m.calc(d, x_try, us_try[t])
            xnext = d.xnext
            cost += d.cost
            if not (math.isfinite(cost) and math.isfinite(xnext.sum())):
                raise RolloutError(f"rollout diverged at node {t}")
        if closing:
            state.integrate(xnext, fs[N] * (alpha - 1.0), out=xs_try[N])
        else:
            xs_try[N] = xnext
        self.terminal_model.calc(self.terminal_data, xs_try[N])
        cost += self.terminal_data.cost
        if not math.isfinite(cost):
            raise RolloutError("terminal cost not finite")
        return cost

    def _feedback(self, t: int, xs, us, k, K, alpha: float, x_try, dx, us_try) -> None:
        """us_try[t] = us[t] − α k[t] − K[t] (x_try ⊖ xs[t]), dx[t] = x_try ⊖ xs[t]."""
        state = self.state
        code = free_flyer_feedback_control(xs[t], x_try, us[t], k[t], K[t], alpha, state.nq, dx[t], us_try[t]) \
            if state._compiled_difference else 1
        if code == 1:  # not a free flyer, or a relative half turn: Pinocchio's difference
            state.diff(xs[t], x_try, out=dx[t])
            code = 0 if feedback_control(us[t], k[t], K[t], dx[t], alpha, us_try[t]) else 2
        if code == 2:
            raise RolloutError(f"control not finite at node {t}")

    def term_costs(self) -> dict[str, float]:
        """Total cost of each named term over the horizon (after calc), running terms scaled by dt."""
        totals: dict[str, float] = {}
        for m, d in zip(self.running_models, self.running_datas):
            for name, cost in m.differential.costs.term_costs(d.differential.costs).items():
                totals[name] = totals.get(name, 0.0) + m.dt * cost
        terminal = self.terminal_model.differential.costs
        for name, cost in terminal.term_costs(self.terminal_data.differential.costs).items():
            totals[f"terminal_{name}"] = totals.get(f"terminal_{name}", 0.0) + cost
        return totals
