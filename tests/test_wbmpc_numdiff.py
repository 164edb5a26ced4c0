"""ActionModelNumDiff on a model whose derivatives are known in closed form."""

from __future__ import annotations

import numpy as np
import pytest
from wbmpc_fixtures import random_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.numdiff import ActionModelNumDiff
from wbmpc.ocp.state import StateMultibody


class _Data:
    def __init__(self, model):
        self.xnext = np.zeros(model.state.nx)
        self.cost = 0.0


class _VelocityQuadratic:
    """x⁺ = [q, v + B u], l = ½ vᵀ P v + uᵀ S v + ½ uᵀ R u (exact: Fx = I, Fu = [0; B], Lxx, Lxu, Luu)."""

    def __init__(self, state, rng):
        nv, self.nu = state.nv, 3
        self.state = state
        self.B = rng.standard_normal((nv, self.nu))
        P = rng.standard_normal((nv, nv))
        self.P = P @ P.T
        self.S = rng.standard_normal((self.nu, nv))
        self.R = np.diag([1.0, 2.0, 3.0])

    def createData(self):
        return _Data(self)

    def calc(self, data, x, u=None):
        nq = self.state.nq
        v = x[nq:]
        u = np.zeros(self.nu) if u is None else u
        data.xnext[:nq] = x[:nq]
        data.xnext[nq:] = v + self.B @ u
        data.cost = 0.5 * v @ self.P @ v + u @ self.S @ v + 0.5 * u @ self.R @ u


@pytest.fixture(scope="module")
def setup():
    robot = load_robot("bolt")
    state = StateMultibody(robot.pinocchio_model)
    rng = np.random.default_rng(0)
    return robot, state, _VelocityQuadratic(state, rng), rng


def test_numdiff_recovers_the_closed_form_derivatives(setup):
    robot, state, model, rng = setup
    nv = state.nv
    x, u = random_state(robot, rng), rng.standard_normal(model.nu)
    numdiff = ActionModelNumDiff(model, hessians=True)
    data = numdiff.createData()
    numdiff.calcDiff(data, x, u)
    v = x[state.nq:]
    Fu = np.vstack([np.zeros((nv, model.nu)), model.B])
    Lx = np.concatenate([np.zeros(nv), model.P @ v + model.S.T @ u])
    Lxx = np.zeros((2 * nv, 2 * nv))
    Lxx[nv:, nv:] = model.P
    Lxu = np.vstack([np.zeros((nv, model.nu)), model.S.T])
    tol = 1e-8
    np.testing.assert_allclose(data.Fx, np.eye(2 * nv), rtol=0, atol=tol)
    np.testing.assert_allclose(data.Fu, Fu, rtol=0, atol=tol * np.abs(Fu).max())
    np.testing.assert_allclose(data.Lx, Lx, rtol=0, atol=tol * np.abs(Lx).max())
    np.testing.assert_allclose(data.Lu, model.S @ v + model.R @ u, rtol=0, atol=tol * np.abs(Lx).max())
    htol = 1e-5  # second differences: error ~ eps^(1/2)
    np.testing.assert_allclose(data.Lxx, Lxx, rtol=0, atol=htol * np.abs(Lxx).max())
    np.testing.assert_allclose(data.Lxu, Lxu, rtol=0, atol=htol * np.abs(Lxx).max())
    np.testing.assert_allclose(data.Luu, model.R, rtol=0, atol=htol * np.abs(Lxx).max())
    assert data.cost == pytest.approx(0.5 * v @ model.P @ v + u @ model.S @ v + 0.5 * u @ model.R @ u)


def test_numdiff_terminal_node_has_no_control(setup):
    robot, state, model, rng = setup
    x = random_state(robot, rng)
    numdiff = ActionModelNumDiff(model)
    data = numdiff.createData()
    numdiff.calcDiff(data, x)
    np.testing.assert_array_equal(data.Fu, 0.0)
    np.testing.assert_allclose(data.Lx[state.nv:], model.P @ x[state.nq:], rtol=1e-8)


@pytest.mark.parametrize("disturbance", [0.0, -1e-6, 1.0, float("nan")])
def test_numdiff_rejects_bad_disturbances(setup, disturbance):
    with pytest.raises(ParameterError, match="disturbance="):
        ActionModelNumDiff(setup[2], disturbance=disturbance)


def test_numdiff_rejects_non_boolean_hessians(setup):
    with pytest.raises(ParameterError, match="hessians=1"):
        ActionModelNumDiff(setup[2], hessians=1)
