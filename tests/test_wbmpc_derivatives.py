"""calc/calcDiff of the wbmpc models and residuals against the library's numdiff (central differences on
the state manifold) at random states, block by block (base/joints × position/velocity)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from robot_extras import needs_h1_extra
from wbmpc_fixtures import alternating_schedule, crossing_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.ocp.activations import ActivationQuadraticBarrier, ActivationWeightedQuad
from wbmpc.ocp.numdiff import ActionModelNumDiff, tangent_jacobian, vector_jacobian
from wbmpc.ocp.state import StateMultibody
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig, swing_path, swing_path_fraction

EPS = float(np.finfo(float).eps)
RTOL = EPS ** (1.0 / 3.0)
"""Relative tolerance of a block: the relative step of the central differences."""
NOISE = 10.0 * EPS ** (2.0 / 3.0)
"""Floor relative to the whole matrix: rounding noise of central differences (eps/h, h = eps^(1/3))."""
ALL_TERMS = WalkingOCPConfig(foothold_weight=100.0, contact_force_weight=1e-2, friction_cone_weight=10.0,
                             touchdown_height_weight=1e5, touchdown_velocity_weight=1e3,
                             baumgarte_gains=(20.0, 40.0), evaluation="nodes")  # the node models themselves


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


def _tangent_blocks(state: StateMultibody) -> dict[str, slice]:
    """Blocks of a tangent vector: base and joints × position and velocity."""
    nv = state.nv
    return {"base q": slice(0, 6), "joint q": slice(6, nv), "base v": slice(nv, nv + 6),
            "joint v": slice(nv + 6, 2 * nv)}


WHOLE = {"": slice(None)}


def _assert_blocks_close(actual, expected, name, rows: dict, cols: dict, rtol: float = RTOL):
    """Every block (rows × cols) of ``actual`` within rtol of its own magnitude in ``expected``
    (numdiff), plus the rounding noise of the whole matrix."""
    actual = np.atleast_2d(actual)
    expected = np.atleast_2d(expected)
    noise = NOISE * float(np.max(np.abs(expected)))
    for row_name, r in rows.items():
        for col_name, c in cols.items():
            a, e = actual[r, c], expected[r, c]
            if e.size == 0:
                continue
            scale = float(np.max(np.abs(e)))
            err = float(np.max(np.abs(a - e)))
            tol = rtol * scale + noise
            assert err <= tol, (f"{name} [{row_name}, {col_name}]: max error {err:.3e} > {tol:.3e} "
                                f"(block scale {scale:.3e})")


def _dynamics_fd(model, x, u):
    """Numdiff Fx, Fu, Lx, Lu of a node at (x, u)."""
    numdiff = ActionModelNumDiff(model)
    data = numdiff.createData()
    numdiff.calcDiff(data, x, u)
    return data


def test_state_jacobians_match_finite_differences(bolt):
    state = StateMultibody(bolt.pinocchio_model)
    rng = np.random.default_rng(1)
    x0, x1 = random_state(bolt, rng), random_state(bolt, rng)
    blocks = _tangent_blocks(state)
    J0, J1 = state.Jdiff(x0, x1)
    _assert_blocks_close(J0, tangent_jacobian(state, lambda x: state.diff(x, x1), x0), "Jdiff first", blocks, blocks)
    _assert_blocks_close(J1, tangent_jacobian(state, lambda x: state.diff(x0, x), x1), "Jdiff second", blocks, blocks)
    dx = 0.1 * rng.standard_normal(state.ndx)
    Ji0, Ji1 = state.Jintegrate(x0, dx)
    _assert_blocks_close(Ji0, tangent_jacobian(
        state, lambda x: state.diff(state.integrate(x0, dx), state.integrate(x, dx)), x0), "Jintegrate first",
        blocks, blocks)
    _assert_blocks_close(Ji1, vector_jacobian(
        lambda d: state.diff(state.integrate(x0, dx), state.integrate(x0, d)), dx), "Jintegrate second",
        blocks, blocks)
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
    numdiff = _dynamics_fd(model, x, u)
    blocks = _tangent_blocks(state)
    _assert_blocks_close(data.Fx, numdiff.Fx, "Fx", blocks, blocks)
    _assert_blocks_close(data.Fu, numdiff.Fu, "Fu", blocks, WHOLE)
    _assert_blocks_close(data.Lx, numdiff.Lx, "Lx", WHOLE, blocks)
    _assert_blocks_close(data.Lu, numdiff.Lu, "Lu", WHOLE, WHOLE)


def _check_every_residual(robot, problem, rng) -> set:
    """Rx, Ru of every residual of ``problem`` against finite differences, each at a node where it
    is active; returns the names checked."""
    state = problem.state
    checked = set()
    for k, model in enumerate(problem.running_models):
        dam = model.differential
        todo = [name for name, item in dam.costs.costs.items() if item.active and name not in checked]
        if not todo:
            continue
        x = random_state(robot, rng)
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
            _assert_blocks_close(rdata.Rx, tangent_jacobian(state, r_of_x, x), f"node {k} {name} Rx", WHOLE,
                                 _tangent_blocks(state))
            _assert_blocks_close(rdata.Ru, vector_jacobian(r_of_u, u), f"node {k} {name} Ru", WHOLE, WHOLE)
            checked.add(name)
    return {name.split("_", 1)[1] if name.startswith(("left_", "right_")) else name for name in checked}


def test_every_residual_jacobian_matches_finite_differences(bolt, walking_nodes):
    """Rx, Ru of every residual of the walking OCP, each at a node where it is active."""
    kinds = _check_every_residual(bolt, walking_nodes.problem, np.random.default_rng(7))
    assert kinds >= {"state_regularization", "control_regularization", "control_bounds", "height", "foothold",
                     "contact_force", "friction_cone", "touchdown_height", "touchdown_velocity"}, kinds


def test_g1_flat_foot_residual_jacobians_match_finite_differences():
    """The G1 preset's flat-foot terms: wrench cones (through the 6D contact forces), swing-sole
    orientation, posture weights by joint name."""
    from wbmpc.walking.preset import load_walking_preset

    g1 = load_robot("g1")
    config = dataclasses.replace(load_walking_preset("g1").ocp, evaluation="nodes", baumgarte_gains=(10.0, 30.0))
    ocp = WalkingOCP(g1, config, n_nodes=6, dt=0.02)
    ocp.update(standing_state(g1), alternating_schedule(0.0, 0.02, 6, step_duration=0.08, foot_y=(0.12, -0.12)),
               np.array([0.05, 0.0, 0.7]))
    kinds = _check_every_residual(g1, ocp.problem, np.random.default_rng(11))
    assert kinds >= {"wrench_cone", "orientation", "state_regularization", "height"}, kinds


def test_terminal_node_com_and_state_gradient(bolt, walking_nodes):
    problem = walking_nodes.problem
    model = problem.terminal_model
    state = problem.state
    x = random_state(bolt, np.random.default_rng(3))
    data = model.createData()
    model.calc(data, x)
    model.calcDiff(data, x)
    numdiff = _dynamics_fd(model, x, None)
    _assert_blocks_close(data.Lx, numdiff.Lx, "terminal Lx", WHOLE, _tangent_blocks(state))
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

        _assert_blocks_close(data.Ar, vector_jacobian(a_of, r)[0], type(activation).__name__, WHOLE, WHOLE)


def test_bad_inputs_raise_clear_errors(bolt):
    from wbmpc.errors import ParameterError
    with pytest.raises(ParameterError, match="barrier bounds need lower <= upper"):
        ActivationQuadraticBarrier(np.ones(2), np.zeros(2))
    with pytest.raises(ParameterError, match="n_nodes=0"):
        WalkingOCP(bolt, WalkingOCPConfig(), n_nodes=0, dt=0.01)
    with pytest.raises(ParameterError, match="control_weight=-1"):
        WalkingOCPConfig(control_weight=-1.0)
    with pytest.raises(ParameterError, match="contact_damping=-0.001 must be finite and >= 0"):
        WalkingOCPConfig(contact_damping=-1e-3)
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

        _assert_blocks_close(data.costs.terms[name].residual.Rx, tangent_jacobian(state, r_of_x, x),
                             f"terminal {name} Rx", WHOLE, _tangent_blocks(state))


@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_flat_foot_contact_dynamics_match_finite_differences(backend):
    """6D (flat-foot) contacts with Baumgarte gains on G1: Fx and Fu of a running node."""
    g1 = load_robot("g1")
    config = WalkingOCPConfig(contact_force_weight=1e-3, baumgarte_gains=(10.0, 20.0), dynamics_backend=backend,
                              evaluation="nodes")
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

    numdiff = _dynamics_fd(model, x, u)
    blocks = _tangent_blocks(state)
    _assert_blocks_close(data.Fx, numdiff.Fx, "G1 Fx", blocks, blocks)
    _assert_blocks_close(data.Fu, numdiff.Fu, "G1 Fu", blocks, WHOLE)


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
    ocp = WalkingOCP(bolt, WalkingOCPConfig(dynamics_backend=backend, evaluation="nodes"), n_nodes=4, dt=0.01)
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

    numdiff = _dynamics_fd(model, x, u)
    blocks = _tangent_blocks(state)
    _assert_blocks_close(data.Fx, numdiff.Fx, "flight Fx", blocks, blocks)
    _assert_blocks_close(data.Fu, numdiff.Fu, "flight Fu", blocks, WHOLE)


DAMPINGS = [("pinocchio", "uniform"), ("kkt", "uniform"), ("kkt", "sole"), ("kkt", "corners"), ("pinocchio", "corners")]


def _h1_double_support_node(backend: str, damping: float, moments: str = "uniform"):
    """Node 1 of an H1 walking OCP in double support (both soles 6D contacts), with the wrench
    cone on (costs that read the contact forces); Baumgarte Kp = 10 except for the soles as four
    corner contacts on the Pinocchio backend, which need Kp = 0."""
    h1 = load_robot("h1")
    kp = 0.0 if (backend, moments) == ("pinocchio", "corners") else 10.0
    config = WalkingOCPConfig(wrench_cone_weight=1e2, contact_force_weight=1e-3, baumgarte_gains=(kp, 20.0),
                              contact_damping=damping, contact_damping_moments=moments, dynamics_backend=backend,
                              evaluation="nodes")
    ocp = WalkingOCP(h1, config, n_nodes=4, dt=0.02)
    schedule = alternating_schedule(0.0, 0.02, 4, step_duration=0.4, foot_y=(0.2, -0.2), t_start=1.0)
    ocp.update(standing_state(h1), schedule, np.array([0.0, 0.0, 0.97]))
    model = ocp.problem.running_models[1]
    assert model.differential.nc == 12
    return h1, ocp, model


@needs_h1_extra
@pytest.mark.parametrize("backend, moments", DAMPINGS)
def test_damped_contact_dynamics_match_finite_differences(backend, moments):
    """H1 double support, whose stacked contact Jacobian is rank deficient near the posture, with
    contact_damping 1e-3 (every row, or the moment rows by the sole's lever arms): Fx, Fu, and
    the gradient of the costs that read the forces."""
    h1, ocp, model = _h1_double_support_node(backend, 1e-3, moments)
    rng = np.random.default_rng(4)
    x = random_state(h1, rng, 0.02, 0.1)
    u = rng.standard_normal(model.nu)
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    numdiff = _dynamics_fd(model, x, u)
    blocks = _tangent_blocks(ocp.state)
    _assert_blocks_close(data.Fx, numdiff.Fx, "H1 damped Fx", blocks, blocks)
    _assert_blocks_close(data.Fu, numdiff.Fu, "H1 damped Fu", blocks, WHOLE)
    _assert_blocks_close(data.Lx, numdiff.Lx, "H1 damped Lx", WHOLE, WHOLE)
    _assert_blocks_close(data.Lu, numdiff.Lu, "H1 damped Lu", WHOLE, WHOLE)


@needs_h1_extra
@pytest.mark.parametrize("backend, moments", DAMPINGS)
def test_contact_damping_is_a_compliant_contact(backend, moments):
    """With damping μ the contact accelerations give way by μ λ: Jc a + a0 = −μ λ (uniform), −μ S⁻² λ
    (sole: S = 1 on the force rows, the sole's lever arms on the moment rows), or, for the sole as
    four corner point contacts each damped by 4 μ, Σ G_iᵀ (a_ci + Kd v_ci) + Kp 4 diag(1, 1, 1, r²)
    log6(error) = −4 μ W over its corners' classical accelerations (computed here from the sole's
    spatial motion), and the dynamics hold, M a + b = τ + Jcᵀ λ; the damped
    split bounds the internal squeeze the rigid contacts leave undetermined (the H1's soles in
    double support)."""
    import pinocchio as pin

    damping = 1e-3
    h1, ocp, model = _h1_double_support_node(backend, damping, moments)
    dam = model.differential
    assert bool(dam.damping_lever_arms) == (moments != "uniform")
    compliance = np.concatenate([np.ones(3), dam.damping_lever_arms["left"] ** -2] * 2) if moments == "sole" else 1.0
    rng = np.random.default_rng(7)
    x = random_state(h1, rng, 0.02, 0.1)
    u = rng.standard_normal(model.nu)
    forces = {}
    for mu in (0.0, damping):
        # rigid corners over-constrain a sole: its rigid limit is the 6D contact of the KKT backend
        corners = (backend, moments) == ("pinocchio", "corners")
        dam_mu = type(dam)(dam.state, dam.actuation, dam.contacts, dam.costs, dam.active_contacts,
                           "kkt" if corners and mu == 0.0 else backend, mu, dam.damping_lever_arms, dam.sole_corners)
        data = dam_mu.createData()
        dam_mu.calc(data, x, u)
        a = data.xout
        lam = np.concatenate([data.contacts[name].force for name in dam_mu.active_contacts])
        pmodel = h1.pinocchio_model
        pdata = pmodel.createData()
        q, v = x[: pmodel.nq], x[pmodel.nq:]
        pin.forwardKinematics(pmodel, pdata, q, v, a)
        pin.computeJointJacobians(pmodel, pdata, q)
        pin.updateFramePlacements(pmodel, pdata)
        Jc = np.vstack([pin.getFrameJacobian(pmodel, pdata, dam.contacts[n].frame_id, pin.LOCAL)
                        for n in dam_mu.active_contacts])
        tau = np.concatenate([np.zeros(6), u])
        residual = pin.rnea(pmodel, pdata, q, v, a) - tau - Jc.T @ lam
        assert np.max(np.abs(residual)) < 1e-7 * max(1.0, np.max(np.abs(lam)))
        # spatial acceleration of each sole, LOCAL, with the Baumgarte terms Kd v + Kp log6(error)
        acc = []
        for n in dam_mu.active_contacts:
            c = dam.contacts[n]
            kp, kd = c.gains
            ac = pin.getFrameAcceleration(pmodel, pdata, c.frame_id, pin.LOCAL)
            vel = pin.getFrameVelocity(pmodel, pdata, c.frame_id, pin.LOCAL)
            err = pin.log6(c.reference_placement().actInv(pdata.oMf[c.frame_id])).vector
            if moments != "corners":
                acc.append(ac.vector + kd * vel.vector + kp * err)
                continue
            b, a_half = dam.damping_lever_arms[n][:2]  # half width, half length
            lhs = 4.0 * kp * np.concatenate([np.ones(3), dam.damping_lever_arms[n] ** 2]) * err
            for corner in ([a_half, b, 0.0], [a_half, -b, 0.0], [-a_half, b, 0.0], [-a_half, -b, 0.0]):
                corner = np.array(corner)
                v_c = vel.linear + np.cross(vel.angular, corner)
                a_c = ac.linear + np.cross(ac.angular, corner) + np.cross(vel.angular, v_c)  # classical
                f_c = a_c + kd * v_c
                lhs += np.concatenate([f_c, np.cross(corner, f_c)])
            acc.append(lhs / 4.0)
        np.testing.assert_allclose(np.concatenate(acc), -mu * compliance * lam, rtol=0,
                                   atol=1e-6 * max(1.0, np.max(np.abs(lam))))
        forces[mu] = lam
    # the left sole's lateral force: the rigid solve splits the squeeze arbitrarily (hundreds of N)
    assert abs(forces[damping][1]) < 0.5 * abs(forces[0.0][1])


@needs_h1_extra
def test_sole_damping_splits_the_standing_load_as_the_quasi_static_split():
    """At rest on the posture with the quasi-static torques, the sole-weighted damping splits the
    load the rigid contacts cannot determine as quasi_static_load does (the same metric), each
    centre of pressure at its sole's centre; the uniform damping puts it 4 cm outside the 2 cm
    wide sole."""
    from wbmpc.walking.ocp import quasi_static_load

    h1 = load_robot("h1")
    x0 = standing_state(h1)
    cops = {}
    for moments, backend in (("sole", "kkt"), ("uniform", "pinocchio")):
        config = WalkingOCPConfig(baumgarte_gains=(0.0, 30.0), contact_damping=1e-4, contact_damping_moments=moments,
                                  dynamics_backend=backend, evaluation="nodes")
        ocp = WalkingOCP(h1, config, n_nodes=2, dt=0.02)
        ocp.update(x0, alternating_schedule(0.0, 0.02, 2, t_start=1.0, foot_y=(0.2, -0.2)), np.zeros(3))
        tau, wrenches = quasi_static_load(ocp, x0)
        dam = ocp.problem.running_models[0].differential
        data = dam.createData()
        dam.calc(data, x0, tau)
        forces = {foot: data.contacts[foot].force for foot in ("left", "right")}
        cops[moments] = max(abs(f[3] / f[2]) for f in forces.values())  # |lateral CoP| [m]
        if moments == "sole":  # the same split, up to the compliance (the soles give way by μ λ: 0.1 % of f_z)
            for foot, wrench in wrenches.items():
                np.testing.assert_allclose(forces[foot], wrench, rtol=0, atol=2e-3 * wrench[2])
    assert cops["sole"] < 1e-3 < 0.5 * h1.sole_size[1] < cops["uniform"]


def test_sole_damping_is_refused_where_it_cannot_apply(bolt):
    from wbmpc.errors import ParameterError
    from wbmpc.ocp.contacts import sole_lever_arms

    with pytest.raises(ParameterError, match="contact_damping_moments='sole' needs dynamics_backend='kkt'"):
        WalkingOCPConfig(contact_damping_moments="sole")
    with pytest.raises(ParameterError, match="contact_damping_moments='corners' with dynamics_backend='pinocchio' needs "
                       r"baumgarte_gains Kp = 0 .*got Kp=10.0"):
        WalkingOCPConfig(contact_damping_moments="corners", baumgarte_gains=(10.0, 20.0))
    with pytest.raises(ParameterError, match=r"contact_damping_moments='points' must be one of \('uniform', 'sole', "
                                             r"'corners'\)"):
        WalkingOCPConfig(contact_damping_moments="points")
    with pytest.raises(ParameterError, match="contact_damping_moments='sole' needs flat feet"):
        WalkingOCP(bolt, WalkingOCPConfig(contact_damping_moments="sole", dynamics_backend="kkt"), n_nodes=2, dt=0.01)
    np.testing.assert_allclose(sole_lever_arms((0.2, 0.1)), [0.05, 0.1, 0.5 * np.hypot(0.2, 0.1)])


@needs_h1_extra
def test_sole_corners_are_refused_where_they_cannot_apply():
    """The soles as four corner contacts (the "corners" damping on the Pinocchio backend) need every contact of the node
    to be such a sole (one damping for every row) with Kp = 0, and lever arms of a rectangle."""
    from wbmpc.errors import ParameterError
    from wbmpc.ocp.contacts import SoleCorners

    _, _, model = _h1_double_support_node("pinocchio", 1e-3, "corners")
    dam = model.differential
    arms = dam.damping_lever_arms["left"]
    with pytest.raises(ParameterError, match="with backend='pinocchio' need sole_corners=True"):
        type(dam)(dam.state, dam.actuation, dam.contacts, dam.costs, backend="pinocchio", contact_damping=1e-3,
                  damping_lever_arms=dam.damping_lever_arms)
    with pytest.raises(ParameterError, match=r"need every contact given lever arms .*\['right'\] have none"):
        type(dam)(dam.state, dam.actuation, dam.contacts, dam.costs, backend="pinocchio", contact_damping=1e-3,
                  damping_lever_arms={"left": arms}, sole_corners=True)
    with pytest.raises(ParameterError, match=r"damping_lever_arms\['left'\]: lever_arms=\[0.01, 0.07, 0.1\] are not a "
                                             "rectangle's"):
        type(dam)(dam.state, dam.actuation, dam.contacts, dam.costs, backend="kkt", contact_damping=1e-3,
                  damping_lever_arms={"left": [0.01, 0.07, 0.1]})
    with pytest.raises(ParameterError, match="need contact_damping > 0 .*got 0"):
        type(dam)(dam.state, dam.actuation, dam.contacts, dam.costs, backend="pinocchio", contact_damping=0.0,
                  damping_lever_arms=dam.damping_lever_arms, sole_corners=True)
    with pytest.raises(ParameterError, match="must be 3 finite lever arms > 0"):
        SoleCorners([0.01, -0.07, 0.1])
    kp_contacts = {name: type(c)(c.state, c.frame_id, c.reference, (5.0, 20.0)) for name, c in dam.contacts.items()}
    with pytest.raises(ParameterError, match="Kp=5.0 of the sole on frame .*need Kp = 0"):
        type(dam)(dam.state, dam.actuation, kp_contacts, dam.costs, backend="pinocchio", contact_damping=1e-3,
                  damping_lever_arms=dam.damping_lever_arms, sole_corners=True)


def _h1_crossing(n_nodes: int = 12):
    """The H1 preset's OCP (node-wise, KKT backend with a Baumgarte position gain) over a right swing that passes
    over a 10 cm box, its sole clearance gated by a straight path, no path (the walk's swings' included) or CoM
    tracking (the tests turn those on): (robot, ocp, schedule, crossings)."""
    from wbmpc.walking.preset import load_walking_preset

    h1 = load_robot("h1")
    config = load_walking_preset("h1").ocp.node_wise(
        dynamics_backend="kkt", baumgarte_gains=(10.0, 30.0), obstacle_clearance_gating="path",
        obstacle_swing_path_timing="straight", obstacle_swing_path_weight=0.0, swing_path_weight=0.0,
        obstacle_com_weight=0.0)
    ocp = WalkingOCP(h1, config, n_nodes=n_nodes, dt=0.02)
    schedule, crossings = crossing_schedule(n_nodes)
    return h1, ocp, schedule, crossings


@needs_h1_extra
def test_h1_obstacle_clearance_residual_jacobians_match_finite_differences():
    """The clearance terms of a crossing swing (sole toe and heel points, knee frame): their Jacobians through
    the point offsets against finite differences, each at a node where it is active."""
    h1, ocp, schedule, crossings = _h1_crossing()
    ocp.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    kinds = _check_every_residual(h1, ocp.problem, np.random.default_rng(13))
    assert kinds >= {"clearance_sole0", "clearance_sole1", "clearance_shank", "height"}, kinds


@needs_h1_extra
def test_h1_profile_shank_clearance_holds_the_knee_above_the_box_only_over_it():
    """``obstacle_shank_gating = "profile"``: the knee's clearance is active at every node of a crossing swing, on the
    box's height profile at the knee's own position (top + ``obstacle_shank_margin`` over the grown footprint, the
    ground beyond the transition), so a knee beside the box at lift-off or touchdown is asked nothing; its Jacobians
    match finite differences; an unknown gating is refused in one line."""
    h1, ocp, schedule, crossings = _h1_crossing()
    config = dataclasses.replace(ocp.config, obstacle_shank_gating="profile")
    profile_ocp = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
    profile_ocp.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    costs = [model.differential.costs.costs for model in profile_ocp.problem.running_models]
    swing = np.flatnonzero(~schedule.in_contact[:-1, 1])
    for k, node in enumerate(costs):
        assert node["right_clearance_shank"].active == (k in swing), k
    residual = costs[int(swing[0])]["right_clearance_shank"].cost.residual
    top = 0.1 + config.obstacle_shank_margin
    edge = 0.05 + config.obstacle_footprint_margin  # the fixture's box: 10 cm deep, centred at x = 0.25 m
    assert residual.profile([0.25, 0.0])[0] == pytest.approx(top)
    assert residual.profile([0.25 - edge - config.obstacle_profile_transition - 1e-6, 0.0])[0] == 0.0
    kinds = _check_every_residual(h1, profile_ocp.problem, np.random.default_rng(19))
    assert "clearance_shank" in kinds, kinds
    from wbmpc.errors import ParameterError
    with pytest.raises(ParameterError, match="obstacle_shank_gating='knee' must be one of"):
        WalkingOCPConfig(obstacle_shank_gating="knee")


@needs_h1_extra
def test_h1_clearance_of_every_leg_holds_a_step_beside_the_box_on_its_profile():
    """``obstacle_clearance_legs = "all"``: a swing that does not pass over the box (the last step before it, here the
    fixture's swing with its crossing index cleared) gets the sole and knee clearance on the box's profile while a
    crossing is planned, a standing leg the knee's; "crossing" leaves them without; "all" without both "profile"
    gatings is refused in one line."""
    from wbmpc.errors import ParameterError
    from wbmpc.walking.reference import CrossingSchedule

    h1, ocp, schedule, crossings = _h1_crossing()
    beside = CrossingSchedule(crossings.obstacles, np.full_like(crossings.index, -1), crossings.liftoff_xy * np.nan,
                              crossings.path_yaw * np.nan, crossings.feet)
    for legs, expected in (("crossing", False), ("all", True)):
        config = dataclasses.replace(ocp.config, obstacle_clearance_gating="profile", obstacle_shank_gating="profile",
                                     obstacle_clearance_legs=legs)
        other = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
        other.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=beside)
        for k, model in enumerate(other.problem.running_models):
            node = model.differential.costs.costs
            for j, foot in enumerate(schedule.feet):
                swinging = not schedule.in_contact[k, j]
                for term in ("clearance_sole0", "clearance_sole1"):
                    assert node[f"{foot}_{term}"].active == (expected and swinging), (legs, k, foot, term)
                assert node[f"{foot}_clearance_shank"].active == expected, (legs, k, foot)
    swing = int(np.flatnonzero(~schedule.in_contact[:-1, 1])[0])
    shank = other.problem.running_models[swing].differential.costs.costs["right_clearance_shank"].cost.residual
    assert shank.profile([0.25, 0.0])[0] == pytest.approx(0.1 + config.obstacle_shank_margin)
    with pytest.raises(ParameterError, match="obstacle_clearance_legs='all' needs obstacle_clearance_gating="):
        dataclasses.replace(config, obstacle_shank_gating="swing")
    with pytest.raises(ParameterError, match="obstacle_clearance_legs='every' must be one of"):
        dataclasses.replace(config, obstacle_clearance_legs="every")


@needs_h1_extra
def test_h1_profile_clearance_holds_the_sole_points_above_the_box_wherever_they_are():
    """``obstacle_clearance_gating = "profile"``: the sole points' clearance is active at every node of a crossing swing
    (not only where the planned path is over the box) with the box's height profile, whose value and gradient are
    the top + margin over the grown footprint, the ground beyond the transition, C1 between (finite differences);
    the residual's Jacobians match finite differences."""
    h1, ocp, schedule, crossings = _h1_crossing()
    config = dataclasses.replace(ocp.config, obstacle_clearance_gating="profile")
    profile_ocp = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
    x0 = standing_state(h1)
    profile_ocp.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    costs = [model.differential.costs.costs for model in profile_ocp.problem.running_models]
    for k, node in enumerate(costs):
        swinging = not schedule.in_contact[k, 1]
        for i in range(len(config.obstacle_sole_points)):
            assert node[f"right_clearance_sole{i}"].active == swinging, k
    residual = costs[int(np.flatnonzero(~schedule.in_contact[:-1, 1])[0])]["right_clearance_sole0"].cost.residual
    top = 0.1 + config.obstacle_clearance_margin
    edge = 0.05 + config.obstacle_footprint_margin  # the fixture's box: 10 cm deep, centred at x = 0.25 m
    assert residual.profile([0.25, 0.0])[0] == pytest.approx(top)
    assert residual.profile([0.25 + edge - 1e-6, 0.3])[0] == pytest.approx(top)
    assert residual.profile([0.25 + edge + config.obstacle_profile_transition + 1e-6, 0.0])[0] == 0.0
    h = 1e-7
    for xy in ([0.25 + edge + 0.02, 0.1], [0.25 - edge - 0.031, -0.2], [0.25, 0.0]):
        xy = np.array(xy)
        value, gradient = residual.profile(xy)
        numeric = [(residual.profile(xy + h * e)[0] - residual.profile(xy - h * e)[0]) / (2 * h) for e in np.eye(2)]
        assert gradient == pytest.approx(numeric, abs=1e-6), xy
    assert residual.profile([0.25 + edge + 0.02, 0.0])[1][0] < 0.0  # falling away from the box
    kinds = _check_every_residual(h1, profile_ocp.problem, np.random.default_rng(17))
    assert {"clearance_sole0", "clearance_sole1"} <= kinds, kinds
    # and with the point on the profile's slope (the box placed beside where it is): Rx through ∇h
    k = int(np.flatnonzero(~schedule.in_contact[:-1, 1])[0])
    dam = profile_ocp.problem.running_models[k].differential
    rng = np.random.default_rng(5)
    x, u = random_state(h1, rng), np.zeros(dam.nu)
    data = dam.createData()
    dam.calc(data, x, u)
    point = residual._point(data.shared)
    axis = np.array([np.cos(0.3), np.sin(0.3)])
    residual.set_box(point[:2] - (0.05 + config.obstacle_footprint_margin + 0.02) * axis, axis, 0.05, 0.6, top)
    assert 0.0 < residual.profile(point[:2])[0] < top and np.linalg.norm(residual.profile(point[:2])[1]) > 1.0
    dam.calcDiff(data, x, u)

    def r_of_x(xx):
        d = dam.createData()
        dam.calc(d, xx, u)
        rd = residual.createData()
        residual.calc(rd, xx, u, d.shared)
        return rd.r.copy()

    rdata = data.costs.terms["right_clearance_sole0"].residual
    _assert_blocks_close(rdata.Rx, tangent_jacobian(dam.state, r_of_x, x), "on the slope", WHOLE,
                         _tangent_blocks(dam.state))
    from wbmpc.errors import ParameterError
    with pytest.raises(ParameterError, match="obstacle_clearance_gating='actual' must be one of"):
        WalkingOCPConfig(obstacle_clearance_gating="actual")
    with pytest.raises(ParameterError, match="obstacle_profile_transition=0.0 m must be finite and > 0"):
        WalkingOCPConfig(obstacle_profile_transition=0.0)


@needs_h1_extra
def test_h1_com_path_is_tracked_only_while_the_horizon_holds_a_crossing():
    """``obstacle_com_weight`` > 0: the running ``com_path`` terms track the given CoM path (x, y) at every running node
    of an update with crossings, and are off otherwise; a path of the wrong shape is refused."""
    from wbmpc.errors import ParameterError

    h1, ocp, schedule, crossings = _h1_crossing()
    config = dataclasses.replace(ocp.config, obstacle_com_weight=1e2)
    assert "com_path" not in ocp.problem.running_models[0].differential.costs.costs  # weight 0: absent
    tracking = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
    x0 = standing_state(h1)
    path = np.column_stack([np.linspace(0.0, 0.3, ocp.n_nodes + 1), np.full(ocp.n_nodes + 1, 0.01),
                            np.full(ocp.n_nodes + 1, 0.97)])
    items = [model.differential.costs.costs["com_path"] for model in tracking.problem.running_models]
    tracking.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings, com_path=path)
    assert all(item.active for item in items)
    for k, item in enumerate(items):
        assert item.cost.residual.reference == pytest.approx(path[k])
    tracking.update(x0, schedule, np.array([0.1, 0.0, 0.97]), com_path=path)  # no crossing in the horizon
    assert not any(item.active for item in items)
    with pytest.raises(ParameterError, match=r"com_path has shape \(3, 3\), expected"):
        tracking.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings, com_path=path[:3])
    with pytest.raises(ParameterError, match="obstacle_com_weight=-1.0 must be finite and >= 0"):
        WalkingOCPConfig(obstacle_com_weight=-1.0)


