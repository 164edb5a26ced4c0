"""Algorithm 1 (FootstepSequencer.plan), the LIPM predictions of a plan, and plan inputs."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sequencer import FootstepSequencer, InfeasibleStep, SequencerParams, StepProblem
from wbmpc.errors import ParameterError

TABLE_I_STATE = dict(t=0.229, stance_foot="left", stance_position=np.array([-0.12, 0.10]),
                     dcm_measured=np.array([-0.12, -0.07]), t_stance_start=0.0)


def check_constraints(plan, params):
    """Every step: length/width/time bounds (eqs. 15a-15f), alternating feet, DCM continuity (16)."""
    previous, stance, start = plan.stance_position, plan.stance_foot, plan.t_stance_start
    dcm = plan.dcm_measured
    omega = params.omega
    for step in plan.steps:
        assert step.foot != stance
        d = step.position - previous
        w_lo, w_hi = params.width_bounds(stance)
        tol = 1e-9
        assert params.l_min - tol <= d[0] <= params.l_max + tol
        assert w_lo - tol <= d[1] <= w_hi + tol
        assert params.t_min - tol <= step.touchdown_time - start <= params.t_max + tol
        if start == plan.t_stance_start:  # first step: no touchdown in the past
            assert step.touchdown_time >= plan.t0 - tol
        # the DCM at touchdown is the LIPM DCM propagated from the previous stance (eq. 1b)
        t_from = plan.t0 if start == plan.t_stance_start else start
        expected = previous + (dcm - previous) * math.exp(omega * (step.touchdown_time - t_from))
        assert step.dcm_at_touchdown == pytest.approx(expected, abs=1e-9, rel=1e-12)
        assert step.dcm_at_touchdown == pytest.approx(step.position + step.dcm_offset, abs=1e-15, rel=1e-15)
        previous, stance, start, dcm = step.position, step.foot, step.touchdown_time, step.dcm_at_touchdown


@pytest.mark.parametrize("preset", ["table_i", "bolt_walking"])
def test_all_constraints_hold_on_every_step(preset):
    params = SequencerParams.preset(preset)
    plan = FootstepSequencer(params).plan(**TABLE_I_STATE)
    check_constraints(plan, params)
    assert plan.steps[-1].touchdown_time >= plan.t0 + params.horizon
    assert plan.steps[-2].touchdown_time < plan.t0 + params.horizon  # stops at the first one beyond H_u


def test_constraints_hold_when_bounds_bind():
    params = dataclasses.replace(SequencerParams.table_i(), l_max=0.12, t_max=0.4, v_x=0.3)
    plan = FootstepSequencer(params).plan(0.1, "right", [0.0, -0.1], [0.35, 0.2], 0.0)
    assert any(step.active for step in plan.steps)
    check_constraints(plan, params)


def test_dcm_stays_bounded_over_a_30_s_sequence():
    params = dataclasses.replace(SequencerParams.table_i(), horizon=30.0)
    plan = FootstepSequencer(params).plan(**TABLE_I_STATE)
    assert len(plan.steps) >= 95
    offsets = np.array([s.dcm_offset for s in plan.steps])
    assert np.max(np.abs(offsets)) < 0.1
    # and converges to the nominal offsets
    assert offsets[-1] == pytest.approx(params.b_nom(plan.steps[-2].foot), abs=1e-6)
    times = np.linspace(plan.t0, plan.steps[-1].touchdown_time, 3000)
    dcm = plan.dcm_at(times)
    assert np.max(np.abs(dcm[:, 1])) < 0.2  # lateral DCM oscillates between the feet
    lag = dcm[:, 0] - params.v_x * (times - plan.t0)  # forward DCM advances at the commanded speed
    assert np.ptp(lag) < 0.2


@pytest.mark.parametrize("v_x", [0.1 / 0.3, 0.2, 0.0, -0.3])
def test_mean_speed_matches_the_command(v_x):
    params = dataclasses.replace(SequencerParams.table_i(), v_x=v_x, horizon=6.0)
    plan = FootstepSequencer(params).plan(**TABLE_I_STATE)
    assert plan.mean_velocity() == pytest.approx([params.l_nom / params.t_nom, 0.0], abs=2e-3)


def test_fig3_speed_is_l_nom_over_t_nom():
    params = SequencerParams.table_i()
    plan = FootstepSequencer(params).plan(**TABLE_I_STATE)
    assert plan.mean_velocity()[0] == pytest.approx(0.1 / 0.3, abs=2e-3)


@pytest.mark.parametrize("backend", ["osqp", "proxqp"])
def test_backends_give_the_same_plan(backend):
    params = SequencerParams.table_i()
    exact = FootstepSequencer(params).plan(**TABLE_I_STATE)
    other = FootstepSequencer(params, backend=backend).plan(**TABLE_I_STATE)
    assert len(other.steps) == len(exact.steps)
    for a, b in zip(exact.steps, other.steps):
        assert (a.foot, a.active) == (b.foot, b.active)
        assert b.position == pytest.approx(a.position, abs=1e-6)
        assert b.touchdown_time == pytest.approx(a.touchdown_time, abs=1e-6)
        assert b.dcm_offset == pytest.approx(a.dcm_offset, abs=1e-6)


def test_lipm_predictions_match_numerical_integration():
    params = SequencerParams.table_i()
    plan = FootstepSequencer(params).plan(**TABLE_I_STATE)
    com0 = np.array([-0.11, -0.01])
    omega = params.omega
    touchdowns = plan.touchdown_times
    feet = [plan.stance_position] + [s.position for s in plan.steps]

    t_eval = np.linspace(plan.t0, 2.0, 50)
    # integrate eqs. (1a)/(1b) stance by stance (the foot jumps at each touchdown)
    breaks = [plan.t0] + [t for t in touchdowns if t < 2.0] + [2.0]
    state = np.concatenate([com0, plan.dcm_measured])
    expected = np.empty((t_eval.size, 4))
    for i, (start, end) in enumerate(zip(breaks[:-1], breaks[1:])):
        foot = feet[i]
        rhs = lambda t, y, foot=foot: np.concatenate([omega * (y[2:] - y[:2]), omega * (y[2:] - foot)])
        inside = (t_eval >= start) & (t_eval < end) if end < 2.0 else (t_eval >= start)
        sol = solve_ivp(rhs, (start, end), state, t_eval=t_eval[inside], rtol=1e-12, atol=1e-14, method="DOP853")
        expected[inside] = sol.y.T
        state = solve_ivp(rhs, (start, end), state, rtol=1e-12, atol=1e-14, method="DOP853").y[:, -1]
    sol_y = expected.T
    assert plan.lipm_com_at(t_eval, com0) == pytest.approx(sol_y[:2].T, abs=1e-8)
    assert plan.dcm_at(t_eval) == pytest.approx(sol_y[2:].T, abs=1e-8)
    assert plan.lipm_com_at(1.0, com0).shape == (2,)
    with pytest.raises(ParameterError, match=r"must be >= the plan's t0=0.229 s"):
        plan.lipm_com_at(0.1, com0)


def test_plan_input_errors_and_late_touchdown():
    seq = FootstepSequencer(SequencerParams.table_i())
    state = dict(TABLE_I_STATE)
    with pytest.raises(ParameterError, match=r"t_stance_start=0.5 s must be <= t=0.229 s"):
        seq.plan(**{**state, "t_stance_start": 0.5})
    with pytest.raises(ParameterError, match=r"stance_foot='both' must be 'left' or 'right'"):
        seq.plan(**{**state, "stance_foot": "both"})
    with pytest.raises(ParameterError, match=r"dcm_measured=.* must be a finite \(x, y\) pair"):
        seq.plan(**{**state, "dcm_measured": [np.inf, 0.0]})
    with pytest.raises(ParameterError, match=r"stance_position=.* must be a finite \(x, y\) pair"):
        seq.plan(**{**state, "stance_position": [0.0, 0.0, 0.0]})
    with pytest.raises(InfeasibleStep, match=r"exceeds T_max=1.0 s") as info:
        seq.plan(**{**state, "t": 1.5})
    assert info.value.problem.stance_foot == "left"
    plan = seq.plan(**{**state, "t": 1.5}, clamp_elapsed=True)  # graceful: touchdown now
    assert plan.steps[0].touchdown_time == pytest.approx(plan.t0)
    with pytest.raises(ParameterError, match="must be a SequencerParams"):
        FootstepSequencer({"z_c": 0.3})


@pytest.mark.parametrize("preset", ["table_i", "bolt_walking"])
def test_random_measured_states_always_give_a_feasible_plan(preset):
    """What a closed loop sees: any state within T_max plans, and every plan satisfies the bounds."""
    params = SequencerParams.preset(preset)
    seq = FootstepSequencer(params)
    rng = np.random.default_rng(7)
    for _ in range(300):
        stance = "left" if rng.random() < 0.5 else "right"
        p0 = rng.uniform(-1.0, 1.0, 2)
        dcm = p0 + rng.normal(0.0, 0.3, 2)
        t_start = rng.uniform(0.0, 5.0)
        t = t_start + rng.uniform(0.0, params.t_max)
        plan = seq.plan(t, stance, p0, dcm, t_start)
        check_constraints(plan, params)
        assert plan.steps[-1].touchdown_time >= t + params.horizon


def test_scalar_and_vector_com_predictions_agree():
    plan = FootstepSequencer(SequencerParams.table_i()).plan(**TABLE_I_STATE)
    com0 = np.array([-0.11, -0.01])
    times = np.concatenate([np.linspace(plan.t0, plan.steps[-1].touchdown_time + 0.2, 37), plan.touchdown_times])
    vector = plan.lipm_com_at(times, com0)
    for t, expected in zip(times, vector):
        assert plan.lipm_com_at(float(t), com0) == pytest.approx(expected, abs=1e-12, rel=1e-12)


def test_the_sequencer_problem_is_the_params_problem_and_the_gait_is_kept():
    params = dataclasses.replace(SequencerParams.table_i(), swing_drift=0.1)
    seq = FootstepSequencer(params)
    for foot in ("left", "right"):
        built, expected = seq.problem(foot, [0.1, 0.2], [0.15, 0.1], 0.05), StepProblem.from_params(
            params, foot, [0.1, 0.2], [0.15, 0.1], 0.05)
        for field in dataclasses.fields(StepProblem):
            assert np.array_equal(getattr(built, field.name), getattr(expected, field.name)), field.name
    gait = seq.nominal_gait((0.2, 0.1))
    assert seq.nominal_gait((0.2, 0.1)) is gait  # the last distinct command is kept
    assert seq.nominal_gait() is not gait and seq.nominal_gait().v_x == params.v_x
