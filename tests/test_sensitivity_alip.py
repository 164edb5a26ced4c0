"""ALIP NMPC sensitivities (issue 14): implicit-function theorem = CasADi's solver derivative = re-solved
finite differences, the active set (held, weakly active, changing within the FD step), the parameter map."""

import dataclasses
import json

import numpy as np
import pytest

from sensitivity.alip_active_set import detect_active_set
from sensitivity.alip_crosscheck import AlipSensitivityAnalysis, relative_disagreement
from sensitivity.alip_finite_differences import AlipFiniteDifferenceRoute, check_fd_step
from sensitivity.alip_kkt import alip_kkt_sensitivity
from sequencer.alip.instances import orbit_instance, random_instances
from sequencer.alip.model import AlipModel
from sequencer.alip.nlp import SENSITIVITY_PARAMETERS, AlipInstance
from sequencer.alip.params import AlipParams
from wbmpc.cli import main
from wbmpc.errors import ParameterError

PARAMS = AlipParams.preset("g1")


@pytest.fixture(scope="module")
def analysis():
    return AlipSensitivityAnalysis(PARAMS, fd_step=1e-6)


@pytest.mark.parametrize("t_curr", [0.1, 0.3, 0.55])  # below t_min, inside (t_min, t_max), above t_max
def test_parameter_jacobian_matches_differences_of_the_nlp_data(analysis, t_curr):
    nlp = analysis.nlp
    instance = AlipInstance([0.02, 3.0, -0.05, -1.0], t_curr, "right", 0.2, -0.05, 0.3)
    dp, dlb = nlp.parameter_jacobian(instance)
    h = 1e-4
    for j in range(len(SENSITIVITY_PARAMETERS)):
        step = np.zeros(8)
        step[j] = h
        plus, minus = instance.with_theta(instance.theta + step), instance.with_theta(instance.theta - step)
        np.testing.assert_allclose((nlp.parameters(plus) - nlp.parameters(minus)) / (2 * h), dp[:, j], atol=1e-9)
        np.testing.assert_allclose((nlp.bounds(plus)[0] - nlp.bounds(minus)[0]) / (2 * h), dlb[:, j], atol=1e-9)
        np.testing.assert_array_equal(nlp.bounds(plus)[1], nlp.bounds(minus)[1])
    assert dlb[0, 4] == (1.0 if PARAMS.t_min < t_curr < PARAMS.t_max else 0.0)
    assert dp[4, 4] == (1.0 if t_curr < PARAMS.t_max else 0.0)


def test_three_routes_agree_on_random_instances_with_active_bounds(analysis):
    kinds, with_active, worst = set(), 0, 0.0
    for instance in random_instances(PARAMS, 14, seed=7):
        check = analysis.crosscheck(instance)
        assert check.active.differentiable and not check.fd_changes
        assert check.max_relative_disagreement <= 1e-6, (check.disagreement, instance)
        assert np.max(check.disagreement["casadi"]) <= 1e-9
        worst = max(worst, check.max_relative_disagreement)
        with_active += bool(check.active.names)
        kinds |= {name.split("_")[0] + ":" + name.split(":")[1] for name in check.active.names}
        assert check.active.names == check.solution.active  # the planner's own reading of the bounds
    assert with_active >= 8
    assert {"T:lower", "T:upper", "tau:lower", "tau:upper", "l:upper"} <= kinds


def test_held_bounds_move_with_their_bound_only(analysis):
    """A variable on an upper bound does not move; T_0 on its lower bound max(t_min, t_curr) follows t_curr."""
    found_upper = found_t_curr = 0
    for instance in random_instances(PARAMS, 30, seed=2):
        solution = analysis.solve(instance)
        sens = analysis.sensitivity(instance, solution)
        active = sens.active
        for i in np.flatnonzero(active.upper):
            np.testing.assert_array_equal(sens.dw_dtheta[i], 0.0)
            found_upper += 1
        if active.lower[0] and PARAMS.t_min < instance.t_curr:  # touchdown now: T_0 = t_curr
            expected = np.zeros(8)
            expected[4] = 1.0
            np.testing.assert_array_equal(sens.dperiods_dtheta[0], expected)
            found_t_curr += 1
    assert found_upper >= 5 and found_t_curr >= 1


