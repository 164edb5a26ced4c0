"""Nominal DCM offsets (Khadiv et al. 2020, App. A): the sign of b_y checked on a periodic LIPM gait."""

import dataclasses
import math

import numpy as np
import pytest

from sequencer import FootstepSequencer, SequencerParams, StepProblem, nominal_dcm_offset
from sequencer.nominal import nominal_step_width
from wbmpc.errors import ParameterError

OMEGA = math.sqrt(9.81 / 0.31)


def simulate_nominal_gait(b_y_left_stance, b_y_right_stance, v_y, l_p=0.25, t_step=0.3, steps=8):
    """Walk the LIPM with nominal widths; at each touchdown b_next = b E - w (DCM continuity).

    Starts on the left foot with the offset expected at the start of a left stance (the offset
    planned from the previous, right, stance) and returns the offsets reached at each touchdown.
    """
    growth = math.exp(OMEGA * t_step)
    stance = "left"
    b = b_y_right_stance  # offset w.r.t. the left foot when it landed (planned from a right stance)
    reached = []
    for _ in range(steps):
        width = nominal_step_width(l_p, v_y, t_step, stance)
        b = b * growth - width
        reached.append((stance, b))
        stance = "right" if stance == "left" else "left"
    return reached


@pytest.mark.parametrize("v_y", [0.0, 0.1, -0.2])
def test_nominal_offsets_make_the_lateral_gait_periodic(v_y):
    left = nominal_dcm_offset(OMEGA, 0.1, 0.25, v_y, 0.3, "left")[1]
    right = nominal_dcm_offset(OMEGA, 0.1, 0.25, v_y, 0.3, "right")[1]
    for stance, b in simulate_nominal_gait(left, right, v_y):
        expected = left if stance == "left" else right
        assert b == pytest.approx(expected, abs=1e-9)  # rounding grows by E ~ 5.4 per step


def test_flipped_sign_is_not_periodic():
    left = nominal_dcm_offset(OMEGA, 0.1, 0.25, 0.0, 0.3, "left")[1]
    right = nominal_dcm_offset(OMEGA, 0.1, 0.25, 0.0, 0.3, "right")[1]
    reached = simulate_nominal_gait(-left, -right, 0.0, steps=4)  # the flipped convention
    assert abs(reached[-1][1]) > 10 * abs(left)  # diverges


def test_left_stance_offset_points_back_to_the_left_foot():
    # the right foot lands on the right (y < 0); the DCM is still left of it, travelling right
    b_x, b_y = nominal_dcm_offset(OMEGA, 0.1, 0.25, 0.0, 0.3, "left")
    assert b_y > 0 and b_x == pytest.approx(0.1 / (math.exp(OMEGA * 0.3) - 1))


def test_qp_on_the_periodic_orbit_reproduces_the_nominal_step_with_zero_cost():
    params = SequencerParams.table_i()
    p0 = np.array([0.0, 0.125])
    b_x, b_y = params.b_nom("right")  # offset at the start of this left stance (planned from a right stance)
    problem = StepProblem.from_params(params, "left", p0, p0 + [b_x, b_y], 0.0)
    plan = FootstepSequencer(params).plan(0.0, "left", p0, p0 + [b_x, b_y], 0.0)
    first = plan.steps[0]
    assert first.position == pytest.approx(p0 + [params.l_nom, params.w_nom("left")], abs=1e-12)
    assert first.duration == pytest.approx(params.t_nom, abs=1e-12)
    assert first.dcm_offset == pytest.approx(params.b_nom("left"), abs=1e-12)
    from sequencer.step_qp import ExactBackend

    assert ExactBackend().solve(problem).objective == pytest.approx(0.0, abs=1e-18)
    for step in plan.steps:  # stays on the orbit
        assert step.duration == pytest.approx(params.t_nom, abs=1e-9)


@pytest.mark.parametrize("kappa", [0.0, 0.2, 0.5])
def test_swing_drift_offset_makes_the_drifting_sagittal_gait_periodic(kappa):
    """With a DCM gain of kappa L per stance, (1 - kappa) L + b_next = b E keeps b periodic."""
    length, t_step = 0.1, 0.3
    b = nominal_dcm_offset(OMEGA, length, 0.25, 0.0, t_step, "left", swing_drift=kappa)[0]
    assert b == pytest.approx((1.0 - kappa) * length / (math.exp(OMEGA * t_step) - 1.0))
    offset = b
    for _ in range(6):  # DCM at touchdown relative to the stance foot: LIPM growth + drift
        offset = offset * math.exp(OMEGA * t_step) + kappa * length - length
        assert offset == pytest.approx(b, abs=1e-9)


def test_swing_drift_and_offset_bias_in_the_sequencer_parameters():
    params = SequencerParams.bolt_walking()
    drifting = dataclasses.replace(params, swing_drift=0.25, dcm_offset_bias=0.003)
    b_x, b_y = params.b_nom("left")
    assert drifting.b_nom("left") == pytest.approx((0.75 * b_x - 0.003, b_y))
    # the lateral offset and the step QP's nominal step are unchanged
    assert drifting.w_nom("right") == params.w_nom("right") and drifting.l_nom == params.l_nom
    with pytest.raises(ParameterError, match=r"swing_drift=0.95 must be in \[0, 0.9\]"):
        dataclasses.replace(params, swing_drift=0.95)
    with pytest.raises(ParameterError, match=r"dcm_offset_bias=0.1 m must be in \[-0.05, 0.05\] m"):
        dataclasses.replace(params, dcm_offset_bias=0.1)
    with pytest.raises(ParameterError, match=r"swing_drift=1.0 must be in \[0, 1\)"):
        nominal_dcm_offset(OMEGA, 0.1, 0.25, 0.0, 0.3, "left", swing_drift=1.0)
