"""ALIP model and step-to-step maps against a numerical integration of eq. (4) (scipy's solve_ivp)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from sequencer.alip.model import AlipModel
from sequencer.alip.nlp import desired_steps, orbit
from sequencer.alip.params import AlipParams
from sequencer.alip.s2s import B_D, reset, s2s
from wbmpc.errors import ParameterError

MODEL = AlipModel(33.34, 0.64)


def integrate(x0, tau, T):
    sol = solve_ivp(lambda t, x: MODEL.dynamics(x, tau), (0.0, T), x0, rtol=1e-12, atol=1e-12, method="DOP853")
    return sol.y[:, -1]


@pytest.mark.parametrize("seed", range(5))
def test_flow_matches_integration(seed):
    rng = np.random.default_rng(seed)
    x0 = rng.normal(size=4) * np.array([0.1, 10.0, 0.1, 10.0])
    tau = rng.normal(size=2) * 5.0
    T = rng.uniform(0.05, 0.6)
    expected = integrate(x0, tau, T)
    scale = np.array([1.0, MODEL.mz, 1.0, MODEL.mz])
    assert np.max(np.abs((MODEL.flow(x0, tau, T) - expected) / scale)) < 1e-9
    assert np.allclose(MODEL.phi(T), expm(MODEL.A * T), rtol=1e-12, atol=1e-12)
    assert np.allclose(MODEL.flow(MODEL.flow(x0, tau, T), tau, -T), x0, atol=1e-9)  # backwards (eq. 17)


def test_reset_is_4x2_and_s2s_is_the_composition():
    assert B_D.shape == (4, 2)
    rng = np.random.default_rng(3)
    x_minus, step = rng.normal(size=4) * [0.1, 8, 0.1, 8], np.array([0.25, -0.2])
    post = reset(x_minus, step)
    assert np.allclose(post, x_minus - np.array([step[0], 0.0, step[1], 0.0]))  # L conserved, p about the new foot
    tau, T = np.array([3.0, -1.0]), 0.37
    expected = integrate(post, tau, T)
    got = s2s(MODEL, x_minus, step, T, tau)
    assert np.max(np.abs((got - expected) / [1, MODEL.mz, 1, MODEL.mz])) < 1e-9
    # the printed eq. 9 (step after the flow of the same step) is a different map
    printed = MODEL.flow(x_minus, tau, T) + B_D @ step
    assert np.max(np.abs(printed - got)) > 1e-2


def test_reset_heading_change_is_a_rotation_of_the_world_quantities():
    x_minus, step, dpsi = np.array([0.1, 5.0, -0.05, 2.0]), np.array([0.2, -0.2]), 0.3
    post = reset(x_minus, step, dpsi)
    c, s = math.cos(dpsi), math.sin(dpsi)
    rot = np.array([[c, -s], [s, c]])
    p_old, L_old = np.array([x_minus[0] - step[0], x_minus[2] - step[1]]), np.array([x_minus[3], x_minus[1]])
    assert np.allclose(rot @ [post[0], post[2]], p_old) and np.allclose(rot @ [post[3], post[1]], L_old)


def test_cop_offset_equivalence():
    tau = np.array([6.0, -2.0])
    c = MODEL.cop_offset(tau)
    x0 = np.array([0.05, 3.0, -0.1, 1.0])
    shifted = x0 - np.array([c[0], 0.0, c[1], 0.0])
    lip = MODEL.flow(shifted, (0.0, 0.0), 0.3) + np.array([c[0], 0.0, c[1], 0.0])
    assert np.allclose(lip, MODEL.flow(x0, tau, 0.3), atol=1e-12)


def test_orbits_are_the_hlip_period1_and_period2():
    params = AlipParams.preset("g1")
    omega, T, mz = params.omega, params.t_des, params.model.mz
    v_x, v_y = 0.4, 0.1
    orbits = orbit(params, v_x, v_y)
    l_x = v_x * T
    for foot in ("left", "right"):  # period 1 sagittally: p = l/2, v = ω coth(ωT/2) l/2
        assert orbits[foot][0] == pytest.approx(l_x / 2, abs=1e-12)
        assert orbits[foot][1] / mz == pytest.approx(omega / math.tanh(omega * T / 2) * l_x / 2, rel=1e-12)
    ell = {f: desired_steps(params, v_x, v_y, f) for f in ("left", "right")}
    flow = params.model.flow
    assert np.allclose(flow(orbits["left"] + B_D @ ell["left"], (0, 0), T), orbits["right"])
    assert np.allclose(flow(orbits["right"] + B_D @ ell["right"], (0, 0), T), orbits["left"])
    still = orbit(params, 0.0, 0.0)["left"]  # in place, left stance: p_y = -w/2, v_y = -σ2 w/2 (Xiong & Ames)
    w = params.width_offset
    assert still[2] == pytest.approx(-w / 2, abs=1e-12)
    assert -still[3] / mz == pytest.approx(-omega * math.tanh(omega * T / 2) * w / 2, rel=1e-12)


def test_bad_model():
    with pytest.raises(ParameterError, match="com_height"):
        AlipModel(30.0, float("nan"))
