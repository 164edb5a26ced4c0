"""Footstep planners and the contact-schedule types (DCM step QP: Roux et al. 2024, section II; Khadiv et al. 2020).

Python API (the controller's: one planner interface, a plan, its schedule)::

    from sequencer import (DcmFootstepPlanner, LipmCorrections, ReducedState, SequencerParams,
                           StanceState, VelocityCommand, contact_schedule)
    params = SequencerParams.bolt_walking()             # or .table_i(), .from_toml(path)
    planner = DcmFootstepPlanner(params, backend="exact")
    planner.check_command(VelocityCommand(0.3, 0.0, 0.2))
    plan = planner.plan(t, StanceState("left", p0_xy, yaw, t_start), ReducedState(com, vcom, dcm_xy),
                        VelocityCommand(0.3, 0.0, 0.2))
    schedule = contact_schedule(plan, t0=t, dt=0.01, n_nodes=100, rounding="nearest")
    com_terminal = plan.com_reference(t + 1.0, com[:2])          # (3,), world frame
    planner.corrections.swing_drift = 0.2                       # read by the next plan

Algorithm 1 directly (world frame, the paper's example)::

    seq = FootstepSequencer(params, backend="exact")    # or "osqp", "proxqp"
    plan = seq.plan(t=0.229, stance_foot="left", stance_position=[-0.12, 0.10],
                    dcm_measured=[-0.12, -0.07], t_stance_start=0.0)
"""

from sequencer.corrections import LipmCorrections
from sequencer.dcm_planner import DcmFootstepPlanner
from sequencer.horizon import FootstepPlan, FootstepSequencer, PlannedStep
from sequencer.nominal import NominalGait, nominal_dcm_offset
from sequencer.params import SequencerParams
from sequencer.planner import FootstepPlanner, ReducedState, StanceState, VelocityCommand
from sequencer.schedule import ContactSchedule, contact_schedule, timed_contact_schedule
from sequencer.step_qp import InfeasibleStep, StepProblem, StepQPError, StepSolution

__all__ = [
    "ContactSchedule",
    "DcmFootstepPlanner",
    "FootstepPlan",
    "FootstepPlanner",
    "FootstepSequencer",
    "InfeasibleStep",
    "LipmCorrections",
    "NominalGait",
    "PlannedStep",
    "ReducedState",
    "SequencerParams",
    "StanceState",
    "StepProblem",
    "StepQPError",
    "StepSolution",
    "VelocityCommand",
    "contact_schedule",
    "nominal_dcm_offset",
    "timed_contact_schedule",
]
