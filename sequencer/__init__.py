"""DCM footstep sequencer (Roux et al. 2024, section II; Khadiv et al. 2020).

Python API::

    from sequencer import SequencerParams, FootstepSequencer, contact_schedule
    params = SequencerParams.table_i()                  # or .bolt_walking(), .from_toml(path)
    seq = FootstepSequencer(params, backend="exact")    # or "osqp", "proxqp"
    plan = seq.plan(t=0.229, stance_foot="left", stance_position=[-0.12, 0.10],
                    dcm_measured=[-0.12, -0.07], t_stance_start=0.0)
    schedule = contact_schedule(plan, t0=plan.t0, dt=0.01, n_nodes=100)
"""

from sequencer.horizon import FootstepPlan, FootstepSequencer, PlannedStep
from sequencer.nominal import nominal_dcm_offset
from sequencer.params import SequencerParams
from sequencer.schedule import ContactSchedule, contact_schedule
from sequencer.step_qp import InfeasibleStep, StepProblem, StepQPError, StepSolution

__all__ = [
    "ContactSchedule",
    "FootstepPlan",
    "FootstepSequencer",
    "InfeasibleStep",
    "PlannedStep",
    "SequencerParams",
    "StepProblem",
    "StepQPError",
    "StepSolution",
    "contact_schedule",
    "nominal_dcm_offset",
]
