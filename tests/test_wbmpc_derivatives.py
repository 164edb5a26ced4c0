"""calc/calcDiff of the wbmpc models and residuals against finite differences at random states."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from wbmpc_fixtures import alternating_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.ocp.activations import ActivationQuadraticBarrier, ActivationWeightedQuad
from wbmpc.ocp.state import StateMultibody
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig

EPS = 1e-7
ALL_TERMS = WalkingOCPConfig(foothold_weight=100.0, contact_force_weight=1e-2, friction_cone_weight=10.0,
                             touchdown_height_weight=1e5, touchdown_velocity_weight=1e3,
                             baumgarte_gains=(20.0, 40.0))


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


def _tangent_fd(state: StateMultibody, f, x, eps=EPS):
    """Columns ∂f/∂dx by forward differences along the tangent space of x (f returns a vector)."""
    f0 = f(x)
    J = np.zeros((f0.size, state.ndx))
    for i in range(state.ndx):
        dx = np.zeros(state.ndx)
        dx[i] = eps
        J[:, i] = (f(state.integrate(x, dx)) - f0) / eps
    return J


def _control_fd(f, u, eps=EPS):
    f0 = f(u)
    J = np.zeros((f0.size, u.size))
    for i in range(u.size):
        du = np.zeros(u.size)
        du[i] = eps
        J[:, i] = (f(u + du) - f0) / eps
    return J


def _dynamics_fd(model, state: StateMultibody, x, u, xnext):
    """Finite-difference (Fx, Fu) of a node's next state at (x, u), as tangents at ``xnext``."""

    def xnext_of_x(xx):
        d = model.createData()
        model.calc(d, xx, u)
        return state.diff(xnext, d.xnext)

    def xnext_of_u(uu):
        d = model.createData()
        model.calc(d, x, uu)
        return state.diff(xnext, d.xnext)

    return _tangent_fd(state, xnext_of_x, x), _control_fd(xnext_of_u, u)


def _assert_close(actual, expected, name, rtol=1e-4):
    scale = max(1.0, float(np.max(np.abs(expected))))
    err = float(np.max(np.abs(actual - expected)))
    assert err <= rtol * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


def test_state_jacobians_match_finite_differences(bolt):
    state = StateMultibody(bolt.pinocchio_model)
    rng = np.random.default_rng(1)
    x0, x1 = random_state(bolt, rng), random_state(bolt, rng)
    J0, J1 = state.Jdiff(x0, x1)
    _assert_close(J0, _tangent_fd(state, lambda x: state.diff(x, x1), x0), "Jdiff first")
    _assert_close(J1, _tangent_fd(state, lambda x: state.diff(x0, x), x1), "Jdiff second")
    dx = 0.1 * rng.standard_normal(state.ndx)
    Ji0, Ji1 = state.Jintegrate(x0, dx)
    _assert_close(Ji0, _tangent_fd(state, lambda x: state.diff(state.integrate(x0, dx), state.integrate(x, dx)), x0),
                  "Jintegrate first")
    _assert_close(Ji1, _control_fd(lambda d: state.diff(state.integrate(x0, dx), state.integrate(x0, d)), dx),
                  "Jintegrate second")
    np.testing.assert_allclose(state.diff(x0, state.integrate(x0, dx)), dx, atol=1e-12)


@pytest.fixture(scope="module", params=["pinocchio", "kkt"])
def walking_nodes(bolt, request):
    ocp = WalkingOCP(bolt, dataclasses.replace(ALL_TERMS, dynamics_backend=request.param), n_nodes=12, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.2, 0.01, 12, t_start=0.0), np.array([0.1, 0.0, 0.3]))
    return ocp


