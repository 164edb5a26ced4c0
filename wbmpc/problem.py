"""Shooting problem: x0, N running nodes and a terminal node (paper eq. 17).

    min Σ_{k<N} l_k(x_k, u_k) + l_N(x_N)   s.t.  x_0 = x0,  x_{k+1} = f_k(x_k, u_k)
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError


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

        ``Fx`` (N, ndx, ndx), ``Fu`` (N, ndx, nu), ``Lx`` (N + 1, ndx), ``Lu`` (N, nu),
        ``Lxx`` (N + 1, ndx, ndx), ``Lxu`` (N, ndx, nu), ``Luu`` (N, nu, nu): the solver's
        Riccati pass reads them without gathering (row N is the terminal node).
        """
        N, ndx = self.T, self.ndx
        nu = self.running_models[0].nu
        if any(m.nu != nu for m in self.running_models):
            raise ParameterError("every running node must have the same control dimension nu")
        self.nu = nu
        self.Fx = np.zeros((N, ndx, ndx))
        self.Fu = np.zeros((N, ndx, nu))
        self.Lx = np.zeros((N + 1, ndx))
        self.Lu = np.zeros((N, nu))
        self.Lxx = np.zeros((N + 1, ndx, ndx))
        self.Lxu = np.zeros((N, ndx, nu))
        self.Luu = np.zeros((N, nu, nu))
        for k, d in enumerate(self.running_datas):
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
