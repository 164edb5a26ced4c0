"""ProxQP (ProxSuite, dense) backend of the footstep QP: one workspace, updated and warm-started.

A warm start from the previous step's result can stall at ProxQP's iteration limit on an instance a cold
start solves in a few iterations (seen with proxsuite 0.7.3: 10 000 iterations warm, 5 cold, on the same
5-variable QP); the backend then rebuilds the workspace and solves once more from no initial guess before it
reports a failure.
"""

from __future__ import annotations

import proxsuite

from sequencer.step_qp import InfeasibleStep, StepProblem, StepQPError, StepSolution, solution_from_solver

_PROXQP = proxsuite.proxqp


class ProxqpBackend:
    """Footstep QP through ProxQP (dense, 5 variables, 2 equalities, 3 bounds as inequalities).

    Args:
        eps_abs: ProxQP absolute tolerance [-].
    """

    name = "proxqp"

    def __init__(self, eps_abs: float = 1e-10, eps_rel: float = 0.0):
        self.eps_abs = eps_abs
        self.eps_rel = eps_rel
        self.qp: _PROXQP.dense.QP | None = None

    def _new_qp(self) -> "_PROXQP.dense.QP":
        qp = _PROXQP.dense.QP(5, 2, 3)
        qp.settings.eps_abs = self.eps_abs
        qp.settings.eps_rel = self.eps_rel
        qp.settings.verbose = False
        qp.settings.initial_guess = _PROXQP.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        return qp

    def _solve_cold(self, data: dict) -> None:
        self.qp = self._new_qp()
        self.qp.init(data["P"], data["q"], data["A"], data["b"], data["C"], data["lower"], data["upper"])
        self.qp.solve()

    def solve(self, problem: StepProblem) -> StepSolution:
        data = problem.qp_matrices()
        if self.qp is None:
            self._solve_cold(data)
        else:
            self.qp.update(H=data["P"], g=data["q"], A=data["A"], b=data["b"], l=data["lower"], u=data["upper"])
            self.qp.solve()
            if self.qp.results.info.status not in (
                _PROXQP.QPSolverOutput.PROXQP_SOLVED,
                _PROXQP.QPSolverOutput.PROXQP_PRIMAL_INFEASIBLE,
            ):
                self._solve_cold(data)
        info = self.qp.results.info
        status = str(info.status).split(".")[-1]
        if info.status == _PROXQP.QPSolverOutput.PROXQP_PRIMAL_INFEASIBLE:
            raise InfeasibleStep("footstep QP is infeasible", problem, status, self.name)
        if info.status != _PROXQP.QPSolverOutput.PROXQP_SOLVED:
            raise StepQPError("ProxQP did not solve the footstep QP", problem, status, self.name)
        results = self.qp.results
        return solution_from_solver(problem, results.x, results.y, results.z, self.name, status, info.iter)
