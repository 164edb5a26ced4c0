"""Reference solver of the ALIP NMPC: CasADi + IPOPT (the paper's solver; bundled with the casadi wheel)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from sequencer.alip.nlp import AlipInstance, AlipNlp, AlipSolution, AlipSolverError

_SUCCESS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


class IpoptSolver:
    """Interior point (exact Hessian, MUMPS), cold-started from :meth:`AlipNlp.initial_guess` unless ``warm`` is given."""

    name = "ipopt"

    def __init__(self, nlp: AlipNlp) -> None:
        self.nlp = nlp
        tol = nlp.params.ipopt_tolerance
        self.solver = ca.nlpsol("alip_ipopt", "ipopt", nlp.nlp, {
            "print_time": False, "error_on_fail": False, "show_eval_warnings": False,
            "ipopt": {"print_level": 0, "sb": "yes", "tol": tol, "constr_viol_tol": tol, "acceptable_iter": 0,
                      "max_iter": nlp.params.max_iterations, "bound_relax_factor": 0.0, "mu_strategy": "adaptive"},
        })

    def solve(self, instance: AlipInstance, warm: AlipSolution | None = None) -> AlipSolution:
        lbw, ubw = self.nlp.scaled_bounds(instance)
        w0 = self.nlp.initial_guess(instance) / self.nlp.scale if warm is None else np.clip(warm.w / self.nlp.scale, lbw, ubw)
        result = self.solver(x0=w0, p=self.nlp.parameters(instance), lbx=lbw, ubx=ubw, lbg=0.0, ubg=0.0)
        stats = self.solver.stats()
        if stats["return_status"] not in _SUCCESS:
            raise AlipSolverError(f"IPOPT failed on the ALIP NMPC: {stats['return_status']}", instance,
                                  stats["return_status"], self.name)
        return self.nlp.solution(result["x"], result["lam_x"], result["lam_g"], float(result["f"]),
                                 stats["iter_count"], self.name, instance)
