"""contact_schedule: per-node contacts of a plan for the whole-body OCP."""

import numpy as np
import pytest

from sequencer import FootstepSequencer, SequencerParams, contact_schedule
from wbmpc.errors import ParameterError


@pytest.fixture(scope="module")
def plan():
    return FootstepSequencer(SequencerParams.table_i()).plan(
        t=0.229, stance_foot="left", stance_position=[-0.12, 0.10], dcm_measured=[-0.12, -0.07], t_stance_start=0.0
    )


def test_exactly_one_foot_in_contact_and_swing_phase_runs_from_0_to_1(plan):
    schedule = contact_schedule(plan, t0=plan.t0, dt=0.01, n_nodes=100)
    assert schedule.in_contact.shape == (101, 2) and schedule.feet == ("left", "right")
    assert np.all(schedule.in_contact.sum(axis=1) == 1)
    assert np.all(np.isnan(schedule.swing_phase[schedule.in_contact]))
    assert np.all(np.isnan(schedule.touchdown_position[schedule.in_contact]))
    swing = ~schedule.in_contact
    assert np.all((schedule.swing_phase[swing] >= 0) & (schedule.swing_phase[swing] <= 1))
    # node 0: left stance, right swinging since t_stance_start = 0 towards the first touchdown
    first = plan.steps[0]
    assert schedule.in_contact[0].tolist() == [True, False]
    assert schedule.swing_phase[0, 1] == pytest.approx(plan.t0 / first.touchdown_time)
    assert schedule.swing_duration[0, 1] == pytest.approx(first.touchdown_time)
    assert schedule.touchdown_position[0, 1] == pytest.approx(first.position)
    # after the first touchdown the right foot is in stance and the left swings towards step 2
    k = int(np.ceil((first.touchdown_time - plan.t0) / 0.01))
    assert schedule.in_contact[k].tolist() == [False, True]
    assert schedule.touchdown_position[k, 0] == pytest.approx(plan.steps[1].position)
    assert schedule.swing_duration[k, 0] == pytest.approx(plan.steps[1].duration)
    # swing phase increases monotonically within one swing
    phases = schedule.swing_phase[k:k + 20, 0]
    assert np.all(np.diff(phases) > 0)


def test_node_on_a_touchdown_starts_the_next_swing(plan):
    first = plan.steps[0]
    schedule = contact_schedule(plan, t0=first.touchdown_time, dt=0.01, n_nodes=5)
    assert schedule.in_contact[0].tolist() == [False, True]
    assert schedule.swing_phase[0, 0] == 0.0


def test_schedule_input_errors(plan):
    with pytest.raises(ParameterError, match=r"dt=0.0 s must be a finite positive number"):
        contact_schedule(plan, plan.t0, 0.0, 10)
    with pytest.raises(ParameterError, match=r"n_nodes=0 must be an integer >= 1"):
        contact_schedule(plan, plan.t0, 0.01, 0)
    with pytest.raises(ParameterError, match=r"at or after the plan's last touchdown"):
        contact_schedule(plan, plan.t0, 0.01, 400)
    with pytest.raises(ParameterError, match=r"t0=-1.0 s must be finite and >= the plan's current stance start"):
        contact_schedule(plan, -1.0, 0.01, 10)


def test_nearest_rounding_puts_each_touchdown_on_the_nearest_node(plan):
    first = plan.steps[0]
    dt = 0.01
    # a grid whose node k lies 3 ms before the first touchdown and node k + 1 7 ms after it
    t0 = first.touchdown_time - 0.003 - 5 * dt
    late = contact_schedule(plan, t0, dt, 20)
    nearest = contact_schedule(plan, t0, dt, 20, rounding="nearest")
    assert late.in_contact[5].tolist() == [True, False] and late.in_contact[6].tolist() == [False, True]
    assert nearest.in_contact[5].tolist() == [False, True] and nearest.in_contact[4].tolist() == [True, False]
    assert nearest.swing_phase[5, 0] == 0.0  # the next swing starts there
    assert 0.0 < nearest.swing_phase[4, 1] < 1.0
    # a touchdown 3 ms after a node stays on the next node
    t0 = first.touchdown_time - 0.007 - 5 * dt
    nearest = contact_schedule(plan, t0, dt, 20, rounding="nearest")
    assert nearest.in_contact[5].tolist() == [True, False] and nearest.in_contact[6].tolist() == [False, True]
    with pytest.raises(ParameterError, match=r"rounding='up' must be one of \('next', 'nearest'\)"):
        contact_schedule(plan, plan.t0, dt, 10, rounding="up")