@needs_h1_extra
def test_h1_leg_posture_is_scaled_only_while_the_horizon_holds_a_crossing():
    """``obstacle_leg_posture_scale`` != 1: the legs' joint-position rows (the ten joints from the hips to the
    ankles, not the torso or arms) are the separate term ``leg_posture``; the problem's cost equals the unsplit
    one without a crossing and drops by (1 - scale) x the legs' posture cost with one; the turned base reference
    reaches both terms."""
    from wbmpc.errors import ParameterError

    h1, ocp, schedule, crossings = _h1_crossing()
    assert "leg_posture" not in ocp.problem.running_models[0].differential.costs.costs  # scale 1: one term
    model = h1.pinocchio_model
    legs = [model.names[j] for j in range(model.njoints) if model.joints[j].idx_v in ocp.leg_position_rows]
    assert sorted(legs) == sorted(f"{side}_{joint}" for side in ("left", "right")
                                  for joint in ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle"))
    scale = 0.1
    split, free = (WalkingOCP(h1, dataclasses.replace(ocp.config, obstacle_leg_posture_scale=value),
                              n_nodes=ocp.n_nodes, dt=0.02) for value in (scale, 0.0))
    x0 = standing_state(h1)
    x0[7:] += 0.1 * np.sin(np.arange(x0.size - 7))  # off the reference posture
    xs, us = [x0] * (ocp.n_nodes + 1), [np.zeros(ocp.nu)] * ocp.n_nodes
    com = np.array([0.1, 0.0, 0.97])
    items = [m.differential.costs.costs["leg_posture"]
             for m in list(split.problem.running_models) + [split.problem.terminal_model]]
    for crossing in (None, crossings):
        costs = []
        for problem in (ocp, split, free):
            problem.update(x0, schedule, com, crossings=crossing)
            costs.append(problem.problem.calc(xs, us))
        whole, parts, without_legs = costs
        assert all(item.weight == pytest.approx(ocp.config.state_weight * (1.0 if crossing is None else scale))
                   for item in items)
        if crossing is None:
            assert parts == pytest.approx(whole, rel=1e-12) and without_legs == pytest.approx(whole, rel=1e-12)
        else:  # the legs' posture cost whole - without_legs, scaled
            assert whole - without_legs > 0.01
            assert parts == pytest.approx(without_legs + scale * (whole - without_legs), rel=1e-12)
    for m in split.problem.running_models:
        costs = m.differential.costs.costs
        assert np.array_equal(costs["leg_posture"].cost.residual.reference,
                              costs["state_regularization"].cost.residual.reference)
    with pytest.raises(ParameterError, match="obstacle_leg_posture_scale=-0.5 must be finite and >= 0"):
        WalkingOCPConfig(obstacle_leg_posture_scale=-0.5)


@needs_h1_extra
def test_h1_swing_orientation_is_scaled_only_at_crossing_swing_nodes():
    """``obstacle_swing_orientation_scale`` != 1: the ``{foot}_orientation`` weight is scaled at the nodes of a crossing
    swing (crossings.index >= 0) and stays ``swing_orientation_weight`` at every other node and without crossings."""
    from wbmpc.errors import ParameterError

    h1, ocp, schedule, crossings = _h1_crossing()
    scale = 0.1
    scaled = WalkingOCP(h1, dataclasses.replace(ocp.config, obstacle_swing_orientation_scale=scale),
                        n_nodes=ocp.n_nodes, dt=0.02)
    weight = ocp.config.swing_orientation_weight
    assert weight > 0
    x0 = standing_state(h1)
    columns = [list(schedule.feet).index(foot) for foot in scaled.feet]
    crossing = np.asarray(crossings.index)[:, columns] >= 0
    assert crossing.any() and not crossing.all()
    for given in (crossings, None, crossings):
        scaled.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=given)
        for k, model in enumerate(scaled.problem.running_models):
            for j, foot in enumerate(scaled.feet):
                item = model.differential.costs.costs[f"{foot}_orientation"]
                expected = weight * scale if given is not None and crossing[k, j] else weight
                assert item.weight == expected
    with pytest.raises(ParameterError, match="obstacle_swing_orientation_scale=-1.0 must be finite and >= 0"):
        WalkingOCPConfig(obstacle_swing_orientation_scale=-1.0)


