"""OSQP backend of the footstep QP: one workspace, set up once, then updated and warm-started."""

from __future__ import annotations

import numpy as np
import osqp
import scipy.sparse as sp

from sequencer.step_qp import InfeasibleStep, StepProblem, StepQPError, StepSolution, solution_from_solver

# Constraint rows: 0-1 the equalities (5), 2-4 the bounds on p_T,x, p_T,y, Gamma.
_INFEASIBLE = {"primal infeasible", "primal infeasible inaccurate", "dual infeasible", "dual infeasible inaccurate"}


class OsqpBackend:
    """Footstep QP through OSQP (paper's choice). Polishing gives an exact active-set solution.

    Args:
        eps_abs, eps_rel: OSQP tolerances [-].
        polishing: run OSQP's solution polishing (recommended: exact multipliers and active set).
    """

    name = "osqp"

    def __init__(self, eps_abs: float = 1e-9, eps_rel: float = 1e-9, polishing: bool = True, max_iter: int = 20000):
        self.settings = dict(
            eps_abs=eps_abs, eps_rel=eps_rel, polishing=polishing, max_iter=max_iter, verbose=False,
            polish_refine_iter=5,
        )
        self._solver: osqp.OSQP | None = None
        self._alpha: np.ndarray | None = None
        self._gamma_entries: np.ndarray | None = None  # indices in A.data of the Gamma column equality entries

    @staticmethod
    def _matrices(problem: StepProblem, data: dict) -> tuple[sp.csc_matrix, sp.csc_matrix, np.ndarray, np.ndarray]:
        P = sp.csc_matrix((np.diag(data["P"]).copy(), np.arange(5), np.arange(6)), shape=(5, 5))
        growth = problem.dcm_growth
        # explicit structure (no dropped zeros): col0 rows (0, 2); col1 (1, 3); col2 (0, 1, 4); col3 (0,); col4 (1,)
        values = np.array([1.0, 1.0, 1.0, 1.0, -growth[0], -growth[1], 1.0, 1.0, 1.0])
        rows = np.array([0, 2, 1, 3, 0, 1, 4, 0, 1])
        indptr = np.array([0, 2, 4, 7, 8, 9])
        A = sp.csc_matrix((values, rows, indptr), shape=(5, 5))
        lower = np.concatenate([data["b"], data["lower"]])
        upper = np.concatenate([data["b"], data["upper"]])
        return P, A, lower, upper

    def solve(self, problem: StepProblem) -> StepSolution:
        data = problem.qp_matrices()
        growth = problem.dcm_growth
        lower = np.concatenate([data["b"], data["lower"]])
        upper = np.concatenate([data["b"], data["upper"]])
        if self._solver is None:
            P, A, lower, upper = self._matrices(problem, data)
            self._solver = osqp.OSQP()
            self._solver.setup(P, data["q"], A, lower, upper, **self.settings)
            self._alpha = problem.alpha.copy()
        else:
            kwargs = dict(q=data["q"], l=lower, u=upper, Ax=np.array([1.0, 1.0, 1.0, 1.0, -growth[0], -growth[1], 1.0, 1.0, 1.0]))
            if not np.array_equal(self._alpha, problem.alpha):
                kwargs["Px"] = np.diag(data["P"]).copy()
                self._alpha = problem.alpha.copy()
            self._solver.update(**kwargs)
        result = self._solver.solve(raise_error=False)  # status handled below
        status = str(result.info.status)
        if status in _INFEASIBLE:
            raise InfeasibleStep("footstep QP is infeasible", problem, status, self.name)
        if status != "solved":
            raise StepQPError("OSQP did not solve the footstep QP", problem, status, self.name)
        return solution_from_solver(
            problem, result.x, result.y[:2], result.y[2:], self.name, status, result.info.iter
        )
