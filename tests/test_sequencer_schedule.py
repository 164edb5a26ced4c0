"""contact_schedule: per-node contacts of a plan for the whole-body OCP (point feet, double support, any feet)."""

import dataclasses

import numpy as np
import pytest

from sequencer import ContactSchedule, FootstepSequencer, SequencerParams, contact_schedule
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
    with pytest.raises(ParameterError, match=r"t0=nan s must be finite"):
        contact_schedule(plan, float("nan"), 0.01, 10)


def test_nodes_before_the_stance_start_are_double_support(plan):
    """A plan for a stance that has not begun (a start from standing): both feet on the ground
    until it begins, then the plan's own schedule."""
    dt = 0.01
    early = contact_schedule(plan, plan.t_stance_start - 0.1, dt, 40)
    later = contact_schedule(plan, plan.t_stance_start, dt, 30)
    assert early.in_contact[:10].all() and np.isnan(early.swing_phase[:10]).all()
    np.testing.assert_array_equal(early.in_contact[10:], later.in_contact)
    np.testing.assert_allclose(early.swing_phase[10:], later.swing_phase, atol=1e-12)


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


# ---------------------------------------------------------------------------- point feet: unchanged
def point_feet_schedule_reference(plan, t0, dt, n_nodes, rounding):
    """Copy of contact_schedule before double support and feet from the plan (biped, point feet)."""
    feet = ("left", "right")
    times = t0 + dt * np.arange(n_nodes + 1)
    touchdowns = plan.touchdown_times
    shift = 0.5 * dt if rounding == "nearest" else 0.0
    interval = np.searchsorted(touchdowns, times + shift, side="right")
    stance_starts = np.concatenate([[plan.t_stance_start], touchdowns])
    stance_index = np.array([feet.index(plan.stance_foot)] + [feet.index(step.foot) for step in plan.steps])
    rows = np.arange(n_nodes + 1)
    stance = stance_index[interval]
    swing = 1 - stance
    start, end = stance_starts[interval], touchdowns[interval]
    in_contact = np.zeros((n_nodes + 1, 2), dtype=bool)
    in_contact[rows, stance] = True
    swing_phase = np.full((n_nodes + 1, 2), np.nan)
    swing_phase[rows, swing] = np.clip((times - start) / (end - start), 0.0, 1.0)
    swing_duration = np.full((n_nodes + 1, 2), np.nan)
    swing_duration[rows, swing] = end - start
    touchdown_position = np.full((n_nodes + 1, 2, 2), np.nan)
    touchdown_position[rows, swing] = plan.positions[interval]
    return dict(in_contact=in_contact, swing_phase=swing_phase, swing_duration=swing_duration,
                touchdown_position=touchdown_position)


def random_plans(count, seed, **changes):
    params = dataclasses.replace(SequencerParams.bolt_walking(), **changes)
    sequencer = FootstepSequencer(params)
    rng = np.random.default_rng(seed)
    for _ in range(count):
        foot = "left" if rng.random() < 0.5 else "right"
        p0 = rng.uniform(-1.0, 1.0, 2)
        t_start = rng.uniform(0.0, 5.0)
        t = t_start + rng.uniform(0.0, params.t_max)
        yield sequencer.plan(t, foot, p0, p0 + rng.normal(0.0, 0.05, 2), t_start,
                             stance_yaw=rng.uniform(-3, 3), yaw_rate=rng.choice([0.0, 0.5]))


