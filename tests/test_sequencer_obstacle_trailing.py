"""The trailing swing's travel bound (``obstacle_swing_length_max``) never puts its foothold inside the box."""

from __future__ import annotations

import numpy as np
import pytest

from sequencer.dcm_planner import DcmFootstepPlanner
from sequencer.footholds import FootholdConstraints, along_heading, sole_on_obstacle
from sequencer.obstacles import Obstacle
from sequencer.planner import ReducedState, StanceState, VelocityCommand
from wbmpc.walking.preset import load_walking_preset

BOX = Obstacle(center=np.array([1.05, 0.0]), yaw=0.0, depth=0.1, width=1.2, height=0.1)
COMMAND = VelocityCommand(0.3, 0.0, 0.0)
# the planner's state at t = 2.7 s of docs/scripts/h1_step_over.py with the overrides below (the right stance
# four steps before the box; the lead crossing lands at 1.3175 m, the trailing foot lifts off at 0.8175 m)
STANCE = StanceState("right", np.array([0.45196, -0.20771]), 0.0, 2.54, swing_liftoff=np.array([0.36136, 0.21201]))
MEASURED = ReducedState(np.array([0.43090, -0.02945, 0.99110]), np.array([0.22063, -0.00391, 0.14632]),
                        np.array([0.50027, -0.03068]))


def _params(swing_length_max: float):
    return load_walking_preset("h1", {"planner.obstacle_swing_length_max": swing_length_max,
                                      "planner.obstacle_trailing_double_support": 0.6,
                                      "planner.obstacle_aim_duration": 0.6}).planner_params


def test_a_travel_bound_too_short_to_clear_the_box_ends_at_its_far_side():
    """s_max = 0.3 m from a lift-off 0.5 m behind the lead foot ended the bound inside the box: the planner
    found no foothold from 2.7 s on (FootholdInfeasible). The bound now stops at the box's far side."""
    params = _params(0.3)
    plan = DcmFootstepPlanner(params).plan(2.7, STANCE, MEASURED, COMMAND, obstacles=(BOX,))
    crossing = [i for i, step in enumerate(plan.steps) if step.crossing is not None]
    assert len(crossing) == 2  # the lead and the trailing swing
    lead, trailing = (plan.steps[i] for i in crossing)
    far = BOX.center[0] + BOX.depth / 2 + params.obstacle_margin + params.sole_rear
    assert lead.position[0] >= far - 1e-9 and trailing.position[0] == pytest.approx(lead.position[0], abs=1e-6)
    assert not any(sole_on_obstacle((BOX,), step.position, step.yaw, params.foothold_geometry()) for step in plan.steps)

def test_a_travel_bound_that_clears_the_box_still_bounds_the_trailing_swing():
    params = _params(0.75)
    plan = DcmFootstepPlanner(params).plan(2.7, STANCE, MEASURED, COMMAND, obstacles=(BOX,))
    lead, trailing = (step for step in plan.steps if step.crossing is not None)
    previous = plan.steps[[step.crossing is not None for step in plan.steps].index(True) - 1]
    assert trailing.position[0] - previous.position[0] <= 0.75 + 1e-6



def test_the_trailing_bounds_without_a_box_in_the_way_are_the_travel_bound():
    chooser = FootholdConstraints((BOX,), _params(0.3).foothold_geometry(), 3.2)
    bounds = (-0.3, 0.3, -0.6, -0.3, 0.3, 0.8)
    p0, liftoff = np.array([0.8, 0.2]), np.array([0.6, -0.2])  # lift-off 0.2 m behind: ℓ <= 0.1
    lift_along = along_heading(liftoff, p0, 0.0)
    free_box = (0.5, 0.7, -1.0, 1.0)  # ahead of the bound's end: not in the way
    assert chooser._trailing_bounds(bounds, lift_along, 1.0, [free_box], 0.25)[:2] == pytest.approx((-0.3, 0.1))
    in_way = (0.0, 0.2, -1.0, 1.0)  # the bound ends inside it, the free foothold beyond it: its far side
    assert chooser._trailing_bounds(bounds, lift_along, 1.0, [in_way], 0.25)[:2] == pytest.approx((-0.3, 0.2))
    assert chooser._trailing_bounds(bounds, lift_along, 1.0)[:2] == pytest.approx((-0.3, 0.1))