def test_orbit_derivatives_have_the_structure_of_the_model(analysis):
    """On the undisturbed orbit: no bound is active, the optimum is the orbit (T = T_des), more forward angular
    momentum lengthens the next step, and the last step (in no state of the horizon: ℓ_{K-1} = ℓ^des) moves
    with the command by exactly ∂ℓ^des/∂v = T_des."""
    instance = orbit_instance(PARAMS, 0.3, 0.0, "left", 0.1)
    check = analysis.crosscheck(instance)
    assert check.active.names == () and check.max_relative_disagreement <= 1e-6
    sens = check.routes["kkt"]
    np.testing.assert_allclose(check.solution.periods, PARAMS.t_des, atol=1e-9)
    assert sens.dsteps_dtheta[0, 0, 1] > 0  # dℓ_x,0 / dL_y
    assert sens.dsteps_dtheta[-1, 0, 5] == pytest.approx(PARAMS.t_des, rel=1e-9)  # ℓ_{K-1} = ℓ^des (free)
    assert sens.dsteps_dtheta[-1, 1, 6] == pytest.approx(PARAMS.t_des, rel=1e-9)


def test_weakly_active_bounds_are_reported():
    """At the command whose desired step is the step bound the orbit's steps touch it with zero multipliers."""
    instance = orbit_instance(PARAMS, PARAMS.length_max / PARAMS.t_des, 0.0, "left", 0.1)
    sens = alip_kkt_sensitivity(AlipSensitivityAnalysis(PARAMS).nlp, instance)
    assert not sens.active.differentiable
    assert set(sens.active.weakly_active) == {f"l_x_{k}:upper" for k in range(PARAMS.steps)}


def test_an_active_set_change_within_the_fd_step_is_reported_not_averaged(analysis):
    route = AlipFiniteDifferenceRoute(analysis.ipopt, fd_step=1e-3)
    seen = 0
    for instance in random_instances(PARAMS, 12, seed=0):
        solution = analysis.solve(instance)
        active = detect_active_set(analysis.nlp, instance, solution)
        result = route.sensitivity(instance, solution, active)
        reference = analysis.kkt.sensitivity(instance, solution, active).dw_dtheta
        for change in result.changes:
            seen += 1
            j = SENSITIVITY_PARAMETERS.index(change.parameter)
            assert np.all(np.isnan(result.sensitivity.dw_dtheta[:, j]))
            assert change.plus_entered or change.plus_left or change.minus_entered or change.minus_left
            # the side that kept the active set is the derivative to O(h)
            if not (change.plus_entered or change.plus_left):
                one_sided = change.forward
            elif not (change.minus_entered or change.minus_left):
                one_sided = change.backward
            else:
                continue
            column = np.column_stack([one_sided] * 8)
            assert relative_disagreement(analysis.nlp, column, np.column_stack([reference[:, j]] * 8))[0] <= 5e-2
    assert seen >= 3


@pytest.mark.parametrize("bad", [0.0, -1e-6, float("nan"), float("inf"), True, "1e-6"])
def test_bad_fd_step_is_refused(bad):
    with pytest.raises(ParameterError, match="fd_step="):
        check_fd_step(bad)


def test_a_perturbation_out_of_the_domain_is_refused(analysis):
    instance = dataclasses.replace(orbit_instance(PARAMS, 0.3, 0.0, "left", 0.1), t_curr=0.0)
    with pytest.raises(ParameterError, match="fd_step=.*t_curr"):
        analysis.finite_differences.sensitivity(instance, analysis.solve(instance))


def test_impulse_changes_the_angular_momentum_by_r_cross_dp():
    model = AlipModel(PARAMS.mass, PARAMS.com_height)
    p, v, impulse = np.array([0.03, -0.04]), np.array([0.2, 0.1, -0.05]), np.array([6.0, -4.0, 2.0])
    jump = model.impulse_state_change(impulse, p, 0.6)
    after = model.state_from_velocity(p, v + impulse / model.mass, 0.6) - model.state_from_velocity(p, v, 0.6)
    np.testing.assert_allclose(jump, after, atol=1e-12)
    r = np.array([p[0], p[1], 0.6])
    L = np.cross(r, impulse)
    np.testing.assert_allclose(jump, [0.0, L[1], 0.0, L[0]], atol=1e-12)
    np.testing.assert_allclose(model.impulse_state_change([5.0, 0.0]), [0, model.com_height * 5.0, 0, 0])
    with pytest.raises(ParameterError, match="impulse="):
        model.impulse_state_change([1.0, np.nan])