@pytest.mark.parametrize("rounding", ["next", "nearest"])
def test_point_feet_schedule_is_unchanged(rounding):
    rng = np.random.default_rng(2)
    for plan in random_plans(40, seed=1):
        t0 = plan.t0 + rng.uniform(0.0, 0.05)
        schedule = contact_schedule(plan, t0, 0.01, 100, rounding=rounding)
        expected = point_feet_schedule_reference(plan, t0, 0.01, 100, rounding)
        for name, array in expected.items():
            np.testing.assert_array_equal(getattr(schedule, name), array, err_msg=name)
        # the swinging foot's touchdown yaw is the planned foothold yaw
        swing = ~schedule.in_contact
        interval = np.searchsorted(plan.touchdown_times, schedule.times + (0.005 if rounding == "nearest" else 0.0),
                                   side="right")
        assert np.array_equal(schedule.touchdown_yaw[swing], plan.yaws[interval])
        assert np.all(np.isnan(schedule.touchdown_yaw[schedule.in_contact]))
        # the stance foot stands on the plan's stance yaw, then on the yaw of the step that landed it
        stance_yaws = np.concatenate([[plan.stance_yaw], plan.yaws])[interval]
        assert np.array_equal(schedule.contact_yaw[schedule.in_contact], stance_yaws)
        assert np.all(np.isnan(schedule.contact_yaw[swing]))


# ---------------------------------------------------------------------------- double support
@pytest.mark.parametrize("rounding", ["next", "nearest"])
def test_double_support_keeps_both_feet_down_after_each_touchdown(rounding):
    double_support, dt = 0.05, 0.01
    for plan in random_plans(20, seed=4, double_support=double_support):
        assert plan.double_support == double_support
        schedule = contact_schedule(plan, plan.t0, dt, 100, rounding=rounding)
        point_feet = contact_schedule(dataclasses.replace(plan, double_support=0.0), plan.t0, dt, 100, rounding=rounding)
        shift = 0.5 * dt if rounding == "nearest" else 0.0
        times = schedule.times + shift
        starts = np.concatenate([[plan.t_stance_start], plan.touchdown_times])
        interval = np.searchsorted(plan.touchdown_times, times, side="right")
        lift_off = starts[interval] + double_support
        both = times < lift_off  # double support: the landing foot of this interval still down
        assert np.all(schedule.in_contact[both])
        assert np.array_equal(schedule.in_contact[~both], point_feet.in_contact[~both])
        swing = ~schedule.in_contact
        assert np.all(swing.sum(axis=1) <= 1)
        # phase and duration run over the shortened swing, from lift-off to touchdown
        node_times = np.broadcast_to(schedule.times[:, None], swing.shape)[swing]
        rows = np.nonzero(swing)[0]
        duration = plan.touchdown_times[interval[rows]] - lift_off[rows]
        assert schedule.swing_duration[swing] == pytest.approx(duration, abs=1e-15)
        assert schedule.swing_phase[swing] == pytest.approx(
            np.clip((node_times - lift_off[rows]) / duration, 0.0, 1.0), abs=1e-15)
        assert np.array_equal(schedule.touchdown_position[swing], point_feet.touchdown_position[swing])
        assert np.array_equal(schedule.touchdown_yaw[swing], point_feet.touchdown_yaw[swing])
        for name in ("swing_phase", "swing_duration", "touchdown_yaw"):
            assert np.all(np.isnan(getattr(schedule, name)[schedule.in_contact])), name
        # in double support the trailing foot stands where it landed: the plan's stance foot after the
        # first touchdown, unknown (NaN) before it
        landing = np.array([schedule.feet.index(step.foot) for step in plan.steps])[interval]
        rows = np.nonzero(both)[0]
        trailing = schedule.contact_yaw[rows, landing[rows]]
        previous = np.concatenate([[np.nan, plan.stance_yaw], plan.yaws])[interval[rows]]
        np.testing.assert_array_equal(trailing, previous)


def test_double_support_nodes_after_a_touchdown():
    params = dataclasses.replace(SequencerParams.table_i(), double_support=0.035)
    plan = FootstepSequencer(params).plan(0.229, "left", [-0.12, 0.10], [-0.12, -0.07], 0.0)
    first = plan.steps[0].touchdown_time
    t0 = first - 0.002  # nodes at touchdown - 2 ms, + 8 ms, + 18 ms, + 28 ms, + 38 ms, ...
    schedule = contact_schedule(plan, t0, 0.01, 10)
    assert schedule.in_contact[:5].tolist() == [[True, False], [True, True], [True, True], [True, True], [False, True]]
    assert schedule.swing_phase[4, 0] == pytest.approx(0.003 / (plan.steps[1].touchdown_time - first - 0.035))
    # nearest: the touchdown rounds to node 0 (2 ms before it), the lift-off at +35 ms to node 4 (+38 ms)
    nearest = contact_schedule(plan, t0, 0.01, 10, rounding="nearest")
    assert nearest.in_contact[:5].tolist() == [[True, True], [True, True], [True, True], [True, True], [False, True]]


