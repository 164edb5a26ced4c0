"""The step timing's speed schedule (SequencerParams.fast_*, at_speed): interpolation, validation, command range,
and the DCM planner's plans at and below the schedule's speeds."""

import dataclasses

import numpy as np
import pytest

from sequencer import DcmFootstepPlanner, ReducedState, StanceState, VelocityCommand
from wbmpc.errors import ParameterError
from wbmpc.walking import load_walking_preset

SCHEDULE = dict(fast_speed_start=0.5, fast_speed_full=1.0, fast_t_nom=0.25, fast_t_min=0.2, fast_double_support=0.05,
                fast_l_max=0.45)


def h1_params(**schedule):
    """The H1's planner without its own schedule (if any), with ``schedule``."""
    base = load_walking_preset("h1").planner
    off = {name: 0.0 for name in SCHEDULE}
    return dataclasses.replace(dataclasses.replace(base, **off), **schedule)


def test_the_timing_moves_linearly_between_the_schedule_speeds():
    base, params = h1_params(), h1_params(**SCHEDULE)
    assert params.at_speed(0.3) is params and params.at_speed(-0.5) is params  # |v_x| <= fast_speed_start
    half = params.at_speed(0.75)
    assert (half.t_nom, half.t_min, half.double_support, half.l_max) == pytest.approx(
        (0.5 * (base.t_nom + 0.25), 0.5 * (base.t_min + 0.2), 0.5 * (base.double_support + 0.05),
         0.5 * (base.l_max + 0.45)))
    fast = params.at_speed(1.3)
    assert (fast.t_nom, fast.t_min, fast.double_support, fast.l_max) == (0.25, 0.2, 0.05, 0.45)
    assert fast.fast_speed_full == 0.0 and fast.at_speed(1.3) is fast  # the scheduled set has the schedule off
    assert base.at_speed(1.3) is base  # off


@pytest.mark.parametrize("schedule, message", [
    (dict(fast_t_nom=0.25), r"fast_t_nom=0.25 needs fast_speed_full > 0 m/s"),
    (dict(fast_speed_start=1.2, fast_speed_full=1.0), r"fast_speed_start=1.2 m/s and fast_speed_full=1.0 m/s must "
                                                      r"satisfy 0 <= fast_speed_start < fast_speed_full <= 5 m/s"),
    (dict(SCHEDULE, fast_t_nom=0.15), r"the timing at fast_speed_full=1.0 m/s \(the fast_\* values\) is invalid: "
                                      r"step durations must satisfy 0 < t_min <= t_nom <= t_max, got t_min=0.2 s, "
                                      r"t_nom=0.15 s"),
])
def test_a_bad_schedule_is_named(schedule, message):
    with pytest.raises(ParameterError, match=message):
        h1_params(**schedule)


def test_the_command_range_follows_the_scheduled_timing():
    base, params = h1_params(), h1_params(**SCHEDULE)
    assert base.velocity_range()["v_x"][1] == pytest.approx(0.75)  # l_max / t_nom = 0.30 / 0.40
    with pytest.raises(ParameterError, match=r"v_x=1.0 m/s gives a nominal step length"):
        base.check_velocity(1.0, 0.0)
    low, high = params.velocity_range()["v_x"]
    assert high == pytest.approx(0.45 / 0.25) and low == pytest.approx(-0.30 / 0.25)
    params.check_velocity(1.0, 0.0)
    params.check_velocity(high, 0.0)  # a command clipped to the range passes
    with pytest.raises(ParameterError, match=r"\(t_nom=0.25 s at this speed\): v_x must lie within \[-1.2, 1.8\]"):
        params.check_velocity(high + 1e-6, 0.0)


def test_the_planner_plans_with_the_timing_of_its_command():
    stance = StanceState("left", [0.0, 0.203], 0.0, 0.0)
    measured = ReducedState(com=[0.05, 0.05, 0.97], com_velocity=[0.5, -0.1, 0.0], dcm=[0.2, 0.02])
    scheduled, plain = DcmFootstepPlanner(h1_params(**SCHEDULE)), DcmFootstepPlanner(h1_params())
    slow = VelocityCommand(0.3, 0.0, 0.0)
    a, b = scheduled.plan(0.05, stance, measured, slow), plain.plan(0.05, stance, measured, slow)
    assert [s.touchdown_time for s in a.steps] == [s.touchdown_time for s in b.steps]  # below it: unchanged
    assert np.array_equal(np.array([s.position for s in a.steps]), np.array([s.position for s in b.steps]))
    fast = scheduled.plan(0.05, stance, measured, VelocityCommand(1.0, 0.0, 0.0))
    assert fast.double_support == scheduled.double_support == 0.05
    durations = np.diff([fast.t_stance_start] + [s.touchdown_time for s in fast.steps])
    assert np.median(durations[1:]) == pytest.approx(0.25, abs=0.01)  # the later steps: the nominal 0.25 s
    assert scheduled.plan(0.05, stance, measured, slow).double_support == a.double_support  # and back