@needs_h1_extra
def test_h1_abducted_crossing_swing_moves_the_path_outwards_and_rolls_the_sole_over_high_boxes_only():
    """``obstacle_swing_abduction`` / ``obstacle_swing_roll``: over a box at least ``obstacle_abduction_height_min``
    high, a crossing swing's path reference moves outwards (the right foot to -y on a path along +x) by the abduction
    times the normalised height reference, and its sole's orientation reference is the flat one rolled outwards
    (about x, negative for the right foot) by the roll times the same profile; over a lower box, and at every node
    of no crossing swing, both are the unshaped problem's; bad values are refused in one line."""
    from wbmpc.errors import ParameterError

    h1, base, schedule, crossings = _h1_crossing()
    abduction, roll = 0.15, 0.35
    top = float(crossings.obstacles[0].height)
    x0, com = standing_state(h1), np.array([0.1, 0.0, 0.97])

    def references(**options):
        ocp = WalkingOCP(h1, dataclasses.replace(base.config, obstacle_swing_path_weight=1e4, **options),
                         n_nodes=base.n_nodes, dt=0.02)
        ocp.update(x0, schedule, com, crossings=crossings)
        costs = [model.differential.costs.costs for model in ocp.problem.running_models]
        path = np.array([c["right_swing_path"].cost.residual.reference[:2].copy() if c["right_swing_path"].active
                         else np.full(2, np.nan) for c in costs])
        rotation = np.array([c["right_orientation"].cost.residual.reference.copy() for c in costs])
        height = np.array([c["right_height"].cost.residual.reference if c["right_height"].active else np.nan
                           for c in costs])
        return ocp, path, rotation, height

    flat_ocp, flat_path, flat_rotation, height = references()
    assert flat_ocp.foot_sides.tolist() == [1.0, -1.0] and flat_ocp.feet == ("left", "right")
    shaped_ocp, path, rotation, shaped_height = references(obstacle_swing_abduction=abduction,
                                                           obstacle_swing_roll=roll, obstacle_abduction_height_min=top)
    crossing = np.asarray(crossings.index)[:-1, list(schedule.feet).index("right")] >= 0
    assert crossing.sum() >= 3 and np.array_equal(np.isfinite(flat_path[:, 0]), crossing)
    profile = (height - shaped_ocp.ground_height) / np.nanmax(height - shaped_ocp.ground_height)
    np.testing.assert_array_equal(shaped_height, height)
    np.testing.assert_allclose(path[crossing, 0], flat_path[crossing, 0], atol=1e-12)  # the path runs along +x
    np.testing.assert_allclose(path[crossing, 1], flat_path[crossing, 1] - abduction * profile[crossing], atol=1e-12)
    assert np.nanmax(flat_path[crossing, 1] - path[crossing, 1]) == pytest.approx(abduction)
    for k in range(base.n_nodes):
        angle = -roll * profile[k] if crossing[k] else 0.0
        np.testing.assert_allclose(rotation[k], flat_rotation[k] @ pin.utils.rotate("x", angle), atol=1e-12)
    _, low_path, low_rotation, _ = references(obstacle_swing_abduction=abduction, obstacle_swing_roll=roll,
                                              obstacle_abduction_height_min=top + 0.01)
    np.testing.assert_array_equal(low_path, flat_path)
    np.testing.assert_array_equal(low_rotation, flat_rotation)
    for name, value, allowed in (("obstacle_swing_abduction", -0.1, "must be finite and >= 0"),
                                 ("obstacle_abduction_height_min", np.inf, "must be finite and >= 0"),
                                 ("obstacle_swing_roll", 2.0, r"must be in \[0, pi/2\)")):
        with pytest.raises(ParameterError, match=f"{name}={value!r} .*{allowed}"):
            WalkingOCPConfig(**{name: value})


