"""Sensitivity of the footstep QP to a disturbance theta on the measured DCM (Roux et al. 2024, eqs. 6-12).

Python API::

    from sequencer import SequencerParams, StepProblem
    from sensitivity import fiacco_sensitivity, crosscheck
    problem = StepProblem.from_params(SequencerParams.table_i(), "left", [-0.12, 0.10], [-0.12, -0.07], 0.229)
    sens = fiacco_sensitivity(problem)      # sens.dx_dtheta: (5, 2)
    check = crosscheck(problem)             # analytic vs CasADi vs finite differences vs ProxQP backward
"""

from sensitivity.crosscheck import Crosscheck, crosscheck
from sensitivity.kkt import DcmSensitivity, DegenerateSensitivity, fiacco_sensitivity

__all__ = ["Crosscheck", "DcmSensitivity", "DegenerateSensitivity", "crosscheck", "fiacco_sensitivity"]
