"""ALIP step-to-step NMPC footstep planner (seed 001: "Hierarchical Reduced-Order Model Predictive Control for
Robust Locomotion on Humanoid Robots", sections 2.3-3, eqs. 4-16), behind sequencer.planner.FootstepPlanner.

One concept per module: ``model`` (ALIP, Φ(T), Γ(T)), ``s2s`` (reset with B_d 4x2, corrected S2S map),
``params`` (AlipParams, presets in sequencer/presets/alip/), ``nlp`` (eq. 11, desired values, instance,
solution, AlipSolverError), ``ipopt_`` (reference), ``sqp_`` (fast path), ``planner`` (AlipFootstepPlanner),
``instances`` (random instances for tests and benchmarks), ``plots``::

    from sequencer.alip import AlipFootstepPlanner, AlipParams
    planner = AlipFootstepPlanner(AlipParams.preset("g1"), solver="sqp")   # or "ipopt"
    plan = planner.plan(t, stance, measured, command)                      # a FootstepPlan
    planner.last_solution.periods, planner.last_solution.torques           # T_k [s], τ_k [N·m]
"""

from sequencer.alip.model import AlipModel
from sequencer.alip.nlp import AlipInstance, AlipNlp, AlipSolution, AlipSolverError
from sequencer.alip.params import AlipParams
from sequencer.alip.planner import AlipFootstepPlanner

__all__ = ["AlipFootstepPlanner", "AlipInstance", "AlipModel", "AlipNlp", "AlipParams", "AlipSolution",
           "AlipSolverError"]