def test_the_swing_path_timings_go_from_lift_off_to_touchdown_and_smooth_lands_at_rest():
    from wbmpc.errors import ParameterError
    phase = np.linspace(0.0, 1.0, 101)
    assert np.array_equal(swing_path_fraction(phase, "straight"), phase)
    smooth = swing_path_fraction(phase, "smooth")
    assert smooth[0] == 0.0 and smooth[-1] == 1.0 and smooth[50] == pytest.approx(0.5)
    assert np.all(np.diff(smooth) > 0)
    h = 1e-6  # at rest at both ends; the peak velocity 15/8 of the mean at s = 1/2
    assert swing_path_fraction(h, "smooth") / h < 1e-10 and (1 - swing_path_fraction(1 - h, "smooth")) / h < 1e-10
    assert (swing_path_fraction(0.5 + h, "smooth") - swing_path_fraction(0.5 - h, "smooth")) / (2 * h) == \
        pytest.approx(1.875)
    path = swing_path(np.array([0.0, 0.1]), np.array([0.6, -0.1]), np.array([0.0, 0.5, 1.0]), "smooth")
    assert path == pytest.approx(np.array([[0.0, 0.1], [0.3, 0.0], [0.6, -0.1]]))
    with pytest.raises(ParameterError, match="timing='linear' must be one of \\('straight', 'smooth'\\)"):
        swing_path_fraction(phase, "linear")
    with pytest.raises(ParameterError, match="obstacle_swing_path_timing='linear' must be one of"):
        WalkingOCPConfig(obstacle_swing_path_timing="linear")
    with pytest.raises(ParameterError, match="obstacle_swing_path_weight"):
        WalkingOCPConfig(obstacle_swing_path_weight=-1.0)


