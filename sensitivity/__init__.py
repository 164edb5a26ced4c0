"""Sensitivity of the footstep QP to a disturbance theta on the measured DCM (Roux et al. 2024, eqs. 6-12).

Python API::

    from sequencer import SequencerParams, StepProblem
    from sensitivity import fiacco_sensitivity, crosscheck
    problem = StepProblem.from_params(SequencerParams.table_i(), "left", [-0.12, 0.10], [-0.12, -0.07], 0.229)
    sens = fiacco_sensitivity(problem)      # sens.dx_dtheta: (5, 2)
    check = crosscheck(problem)             # analytic vs CasADi vs finite differences vs ProxQP backward

The parametric sensitivity of a shooting problem (issue 16: the whole-body OCP to its contact
timings, composed in :mod:`wbmpc.walking.timing`): :mod:`sensitivity.ocp_parametric` (optimality
conditions, exact Lagrangian Hessian, the LQ problem), one route per file: ``ocp_riccati`` (the
sweep), ``ocp_kkt`` (the full KKT system), ``ocp_finite_differences`` (re-solved OCPs).

The ALIP step-to-step NMPC's (ℓ*, T*, τ*) to the measured ALIP state, t_curr and the command (issue 14):
``alip_active_set`` (active / weakly active bounds at IPOPT's optimum), one route per file: ``alip_kkt``
(implicit-function theorem), ``alip_casadi`` (CasADi's derivative of the solver), ``alip_finite_differences``
(re-solved NLPs), and ``alip_crosscheck`` (all three, disagreement, cost)::

    from sensitivity.alip_crosscheck import AlipSensitivityAnalysis
    check = AlipSensitivityAnalysis(AlipParams.preset("g1")).crosscheck(instance)
"""

from sensitivity.crosscheck import Crosscheck, crosscheck
from sensitivity.kkt import DcmSensitivity, DegenerateSensitivity, fiacco_sensitivity

__all__ = ["Crosscheck", "DcmSensitivity", "DegenerateSensitivity", "crosscheck", "fiacco_sensitivity"]
