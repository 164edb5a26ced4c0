"""RiccatiPolicy against the closed loop's feedback law written with Pinocchio (the controller's
former ``compute()``), and its parameter checks."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
import pytest
from wbmpc_fixtures import random_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.policy import RiccatiPolicy
from wbmpc.ocp.state import StateMultibody


@pytest.fixture(scope="module")
def robot():
    return load_robot("bolt")


def _solution(robot, rng, n_nodes=8):
    model = robot.pinocchio_model
    xs = np.array([random_state(robot, rng, q_scale=0.3) for _ in range(n_nodes + 1)])
    us = rng.standard_normal((n_nodes, model.nv - 6))
    K = rng.standard_normal((n_nodes, model.nv - 6, 2 * model.nv))
    return xs, us, K


def _reference_law(model, t0, dt, xs, us, K, delay_nodes, interpolate, feedback, t, x):
    """u_k + K_k (x ⊖ x_k) as the walking controller computed it (Pinocchio throughout)."""
    nq = model.nq
    n = us.shape[0]
    elapsed = (t - t0) / dt
    base = int(np.floor(elapsed + 1e-9))
    k = min(max(base + delay_nodes, 0), n - 1)
    if interpolate and k + 1 < n:
        alpha = min(max(elapsed - base, 0.0), 1.0)
        u = (1.0 - alpha) * us[k] + alpha * us[k + 1]
        x_ref = np.concatenate([pin.interpolate(model, xs[k, :nq], xs[k + 1, :nq], alpha),
                                (1.0 - alpha) * xs[k, nq:] + alpha * xs[k + 1, nq:]])
    else:
        u, x_ref = us[k], xs[k]
    tau = np.array(u, dtype=float)
    if feedback:
        dx = np.concatenate([pin.difference(model, x_ref[:nq], x[:nq]), x[nq:] - x_ref[nq:]])
        tau += K[k] @ dx
    return k, tau


@pytest.mark.parametrize("interpolate", [False, True])
@pytest.mark.parametrize("delay_nodes", [0, 1])
@pytest.mark.parametrize("feedback", [True, False])
def test_policy_matches_the_controller_law(robot, interpolate, delay_nodes, feedback):
    rng = np.random.default_rng(3)
    model = robot.pinocchio_model
    state = StateMultibody(model)
    xs, us, K = _solution(robot, rng)
    t0, dt = 1.234, 0.01
    policy = RiccatiPolicy(state, t0, dt, xs, us, K, delay_nodes=delay_nodes, interpolate=interpolate)
    for t in np.concatenate([t0 + dt * np.array([-0.5, 0.0, 1.0, 2.999999, 7.0, 7.5, 9.0, 20.0]),
                             t0 + rng.uniform(0.0, 8 * dt, 30)]):
        x = random_state(robot, rng, q_scale=0.3)
        k_ref, tau_ref = _reference_law(model, t0, dt, xs, us, K, delay_nodes, interpolate, feedback, t, x)
        assert policy.node(t) == k_ref
        tau = policy.control(t, x, feedback=feedback)
        assert tau.shape == (model.nv - 6,)
        np.testing.assert_allclose(tau, tau_ref, rtol=0.0, atol=1e-12 * (1.0 + np.abs(tau_ref).max()))


def test_policy_near_a_half_turn_takes_pinocchio(robot):
    rng = np.random.default_rng(4)
    model = robot.pinocchio_model
    state = StateMultibody(model)
    xs, us, K = _solution(robot, rng, n_nodes=3)
    x = xs[1].copy()
    x[:model.nq] = pin.integrate(model, xs[1, :model.nq], np.r_[0.0, 0.0, 0.0, 0.0, 0.0, np.pi - 1e-3,
                                                               np.zeros(model.nv - 6)])
    policy = RiccatiPolicy(state, 0.0, 0.01, xs, us, K)
    _, tau_ref = _reference_law(model, 0.0, 0.01, xs, us, K, 0, False, True, 0.01, x)
    np.testing.assert_allclose(policy.control(0.01, x), tau_ref, rtol=0.0, atol=1e-9 * np.abs(tau_ref).max())


def test_policy_arrays_are_copied_and_control_is_fast(robot):
    rng = np.random.default_rng(5)
    state = StateMultibody(robot.pinocchio_model)
    xs, us, K = _solution(robot, rng, n_nodes=100)
    policy = RiccatiPolicy(state, 0.0, 0.01, xs, us, K, interpolate=True)
    x = random_state(robot, rng)
    before = policy.control(0.0123, x)
    us[:] = 0.0
    np.testing.assert_array_equal(policy.control(0.0123, x), before)
    tic = time.perf_counter()
    for i in range(1000):
        policy.control(1e-3 * i, x)
    assert (time.perf_counter() - tic) / 1000 < 100e-6  # the 1 kHz loop's budget is 1 ms


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"dt": 0.0}, "dt=0.0"),
    ({"dt": float("nan")}, "dt=nan"),
    ({"delay_nodes": -1}, "delay_nodes=-1"),
    ({"delay_nodes": 1.5}, "delay_nodes=1.5"),
    ({"interpolate": 1}, "interpolate=1"),
])
def test_policy_rejects_bad_parameters(robot, kwargs, match):
    rng = np.random.default_rng(6)
    state = StateMultibody(robot.pinocchio_model)
    xs, us, K = _solution(robot, rng, n_nodes=3)
    args = {"t0": 0.0, "dt": 0.01} | kwargs
    with pytest.raises(ParameterError, match=match):
        RiccatiPolicy(state, args.pop("t0"), args.pop("dt"), xs, us, K, **args)


def test_policy_rejects_inconsistent_shapes(robot):
    rng = np.random.default_rng(7)
    state = StateMultibody(robot.pinocchio_model)
    xs, us, K = _solution(robot, rng, n_nodes=3)
    with pytest.raises(ParameterError, match="K has shape"):
        RiccatiPolicy(state, 0.0, 0.01, xs, us, K[:2])
    with pytest.raises(ParameterError, match="xs has shape"):
        RiccatiPolicy(state, 0.0, 0.01, xs[:, :5], us, K)