@needs_h1_extra
def test_h1_smooth_crossing_swing_is_tracked_along_its_path_and_gated_where_that_path_is_over_the_box():
    """A crossing swing timed "smooth" with the path term on: ``{foot}_swing_path`` is active at every node of a
    crossing swing (the fixture's swings all cross) with the smooth path's (x, y) as reference, nowhere else;
    the sole barriers are gated and the plateau held where the smooth path (not the straight one) puts a sole
    point over the grown footprint."""
    h1, ocp, schedule, crossings = _h1_crossing()
    config = dataclasses.replace(ocp.config, obstacle_swing_path_timing="smooth", obstacle_swing_path_weight=1e4,
                                 obstacle_plateau_transition_min=0.05)
    assert "right_swing_path" not in ocp.problem.running_models[0].differential.costs.costs  # weight 0: absent
    smooth_ocp = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
    x0 = standing_state(h1)
    costs = [model.differential.costs.costs for model in smooth_ocp.problem.running_models]
    smooth_ocp.update(x0, schedule, np.array([0.1, 0.0, 0.97]))  # no crossing: no path tracking
    assert not any(node[f"{foot}_swing_path"].active for node in costs for foot in ("left", "right"))
    smooth_ocp.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    path = swing_path(crossings.liftoff_xy, schedule.touchdown_position, schedule.swing_phase, "smooth")[:, 1]
    straight = swing_path(crossings.liftoff_xy, schedule.touchdown_position, schedule.swing_phase)[:, 1]
    sole_x = np.array([point[0] for point in config.obstacle_sole_points])
    reach = 0.05 + config.obstacle_footprint_margin
    differs = 0
    for k, node in enumerate(costs):
        swinging = not schedule.in_contact[k, 1]
        tracking = node["right_swing_path"]
        assert tracking.active == swinging and node["left_swing_path"].active == (not schedule.in_contact[k, 0]), k
        if swinging:
            assert tracking.cost.residual.reference[:2] == pytest.approx(path[k]), k
            over = np.abs(path[k, 0] + sole_x - 0.25) <= reach
            assert [node[f"right_clearance_sole{i}"].active for i in range(sole_x.size)] == over.tolist(), k
            if over.any():
                assert node["right_height"].cost.residual.reference == pytest.approx(0.1 + config.obstacle_apex_margin)
            differs += bool(np.any(over != (np.abs(straight[k, 0] + sole_x - 0.25) <= reach)))
    assert differs  # the two timings gate different nodes on this swing


