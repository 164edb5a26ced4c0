"""Fast path of the ALIP NMPC: CasADi's SQP (exact Hessian) with the qrqp active-set QP, warm-started.

The same symbolic, scaled NLP as :mod:`sequencer.alip.ipopt_` (:class:`sequencer.alip.nlp.AlipNlp`). Two
configurations of one method, each one C++ call:

- *local*: full Newton-SQP steps (no line search), the real-time iteration of a receding-horizon loop: from
  the previous plan's primal-dual solution (``warm``) it converges quadratically in 2-4 iterations;
- *globalised*: the same SQP with its merit line search, from the cold start (:meth:`AlipNlp.initial_guess`),
  without a warm start or when the local iteration from it fails (a warm start far from the new optimum).
  Near the optimum its line search can reject a step of round-off size (status
  ``Search_Direction_Becomes_Too_Small``) before the multipliers are updated: the local iteration then
  finishes from that point (a polish).

The sequence is the method, not a silent fallback: :attr:`AlipSolution.iterations` counts all SQP
iterations and a failure of the last phase raises :class:`~sequencer.alip.nlp.AlipSolverError`.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from sequencer.alip.nlp import AlipInstance, AlipNlp, AlipSolution, AlipSolverError

_POLISH = ("Search_Direction_Becomes_Too_Small",)


class SqpSolver:
    """SQP + qrqp; ``solve(instance, warm)`` with ``warm`` an :class:`AlipSolution` (None: cold start)."""

    name = "sqp"

    def __init__(self, nlp: AlipNlp) -> None:
        self.nlp = nlp
        tol = nlp.params.tolerance
        options = {
            "qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "error_on_fail": False},
            "print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
            "error_on_fail": False, "show_eval_warnings": False, "max_iter": nlp.params.max_iterations, "tol_pr": tol,
            "tol_du": tol,
            "min_step_size": 1e-14, "hessian_approximation": "exact",
        }
        self.globalised = ca.nlpsol("alip_sqp", "sqpmethod", nlp.nlp, options)
        self.local = ca.nlpsol("alip_sqp_local", "sqpmethod", nlp.nlp, {**options, "max_iter_ls": 0})

    def _run(self, solver, p, lbw, ubw, x0, lam_x0=None, lam_g0=None):
        args = {"x0": x0} if lam_x0 is None else {"x0": x0, "lam_x0": lam_x0, "lam_g0": lam_g0}
        result = solver(p=p, lbx=lbw, ubx=ubw, lbg=0.0, ubg=0.0, **args)
        stats = solver.stats()
        return result, stats

    def solve(self, instance: AlipInstance, warm: AlipSolution | None = None) -> AlipSolution:
        nlp = self.nlp
        lbw, ubw = nlp.scaled_bounds(instance)
        p = nlp.parameters(instance)
        iterations = 0
        stats = {"success": False, "return_status": "not run"}
        if warm is not None:
            result, stats = self._run(self.local, p, lbw, ubw, np.clip(warm.w / nlp.scale, lbw, ubw),
                                      warm.lam_w, warm.lam_g)
            iterations += stats["iter_count"]
        if not stats["success"]:
            result, stats = self._run(self.globalised, p, lbw, ubw, nlp.initial_guess(instance) / nlp.scale)
            iterations += stats["iter_count"]
            if not stats["success"] and stats["return_status"] in _POLISH:
                result, stats = self._run(self.local, p, lbw, ubw, result["x"], result["lam_x"], result["lam_g"])
                iterations += stats["iter_count"]
        if not stats["success"]:
            raise AlipSolverError(f"SQP failed on the ALIP NMPC: {stats['return_status']}", instance,
                                  stats["return_status"], self.name)
        return nlp.solution(result["x"], result["lam_x"], result["lam_g"], float(result["f"]), iterations, self.name,
                            instance)