def test_double_support_parameter_is_validated():
    with pytest.raises(ParameterError, match=r"double_support=0.1 s must be in \[0, t_min=0.1 s\)"):
        dataclasses.replace(SequencerParams.table_i(), double_support=0.1)
    with pytest.raises(ParameterError, match=r"double_support=-0.01 s must be in \[0, t_min=0.1 s\)"):
        dataclasses.replace(SequencerParams.table_i(), double_support=-0.01)


def test_double_support_longer_than_a_swing_is_refused(plan):
    late = dataclasses.replace(plan, double_support=plan.steps[0].touchdown_time - plan.t_stance_start)
    with pytest.raises(ParameterError, match=r"double_support=.* s leaves no swing before the touchdown at"):
        contact_schedule(late, plan.t0, 0.01, 10)


# ---------------------------------------------------------------------------- feet from the plan
def test_feet_and_their_order_come_from_the_plan(plan):
    """A plan over three feet landing in turn: one foot swings at a time, the two others stand."""
    feet = ("front", "hind_left", "hind_right")
    order = ["hind_left", "hind_right", "front"]
    steps = tuple(dataclasses.replace(step, foot=order[k % 3], yaw=0.1 * k) for k, step in enumerate(plan.steps))
    tripod = dataclasses.replace(plan, stance_foot="front", steps=steps, feet=feet)
    schedule = contact_schedule(tripod, plan.t0, 0.01, 150)
    assert schedule.feet == feet and schedule.in_contact.shape == (151, 3)
    assert np.all((~schedule.in_contact).sum(axis=1) == 1)
    interval = np.searchsorted(tripod.touchdown_times, schedule.times, side="right")
    swinging = [feet[j] for j in np.argmax(~schedule.in_contact, axis=1)]
    assert swinging == [order[k % 3] for k in interval]
    assert schedule.touchdown_yaw[~schedule.in_contact] == pytest.approx(0.1 * interval)
    # the front foot stands at the plan's stance yaw until it lifts off; the hind feet are unknown
    # (they landed before the plan) until their first planned touchdown
    front = schedule.contact_yaw[:, 0][schedule.in_contact[:, 0] & (interval < 2)]
    assert np.all(front == tripod.stance_yaw)
    assert np.all(np.isnan(schedule.contact_yaw[interval == 0, 1:]))
    assert schedule.contact_yaw[interval == 1, 1] == pytest.approx(0.0)  # hind_left landed with yaw 0.1 * 0
    with pytest.raises(ParameterError, match=r"the plan's stance and steps use feet \['left'\] that are not in its feet"):
        contact_schedule(dataclasses.replace(tripod, stance_foot="left"), plan.t0, 0.01, 10)


def test_a_schedule_built_without_yaws_has_zero_yaw_in_swing(plan):
    schedule = contact_schedule(plan, plan.t0, 0.01, 20)
    bare = ContactSchedule(t0=schedule.t0, dt=schedule.dt, feet=schedule.feet, in_contact=schedule.in_contact,
                           swing_phase=schedule.swing_phase, swing_duration=schedule.swing_duration,
                           touchdown_position=schedule.touchdown_position)
    np.testing.assert_array_equal(bare.touchdown_yaw, schedule.touchdown_yaw)  # a plan without heading: 0
    np.testing.assert_array_equal(bare.contact_yaw, schedule.contact_yaw)
    with pytest.raises(ParameterError, match=r"touchdown_yaw has shape \(21, 3\), expected \(21, 2\)"):
        dataclasses.replace(schedule, touchdown_yaw=np.zeros((21, 3)))