@needs_h1_extra
def test_h1_every_swing_tracks_its_path_from_its_liftoff_with_the_swing_path_weight():
    """``swing_path_weight`` > 0: ``{foot}_swing_path`` is active at every running swing node whose lift-off is given,
    with the ``swing_path_timing`` path from it to the touchdown as reference and that weight; off where the lift-off
    is NaN or not given. A crossing swing tracks its own path with ``obstacle_swing_path_weight`` when that is > 0,
    and the next update without the crossing restores the weight. A lift-off array of the wrong shape is refused."""
    from wbmpc.errors import ParameterError

    h1, ocp, schedule, crossings = _h1_crossing()
    config = dataclasses.replace(ocp.config, swing_path_weight=1e3, swing_path_timing="smooth")
    paths = WalkingOCP(h1, config, n_nodes=ocp.n_nodes, dt=0.02)
    x0, com = standing_state(h1), np.array([0.1, 0.0, 0.97])
    swinging = ~schedule.in_contact
    liftoff = np.where(swinging[..., None], np.array([[-0.3, 0.2], [-0.1, -0.25]]), np.nan)
    liftoff[2] = np.nan  # a node whose swing's lift-off is unknown
    costs = [model.differential.costs.costs for model in paths.problem.running_models]
    paths.update(x0, schedule, com)
    assert not any(node[f"{foot}_swing_path"].active for node in costs for foot in ("left", "right"))
    paths.update(x0, schedule, com, swing_liftoff=liftoff)
    expected = swing_path(np.nan_to_num(liftoff), np.nan_to_num(schedule.touchdown_position),
                          np.nan_to_num(schedule.swing_phase), "smooth")
    for k, node in enumerate(costs):
        for j, foot in enumerate(("left", "right")):
            item = node[f"{foot}_swing_path"]
            assert item.active == (swinging[k, j] and k != 2), (k, foot)
            if item.active:
                assert item.weight == 1e3 and item.cost.residual.reference[:2] == pytest.approx(expected[k, j])
    assert sum(node["right_swing_path"].active for node in costs) >= 3
    crossing = WalkingOCP(h1, dataclasses.replace(config, obstacle_swing_path_weight=1e4,
                                                  obstacle_swing_path_timing="straight"), n_nodes=ocp.n_nodes, dt=0.02)
    costs = [model.differential.costs.costs for model in crossing.problem.running_models]
    crossing.update(x0, schedule, com, crossings=crossings, swing_liftoff=liftoff)
    straight = swing_path(crossings.liftoff_xy, schedule.touchdown_position, schedule.swing_phase)
    for k, node in enumerate(costs):  # the fixture's swings all cross: the crossing's path and weight everywhere
        for j, foot in enumerate(("left", "right")):
            item = node[f"{foot}_swing_path"]
            assert item.active == swinging[k, j], (k, foot)
            if item.active:
                assert item.weight == 1e4 and item.cost.residual.reference[:2] == pytest.approx(straight[k, j])
    crossing.update(x0, schedule, com, swing_liftoff=liftoff)
    assert all(node["right_swing_path"].weight == 1e3 for k, node in enumerate(costs) if swinging[k, 1] and k != 2)
    with pytest.raises(ParameterError, match=r"swing_liftoff has shape \(3, 2, 2\), the schedule's touchdowns"):
        paths.update(x0, schedule, com, swing_liftoff=liftoff[:3])
    with pytest.raises(ParameterError, match="swing_path_timing='linear' must be one of"):
        WalkingOCPConfig(swing_path_timing="linear")
    with pytest.raises(ParameterError, match="swing_path_weight=-1.0 must be finite and >= 0"):
        WalkingOCPConfig(swing_path_weight=-1.0)