@pytest.mark.parametrize("node", [0, 5, 9])
def test_integrated_node_derivatives_match_finite_differences(bolt, walking_nodes, node):
    """Fx, Fu (through the contact dynamics) and the cost gradient Lx, Lu of a running node."""
    problem = walking_nodes.problem
    model = problem.running_models[node]
    data = model.createData()
    state = problem.state
    rng = np.random.default_rng(node)
    x = random_state(bolt, rng)
    u = 0.5 * rng.standard_normal(model.nu)
    model.calc(data, x, u)
    model.calcDiff(data, x, u)

    def cost_of_x(xx):
        d = model.createData()
        model.calc(d, xx, u)
        return np.array([d.cost])

    def cost_of_u(uu):
        d = model.createData()
        model.calc(d, x, uu)
        return np.array([d.cost])

    Fx, Fu = _dynamics_fd(model, state, x, u, data.xnext)
    _assert_close(data.Fx, Fx, "Fx")
    _assert_close(data.Fu, Fu, "Fu")
    _assert_close(data.Lx, _tangent_fd(state, cost_of_x, x)[0], "Lx", rtol=1e-3)
    _assert_close(data.Lu, _control_fd(cost_of_u, u)[0], "Lu", rtol=1e-3)


def test_every_residual_jacobian_matches_finite_differences(bolt, walking_nodes):
    """Rx, Ru of every residual of the walking OCP, each at a node where it is active."""
    problem = walking_nodes.problem
    state = problem.state
    rng = np.random.default_rng(7)
    checked = set()
    for k, model in enumerate(problem.running_models):
        dam = model.differential
        todo = [name for name, item in dam.costs.costs.items() if item.active and name not in checked]
        if not todo:
            continue
        x = random_state(bolt, rng)
        u = 0.5 * rng.standard_normal(dam.nu)
        data = dam.createData()
        dam.calc(data, x, u)
        dam.calcDiff(data, x, u)
        for name in todo:
            residual = dam.costs.costs[name].cost.residual

            def r_of_x(xx, residual=residual, dam=dam, u=u):
                d = dam.createData()
                dam.calc(d, xx, u)
                rd = residual.createData()
                residual.calc(rd, xx, u, d.shared)
                return rd.r.copy()

            def r_of_u(uu, residual=residual, dam=dam, x=x):
                d = dam.createData()
                dam.calc(d, x, uu)
                rd = residual.createData()
                residual.calc(rd, x, uu, d.shared)
                return rd.r.copy()

            rdata = data.costs.terms[name].residual
            _assert_close(rdata.Rx, _tangent_fd(state, r_of_x, x), f"node {k} {name} Rx")
            _assert_close(rdata.Ru, _control_fd(r_of_u, u), f"node {k} {name} Ru")
            checked.add(name)
    kinds = {name.split("_", 1)[1] if name.startswith(("left_", "right_")) else name for name in checked}
    assert kinds >= {"state_regularization", "control_regularization", "control_bounds", "height", "foothold",
                     "contact_force", "friction_cone", "touchdown_height", "touchdown_velocity"}, kinds


def test_terminal_node_com_and_state_gradient(bolt, walking_nodes):
    problem = walking_nodes.problem
    model = problem.terminal_model
    state = problem.state
    x = random_state(bolt, np.random.default_rng(3))
    data = model.createData()
    model.calc(data, x)
    model.calcDiff(data, x)

    def cost_of_x(xx):
        d = model.createData()
        model.calc(d, xx)
        return np.array([d.cost])

    _assert_close(data.Lx, _tangent_fd(state, cost_of_x, x)[0], "terminal Lx", rtol=1e-3)
    np.testing.assert_allclose(data.xnext, x)


def test_activation_gradients():
    rng = np.random.default_rng(0)
    r = rng.standard_normal(5)
    for activation in (ActivationWeightedQuad(np.arange(1.0, 6.0)),
                       ActivationQuadraticBarrier(-0.5 * np.ones(5), 0.5 * np.ones(5))):
        data = activation.createData()
        activation.calc(data, r)
        activation.calcDiff(data, r)

        def a_of(rr, activation=activation):
            d = activation.createData()
            activation.calc(d, rr)
            return np.array([d.a_value])

        _assert_close(data.Ar, _control_fd(a_of, r)[0], type(activation).__name__)


def test_bad_inputs_raise_clear_errors(bolt):
    from wbmpc.errors import ParameterError

    with pytest.raises(ParameterError, match="barrier bounds need lower <= upper"):
        ActivationQuadraticBarrier(np.ones(2), np.zeros(2))
    with pytest.raises(ParameterError, match="n_nodes=0"):
        WalkingOCP(bolt, WalkingOCPConfig(), n_nodes=0, dt=0.01)
    with pytest.raises(ParameterError, match="control_weight=-1"):
        WalkingOCPConfig(control_weight=-1.0)
    state = StateMultibody(bolt.pinocchio_model)
    with pytest.raises(ParameterError, match=r"x0 has shape \(3,\)"):
        state.check_state("x0", np.zeros(3))
    ocp = WalkingOCP(bolt, WalkingOCPConfig(), n_nodes=5, dt=0.01)
    with pytest.raises(ParameterError, match="schedule has n_nodes=8"):
        ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 8), np.zeros(3))


