"""Compiled free-flyer Lie-group operations against Pinocchio and against each other."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robots import load_robot
from wbmpc.ocp.kernels.integration import free_flyer_euler_step
from wbmpc.ocp.kernels.lie import (
    free_flyer_ddifference_second,
    free_flyer_dintegrate,
    free_flyer_integrate,
    so3_log,
    so3_log_jacobian,
)


@pytest.fixture(scope="module")
def model():
    return load_robot("bolt").pinocchio_model


def _samples(model, scale: float, count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = pin.integrate(model, pin.neutral(model), rng.uniform(-2.0, 2.0, model.nv))
        yield q, scale * rng.standard_normal(model.nv)


def _jacobians(q, dq):
    nv = dq.size
    J_q, J_dq = np.empty((nv, nv)), np.empty((nv, nv))
    free_flyer_dintegrate(q, dq, J_q, J_dq)
    return J_q, J_dq


@pytest.mark.parametrize("scale", [1e-8, 1e-4, 1e-2, 0.3, 2.0])
def test_integrate_and_its_configuration_jacobian_match_pinocchio(model, scale):
    for q, dq in _samples(model, scale, 50, seed=1):
        out = np.empty(model.nq)
        free_flyer_integrate(q, dq, out)
        np.testing.assert_allclose(out, pin.integrate(model, q, dq), rtol=0, atol=1e-14)
        J_q, _ = _jacobians(q, dq)
        np.testing.assert_allclose(J_q, pin.dIntegrate(model, q, dq, pin.ARG0), rtol=0, atol=1e-13)


@pytest.mark.parametrize("scale", [1e-8, 0.1, 0.5, 2.0])
def test_tangent_jacobians_match_pinocchio_where_it_is_exact(model, scale):
    """Away from θ ~ 1e-5..1e-2 (where Pinocchio's Jexp6 series loses up to ~6e-8, checked against
    a 60-digit reference while writing these kernels) both agree to rounding."""
    for q, dq in _samples(model, scale, 50, seed=2):
        _, J_dq = _jacobians(q, dq)
        np.testing.assert_allclose(J_dq, pin.dIntegrate(model, q, dq, pin.ARG1), rtol=0, atol=1e-12)
        q1 = pin.integrate(model, q, dq)
        J = np.empty((model.nv, model.nv))
        assert free_flyer_ddifference_second(q, q1, J)
        np.testing.assert_allclose(J, pin.dDifference(model, q, q1, pin.ARG1), rtol=0, atol=1e-12)


@pytest.mark.parametrize("scale", [1e-6, 1e-4, 1e-3, 1e-2, 1.0])
def test_difference_jacobian_inverts_the_integrate_jacobian(model, scale):
    """∂(q ⊕ dq ⊖ q)/∂dq = I: dDifference(q, q ⊕ dq) · dIntegrate_dv(q, dq) is the identity at
    every angle, including the small ones where the series take over."""
    for q, dq in _samples(model, scale, 50, seed=3):
        _, J_dq = _jacobians(q, dq)
        q1 = np.empty(model.nq)
        free_flyer_integrate(q, dq, q1)
        J = np.empty((model.nv, model.nv))
        assert free_flyer_ddifference_second(q, q1, J)
        np.testing.assert_allclose(J @ J_dq, np.eye(model.nv), rtol=0, atol=1e-12)


def test_tangent_jacobian_matches_finite_differences(model):
    h = 1e-6
    for q, dq in _samples(model, 1e-3, 10, seed=4):
        _, J_dq = _jacobians(q, dq)
        base = np.empty(model.nq)
        free_flyer_integrate(q, dq, base)
        fd = np.empty((model.nv, model.nv))
        for j in range(model.nv):
            plus, minus = np.empty(model.nq), np.empty(model.nq)
            e = np.zeros(model.nv)
            e[j] = h
            free_flyer_integrate(q, dq + e, plus)
            free_flyer_integrate(q, dq - e, minus)
            fd[:, j] = (pin.difference(model, base, plus) - pin.difference(model, base, minus)) / (2 * h)
        np.testing.assert_allclose(J_dq, fd, rtol=0, atol=1e-8)


def test_half_turn_is_left_to_pinocchio(model):
    q0 = pin.neutral(model)
    q1 = pin.integrate(model, q0, np.r_[0, 0, 0, np.pi - 1e-3, 0, 0, np.zeros(model.nv - 6)])
    assert not free_flyer_ddifference_second(q0, q1, np.empty((model.nv, model.nv)))


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-6, 0.05, 0.3, 2.0, np.pi - 0.02])
def test_so3_log_and_its_jacobian_match_pinocchio(angle):
    rng = np.random.default_rng(7)
    for _ in range(5):
        axis = rng.standard_normal(3)
        R = pin.exp3(angle * axis / np.linalg.norm(axis))
        w, J = np.full(3, np.nan), np.full((3, 3), np.nan)
        theta = so3_log(R, w)
        # 2 sin θ is small near the half turn: its rounding grows as 1/(π − θ) (Pinocchio branches there)
        np.testing.assert_allclose(w, pin.log3(R), rtol=0, atol=1e-12 if angle < 3.0 else 1e-10)
        assert theta == pytest.approx(np.linalg.norm(pin.log3(R)), abs=3e-8)  # from the trace: ~√eps near 0
        so3_log_jacobian(w, J)
        np.testing.assert_allclose(J, pin.Jlog3(R), rtol=0, atol=1e-10 if angle < 3.0 else 1e-8)


def test_so3_log_leaves_the_half_turn_to_pinocchio():
    w = np.full(3, np.nan)
    assert so3_log(pin.exp3(np.array([0.0, np.pi - 1e-3, 0.0])), w) < 0.0
    assert np.isnan(w).all()  # untouched


def test_euler_step(model):
    rng = np.random.default_rng(5)
    q = pin.integrate(model, pin.neutral(model), rng.standard_normal(model.nv))
    x = np.r_[q, rng.standard_normal(model.nv)]
    a = rng.standard_normal(model.nv)
    dt = 0.01
    dx, x_next = np.empty(2 * model.nv), np.empty(model.nq + model.nv)
    free_flyer_euler_step(x, a, dt, dx, x_next)
    v = x[model.nq:]
    np.testing.assert_allclose(dx, np.r_[v * dt + a * dt**2, a * dt], atol=1e-16)
    np.testing.assert_allclose(x_next, np.r_[pin.integrate(model, q, v * dt + a * dt**2), v + a * dt], atol=1e-14)