@needs_h1_extra
def test_h1_crossing_swing_holds_a_plateau_over_the_box_and_turns_the_clearance_on_only_over_it():
    h1, ocp, schedule, crossings = _h1_crossing()
    x0 = standing_state(h1)
    ocp.update(x0, schedule, np.array([0.1, 0.0, 0.97]))  # no crossing: every clearance term off
    costs = [model.differential.costs.costs for model in ocp.problem.running_models]
    assert not any(item.active for node in costs for name, item in node.items() if "clearance" in name)
    plain_heights = [node["right_height"].cost.residual.reference for node in costs]
    ocp.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    config = ocp.config
    assert config.obstacle_swing_path_timing == "straight"
    straight_x = swing_path(crossings.liftoff_xy, schedule.touchdown_position, schedule.swing_phase)[:, 1, 0]
    for k, node in enumerate(costs):
        swinging = not schedule.in_contact[k, 1]
        toe = node["right_clearance_sole0"]
        # the toe's straight-path position over the box grown by the footprint margin, its reference the top + margin
        toe_x = straight_x[k] + config.obstacle_sole_points[0][0]
        over = swinging and abs(toe_x - 0.25) <= 0.05 + config.obstacle_footprint_margin
        assert toe.active == over, k
        if over:
            assert toe.cost.residual.reference == pytest.approx(0.1 + config.obstacle_clearance_margin)
        assert node["right_clearance_shank"].active == swinging
        if swinging and 0.0 < schedule.swing_phase[k, 1] < 1.0:  # the swing is raised: the reference higher
            assert node["right_height"].cost.residual.reference > plain_heights[k]
    assert config.obstacle_swing_profile == "plateau"
    plateau = [node["right_height"].cost.residual.reference for node in costs]
    assert max(plateau) == pytest.approx(0.1 + config.obstacle_apex_margin)  # not the 1.7 m an apex would need
    # with the shortest transitions, the plateau covers every node where a sole point is over the grown footprint
    for profile in ("plateau", "apex"):
        other = WalkingOCP(h1, dataclasses.replace(config, obstacle_swing_profile=profile,
                                                   obstacle_plateau_transition_min=0.05), n_nodes=ocp.n_nodes, dt=0.02)
        other.update(x0, schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
        heights = [model.differential.costs.costs["right_height"].cost.residual.reference
                   for model in other.problem.running_models]
        if profile == "apex":
            assert max(heights) > max(plateau)  # eq. (19) clearing the same nodes peaks higher
            continue
        for k, height in enumerate(heights):
            path_x = straight_x[k] + np.array([point[0] for point in config.obstacle_sole_points])
            if not schedule.in_contact[k, 1] and np.any(np.abs(path_x - 0.25) <= 0.05 + config.obstacle_footprint_margin):
                assert height == pytest.approx(0.1 + config.obstacle_apex_margin), k
    # one-sided: no cost above the reference, a quadratic one below
    model = ocp.problem.running_models[0].differential
    data = model.createData()
    shank, u = model.costs.costs["right_clearance_shank"], np.zeros(ocp.nu)
    assert shank.active  # the right foot swings from node 0

    def cost(reference, active=True):
        shank.cost.residual.reference, shank.active = reference, active
        model.calc(data, x0, u)
        return data.cost

    assert cost(-1.0) == cost(-1.0, active=False)  # the knee far above a reference 1 m below the ground
    assert cost(2.0) > cost(2.0, active=False) + 1.0  # a reference above the knee