def test_casadi_route_keeps_equalities_with_a_zero_multiplier(analysis):
    """Standing still (v = 0) the sagittal S2S multipliers are exactly 0; CasADi would drop those equalities."""
    instance = orbit_instance(PARAMS, 0.0, 0.0, "left", 0.1)
    check = analysis.crosscheck(instance)
    assert np.any(check.solution.lam_g == 0.0)
    assert check.max_relative_disagreement <= 1e-6
    assert abs(check.routes["casadi"].dsteps_dtheta[0, 0, 0]) > 0.1  # dℓ_x,0 / dp_x, not the 0 CasADi gave


# ----------------------------------------------------------------------------- CLI
def test_cli_alip_json_has_every_route_and_the_active_bounds(capsys):
    assert main(["sensitivity", "--planner", "alip", "--push", "8", "-3", "--t", "0.3", "--vx", "0.3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["planner"] == "alip" and set(report["routes"]) == {"kkt", "casadi", "finite_differences"}
    assert report["parameters"] == list(SENSITIVITY_PARAMETERS)
    assert np.asarray(report["routes"]["kkt"]).shape == (5 * PARAMS.steps, 8)
    assert report["max_relative_disagreement"] <= 1e-6
    assert report["active_bounds"] == ["tau_y_0:lower"] and report["differentiable"]
    assert report["instance"]["x0"][1] == pytest.approx(
        orbit_instance(PARAMS, 0.3, 0.0, "left", 0.3).x0[1] + PARAMS.com_height * 8.0)
    assert set(report["cost_ms"]) == {"ipopt_solve", "kkt", "casadi", "finite_differences"}


def test_cli_alip_text_and_a_reported_active_set_change(capsys):
    assert main(["sensitivity", "--planner", "alip", "--push", "8", "-3", "--t", "0.3", "--vx", "0.3",
                 "--fd-step", "0.02"]) == 0
    out = capsys.readouterr().out
    assert "active set changes within the FD step of v_x (+: entered -, left ('tau_y_0:lower',)" in out


@pytest.mark.parametrize("argv, needle", [
    (["--planner", "lip"], "argument --planner: invalid choice: 'lip'"),
    (["--planner", "alip", "--fd-step", "0"], "argument --fd-step: invalid value '0'"),
    (["--planner", "alip", "--fd-step", "nan"], "argument --fd-step: invalid value 'nan'"),
    (["--planner", "alip", "--fd-step=-1e-6"], "argument --fd-step: invalid value '-1e-6'"),
    (["--planner", "alip", "--alpha1", "3"], "--alpha1"),
    (["--planner", "alip", "--wrt", "dcm"], "--wrt"),
    (["--planner", "alip", "--vx", "3"], "v_x=3.0 m/s"),
    (["--push", "1", "0"], "--push"),
])
def test_cli_bad_input_is_one_line_naming_the_parameter(capsys, argv, needle):
    assert main(["sensitivity", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err, err


def test_push_study_slope_is_the_derivative_of_the_re_solves(analysis):
    from sensitivity.studies.alip_push import OUTPUTS, run_push_study

    instance = orbit_instance(PARAMS, 0.3, 0.0, "left", 0.1)
    h = 1e-3
    for axis in ("x", "y"):
        study = run_push_study(analysis, instance, axis, [-h, 0.0, h, 8.0 if axis == "x" else 12.0])
        assert study.same_active_set.tolist() == [True, True, True, False]  # a large push changes the set
        for name in OUTPUTS:
            slope = (study.predicted[name][2] - study.predicted[name][0]) / (2 * h)
            secant = (study.truth[name][2] - study.truth[name][0]) / (2 * h)
            assert slope == pytest.approx(secant, rel=1e-5, abs=1e-9), (axis, name)
            assert study.predicted[name][1] == pytest.approx(study.truth[name][1], abs=1e-12)
    np.testing.assert_allclose(study.state_jump, [0.0, 0.0, 0.0, -PARAMS.com_height])  # y: ΔL_x = −z Δp_y
    forward = run_push_study(analysis, instance, "x", [2.0])
    assert forward.truth["l_x_0"][0] > forward.sensitivity.solution.steps[0, 0]  # pushed forward: a longer step
    assert forward.truth["T_0"][0] < forward.sensitivity.solution.periods[0]  # ... taken sooner
