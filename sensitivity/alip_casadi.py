"""Route (b) to the ALIP NMPC's sensitivity: CasADi's own derivative of the IPOPT solver function.

``casadi.nlpsol`` solvers are differentiable functions of their inputs (x0, p, lbx, ubx, lbg, ubg): their
forward derivative (``solver.forward(n)``) assembles and solves the KKT sensitivity system itself (its
``sens_linsol``, QR by default), reading the active set from the nonzero bound multipliers ``lam_x``. The
seeds here are dp/dθ and d lbx/dθ of :meth:`sequencer.alip.nlp.AlipNlp.parameter_jacobian`, all 8 columns in
one forward call, at IPOPT's optimum.

What does not work: ``casadi.jacobian`` of the solver's output with respect to a symbolic p (the same
forward derivative, with the multipliers IPOPT returns). An interior point leaves every inactive bound a
multiplier of ≈ 1e-11 to 5e-9, not 0, so CasADi counts every bound active (and both bounds of a variable
at once): the derivative call fails ("Evaluation failed"; casadi 3.8.2) or returns NaN. The nominal outputs
handed to the forward function therefore carry the multipliers of
:meth:`~sensitivity.alip_active_set.AlipActiveSet.clean_multipliers` (inactive ones exactly 0), the same
active set as route (a); the KKT assembly, factorisation and solve are CasADi's.

CasADi reads the equality constraints' activity from their multipliers' signs as well (``lam_g > min_lam``
or ``< −min_lam``, ``Nlpsol::get_forward``; casadi issue #2545). An S2S constraint whose multiplier is exactly
0 (e.g. the sagittal ones on the orbit at v_x = 0: the sagittal state is on its target, no cost gradient)
is then dropped from the sensitivity system and the derivative comes out wrong (0 for every sagittal
quantity on that instance, against route (a) and the re-solves). The S2S constraints are equalities, always
active: their exact zeros are handed to CasADi as 1e-300, which marks them active and changes the Hessian
λ_gᵀ∇²g by 1e-300 (:data:`EQUALITY_MARK`).
"""

from __future__ import annotations

import numpy as np

from sensitivity.alip_active_set import AlipActiveSet, detect_active_set
from sensitivity.alip_kkt import AlipSensitivity
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import SENSITIVITY_PARAMETERS, AlipInstance, AlipSolution
from wbmpc.errors import SolverError

#: what an exactly-zero S2S multiplier is replaced by so that CasADi keeps the equality in its KKT system
EQUALITY_MARK = 1e-300


class AlipCasadiRoute:
    """Route (b) on an :class:`~sequencer.alip.ipopt_.IpoptSolver`'s ``nlpsol`` function (forward derivative built once)."""

    name = "casadi"

    def __init__(self, ipopt: IpoptSolver) -> None:
        self.ipopt = ipopt
        self.nlp = ipopt.nlp
        self._forward = ipopt.solver.forward(len(SENSITIVITY_PARAMETERS))

    def sensitivity(self, instance: AlipInstance, solution: AlipSolution,
                    active: AlipActiveSet | None = None) -> AlipSensitivity:
        """dw*/dθ from the solver's forward derivative at ``solution`` (IPOPT's optimum of ``instance``).

        Raises:
            SolverError: CasADi's sensitivity system failed or returned non-finite values.
        """
        nlp = self.nlp
        if active is None:
            active = detect_active_set(nlp, instance, solution)
        dp, dlb = nlp.parameter_jacobian(instance)
        lbw, ubw = nlp.scaled_bounds(instance)
        w_s = solution.w / nlp.scale
        n = len(SENSITIVITY_PARAMETERS)
        lam_g = np.where(solution.lam_g == 0.0, EQUALITY_MARK, solution.lam_g)  # equalities: always active
        try:
            out = self._forward(
                x0=w_s, p=nlp.parameters(instance), lbx=lbw, ubx=ubw, lbg=0.0, ubg=0.0, lam_x0=solution.lam_w,
                lam_g0=lam_g, out_x=w_s, out_f=solution.cost, out_g=0.0,
                out_lam_x=active.clean_multipliers(solution.lam_w), out_lam_g=lam_g, out_lam_p=0.0,
                fwd_x0=np.zeros((nlp.n_w, n)), fwd_p=dp, fwd_lbx=dlb / nlp.scale[:, None], fwd_ubx=np.zeros((nlp.n_w, n)),
                fwd_lbg=np.zeros((nlp.n_g, n)), fwd_ubg=np.zeros((nlp.n_g, n)), fwd_lam_x0=np.zeros((nlp.n_w, n)),
                fwd_lam_g0=np.zeros((nlp.n_g, n)))
        except RuntimeError as err:
            raise SolverError(f"CasADi's derivative of the IPOPT solver failed: {' '.join(str(err).split())[-200:]}") from err
        dw_s = np.asarray(out["fwd_x"], dtype=float)
        if not np.all(np.isfinite(dw_s)):
            raise SolverError("CasADi's derivative of the IPOPT solver is not finite (singular sensitivity system)")
        return AlipSensitivity(instance=instance, solution=solution, dw_dtheta=dw_s * nlp.scale[:, None], active=active,
                               method=self.name, names=tuple(nlp.names),
                               dlam_g_dtheta=np.asarray(out["fwd_lam_g"], dtype=float))