def test_terminal_residuals_match_finite_differences(bolt, walking_nodes):
    """CoM position and swing-height residuals of the terminal node (no control)."""
    problem = walking_nodes.problem
    dam = problem.terminal_model.differential
    state = problem.state
    x = random_state(bolt, np.random.default_rng(11))
    data = dam.createData()
    dam.calc(data, x)
    dam.calcDiff(data, x)
    active = [name for name, item in dam.costs.costs.items() if item.active]
    assert "com_position" in active
    for name in active:
        residual = dam.costs.costs[name].cost.residual

        def r_of_x(xx, residual=residual):
            d = dam.createData()
            dam.calc(d, xx)
            rd = residual.createData()
            residual.calc(rd, xx, None, d.shared)
            return rd.r.copy()

        _assert_close(data.costs.terms[name].residual.Rx, _tangent_fd(state, r_of_x, x), f"terminal {name} Rx")


@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_flat_foot_contact_dynamics_match_finite_differences(backend):
    """6D (flat-foot) contacts with Baumgarte gains on G1: Fx and Fu of a running node."""
    g1 = load_robot("g1")
    config = WalkingOCPConfig(contact_force_weight=1e-3, baumgarte_gains=(10.0, 20.0), dynamics_backend=backend)
    ocp = WalkingOCP(g1, config, n_nodes=4, dt=0.02)
    schedule = alternating_schedule(0.0, 0.02, 4, step_duration=0.4, foot_y=(0.12, -0.12))
    ocp.update(standing_state(g1), schedule, np.array([0.0, 0.0, 0.7]))
    model = ocp.problem.running_models[1]
    state = ocp.state
    rng = np.random.default_rng(4)
    x = random_state(g1, rng, 0.05, 0.2)
    u = rng.standard_normal(model.nu)
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)

    Fx, Fu = _dynamics_fd(model, state, x, u, data.xnext)
    _assert_close(data.Fx, Fx, "G1 Fx", rtol=1e-3)
    _assert_close(data.Fu, Fu, "G1 Fu", rtol=1e-3)


def test_compiled_state_difference_matches_pinocchio(bolt):
    """The compiled free-flyer difference equals pin.difference, small to half-turn rotations."""
    import pinocchio as pin

    state = StateMultibody(bolt.pinocchio_model)
    assert state._compiled_difference
    rng = np.random.default_rng(9)
    model = bolt.pinocchio_model
    for scale in (1e-9, 1e-4, 0.3, 3.0):
        for _ in range(20):
            x0 = random_state(bolt, rng)
            x1 = np.concatenate([pin.integrate(model, x0[: model.nq], scale * rng.standard_normal(model.nv)),
                                 rng.standard_normal(model.nv)])
            expected = np.concatenate([pin.difference(model, x0[: model.nq], x1[: model.nq]),
                                       x1[model.nq:] - x0[model.nq:]])
            np.testing.assert_allclose(state.diff(x0, x1), expected, rtol=0, atol=1e-11)


@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_flight_node_after_stance_matches_finite_differences(bolt, backend):
    """A node without contact, evaluated after it was a stance node (its data reused): Fx, Fu."""
    ocp = WalkingOCP(bolt, WalkingOCPConfig(dynamics_backend=backend), n_nodes=4, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 4), np.array([0.0, 0.0, 0.3]))
    rng = np.random.default_rng(0)
    x, u = random_state(bolt, rng), rng.standard_normal(6)
    model, data = ocp.problem.running_models[2], ocp.problem.running_datas[2]
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    model.differential.set_active_contacts([])
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    state = ocp.state

    Fx, Fu = _dynamics_fd(model, state, x, u, data.xnext)
    _assert_close(data.Fx, Fx, "flight Fx")
    _assert_close(data.Fu, Fu, "flight Fu")
