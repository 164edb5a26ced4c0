"""The one-call KKT contact dynamics of a node (wbmpc/ocp/kernels/contact_dynamics.py) against the
separate calls (the actuation, the contact set's calc, the damped KKT solve): the same
accelerations, forces and KKT factors to the last bit. The rollouts' solve by triangular solves
(``calc_dynamics(..., rollout_dynamics="compiled")``, :func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`) against
the explicit-inverse one: the same accelerations and forces to rounding, also with M and b compiled on the
contacts' tree (no Pinocchio kinematics, :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_solve`). The
derivative pass with ``derivative_dynamics="compiled"`` (the RNEA derivatives compiled, with M and b where the costs
read no Pinocchio kinematics) against the default: the same accelerations and derivatives to rounding."""

from __future__ import annotations

import numpy as np
import pytest
from robot_extras import needs_h1_extra
from wbmpc_fixtures import alternating_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.kkt import KKTBuffers, damped_kkt_dynamics, damped_kkt_solve, velocity_parents
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig
from wbmpc.walking.preset import load_walking_preset


def _separate_calls(dam, data, x, u):
    """The dynamics as separate calls (the path of a node whose 6D contacts have Kp > 0): (a, forces, M⁻¹, Y)."""
    nq, nc = dam.state.nq, dam.nc
    q, v = x[:nq], x[nq:]
    dam.actuation.calc(data.tau, u)
    Jc, a0 = data.Jc_all[:nc], data.a0_all[:nc]
    dam.contact_set.calc(data.tree, data.contact_work, q, v, data.zero_acceleration, Jc, a0)
    a, forces = np.zeros(dam.state.nv), np.zeros(nc)
    buffers = data.kkt_buffers(nc)
    assert damped_kkt_dynamics(data.pinocchio.M, data.pinocchio.nle, data.tau, Jc, a0, dam.row_scales,
                               dam.contact_damping, a, forces, *buffers.dynamics_buffers())
    return a, forces, buffers.Minv.copy(), buffers.Y.copy()


def _assert_one_call_is_the_separate_calls(ocp, robot, seed: int) -> int:
    rng = np.random.default_rng(seed)
    checked = 0
    for model, data in zip(ocp.problem.running_models, ocp.problem.running_datas):
        dam, ddata = model.differential, data.differential
        if not dam.nc:
            continue
        assert not dam.contact_set.has_positioned_soles
        x = random_state(robot, rng, 0.02, 0.2)
        u = rng.standard_normal(dam.nu)
        dam.calc_dynamics(ddata, x, u)  # the one call
        a, forces = ddata.xout.copy(), ddata.force_all[:dam.nc].copy()
        buffers = ddata.kkt_buffers(dam.nc)
        Minv, Y = buffers.Minv.copy(), buffers.Y.copy()
        expected = _separate_calls(dam, ddata, x, u)
        assert np.array_equal(a, expected[0]) and np.array_equal(forces, expected[1])
        assert np.array_equal(Minv, expected[2]) and np.array_equal(Y, expected[3])
        for name, rows in dam._active_rows:
            assert np.array_equal(ddata.contacts[name].force, forces[rows])
        checked += 1
    return checked


def _assert_close(new, old, rtol=1e-12):
    """Agreement to rounding, relative to the vector's size (entries near zero are not compared alone)."""
    assert np.max(np.abs(new - old)) <= rtol * max(np.max(np.abs(old)), 1e-300), (new, old)


def _assert_rollout_solve_is_the_explicit_inverse(ocp, robot, seed: int) -> int:
    """calc_dynamics without derivatives (triangular solves) against with them (M⁻¹, Y formed), node by
    node: accelerations and forces to ~1e-12 relative; the derivatives refuse to run after it."""
    rng = np.random.default_rng(seed)
    checked = 0
    for model, data in zip(ocp.problem.running_models, ocp.problem.running_datas):
        dam, ddata = model.differential, data.differential
        x = random_state(robot, rng, 0.02, 0.2)
        u = rng.standard_normal(dam.nu)
        dam.calc_dynamics(ddata, x, u)
        a, forces = ddata.xout.copy(), ddata.force_all[:dam.nc].copy()
        buffers = ddata.kkt_buffers(dam.nc)
        factors = buffers.Minv.copy(), buffers.A.copy(), buffers.Y.copy(), buffers.J_scaled.copy()
        ddata.xout[:] = np.nan
        ddata.force_all[:] = np.nan
        dam.calc_dynamics(ddata, x, u, rollout_dynamics="compiled")
        _assert_close(ddata.xout, a)
        if dam.nc:
            _assert_close(ddata.force_all[:dam.nc], forces)
        for name, rows in dam._active_rows:
            assert np.array_equal(ddata.contacts[name].force, ddata.force_all[rows])
        if dam.nc and not dam.contact_set.has_positioned_soles:  # M and b compiled, no Pinocchio kinematics
            M, nle = np.triu(ddata.pinocchio.M), ddata.pinocchio.nle.copy()
            ddata.kinematics_for_costs = False
            ddata.xout[:] = np.nan
            dam.calc_dynamics(ddata, x, u, rollout_dynamics="compiled")
            ddata.kinematics_for_costs = True
            _assert_close(np.triu(ddata.M), M)
            _assert_close(ddata.nle, nle)
            assert np.array_equal(np.triu(ddata.pinocchio.M), M)  # Pinocchio's data not touched
            _assert_close(ddata.xout, a)
            _assert_close(ddata.force_all[:dam.nc], forces)
        # the derivatives' factors are left alone, and the derivatives refuse to read them
        assert all(np.array_equal(f, g) for f, g in zip(factors, (buffers.Minv, buffers.A, buffers.Y,
                                                                  buffers.J_scaled)))
        with pytest.raises(ParameterError, match="rollout_dynamics=.compiled."):
            dam.calc_diff_dynamics(ddata, x, u)
        dam.calc_dynamics(ddata, x, u)
        dam.calc_diff_dynamics(ddata, x, u)
        checked += 1
    return checked


def _assert_compiled_derivatives_are_pinocchios(ocp, robot, seed: int) -> int:
    """calc_dynamics and calc_diff_dynamics with derivative_dynamics="compiled" (with and without Pinocchio kinematics
    for the costs: Pinocchio's M and b, or the compiled ones) against the default, node by node: accelerations,
    forces, Fx, Fu and the forces' derivatives to ~1e-15 relative (1e-12 allowed); calc_and_diff_dynamics's one call
    (no Pinocchio kinematics, no positioned soles) the two calls' to the bit."""
    rng = np.random.default_rng(seed)
    checked = 0
    for model, data in zip(ocp.problem.running_models, ocp.problem.running_datas):
        dam, ddata = model.differential, data.differential
        if not dam.nc:
            continue
        x = random_state(robot, rng, 0.02, 0.2)
        u = rng.standard_normal(dam.nu)
        outputs = []
        for kinematics_for_costs, derivative_dynamics in ((True, "pinocchio"), (True, "compiled"), (False, "compiled")):
            ddata.kinematics_for_costs = kinematics_for_costs
            dam.calc_dynamics(ddata, x, u, derivative_dynamics=derivative_dynamics)
            dam.calc_diff_dynamics(ddata, x, u, derivative_dynamics)
            outputs.append([ddata.xout.copy(), ddata.force_all[:dam.nc].copy(), ddata.Fx.copy(), ddata.Fu.copy()]
                           + [np.hstack([ddata.contacts[name].df_dx, ddata.contacts[name].df_du])
                              for name in dam.active_contacts])
        if not dam.contact_set.has_positioned_soles:  # the two calls in one: the same numbers to the bit
            for array in (ddata.xout, ddata.force_all, ddata.Fx, ddata.Fu):
                array[:] = np.nan
            dam.calc_and_diff_dynamics(ddata, x, u, "compiled")
            fused = [ddata.xout, ddata.force_all[:dam.nc], ddata.Fx, ddata.Fu] + [
                np.hstack([ddata.contacts[name].df_dx, ddata.contacts[name].df_du]) for name in dam.active_contacts]
            assert all(np.array_equal(new, old) for new, old in zip(fused, outputs[2]))
            for name, rows in dam._active_rows:
                assert np.array_equal(ddata.contacts[name].force, outputs[2][1][rows])
        ddata.kinematics_for_costs = True
        for compiled in outputs[1:]:
            for new, old in zip(compiled, outputs[0]):
                _assert_close(new, old)
        checked += 1
    return checked


def _tree_inertia(rng, parents: np.ndarray) -> np.ndarray:
    """A random positive definite M (nv, nv) nonzero only between a row and its ancestors along
    ``parents`` (a joint-space inertia's sparsity), as M = Lᵀ D L."""
    nv = parents.size
    L = np.eye(nv)
    for k in range(nv):
        i = parents[k]
        while i >= 0:
            L[k, i] = 0.3 * rng.standard_normal()
            i = parents[i]
    return L.T @ np.diag(rng.uniform(0.1, 2.0, nv)) @ L


@pytest.mark.parametrize("nc, mu, tree", [(nc, mu, tree) for nc, mu in [(0, 0.0), (3, 0.0), (12, 1e-4), (12, 0.0), (24, 1e-3)]
                                          for tree in (False, True) if not (tree and nc > 22)])
def test_the_triangular_solve_is_the_explicit_inverse_to_rounding(nc, mu, tree):
    """damped_kkt_solve against damped_kkt_dynamics on random well-conditioned systems (nv = 25): a
    dense M with chain parents, and an M with the sparsity of the H1's tree (its velocity rows' parents; at most
    22 contact rows there: more rows on a leg than the leg and the base have dofs make a rank-deficient Jacobian)."""
    rng = np.random.default_rng(nc)
    nv = 25
    parents = np.arange(nv, dtype=np.int64) - 1
    if tree:  # the H1's: a free flyer, two legs of 5 joints, a torso and two arms of 4 joints on it
        parents = np.array([-1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 5, 11, 12, 13, 14, 5, 16, 17, 18, 19, 16, 21, 22, 23])
    for _ in range(5):
        if tree:
            M = _tree_inertia(rng, parents)
        else:
            B = rng.standard_normal((nv, nv + 4))
            M = B @ B.T + 0.1 * np.eye(nv)
        M = np.triu(M) + np.tril(np.full((nv, nv), np.nan), -1)  # the upper triangle is read
        nle, tau = rng.standard_normal(nv), rng.standard_normal(nv)
        Jc, a0 = rng.standard_normal((nc, nv)), rng.standard_normal(nc)
        if tree:
            Jc[:, 16:] = 0.0  # contacts on the legs
            Jc[:nc // 2, 11:16] = 0.0
            Jc[nc // 2:, 6:11] = 0.0
        scales = rng.uniform(0.05, 1.0, nc)
        buffers = KKTBuffers(nv, nc, 2 * nv)
        a, force = np.zeros(nv), np.zeros(nc)
        assert damped_kkt_dynamics(M, nle, tau, Jc, a0, scales, mu, a, force, *buffers.dynamics_buffers())
        a_solve, force_solve = np.full(nv, np.nan), np.full(nc, np.nan)
        assert damped_kkt_solve(M, nle, tau, Jc, a0, scales, mu, parents, a_solve, force_solve,
                                *buffers.solve_buffers())
        _assert_close(a_solve, a)
        if nc:
            _assert_close(force_solve, force)
            # the KKT system itself: M a − J̃ᵀ λ̃ = τ − b, J̃ a + ã0 = −μ λ̃ (λ̃ = force / s)
            lam = force_solve / scales
            Mfull = np.triu(M) + np.triu(M, 1).T
            Jt = scales[:, None] * Jc
            np.testing.assert_allclose(Mfull @ a_solve - Jt.T @ lam, tau - nle, atol=1e-9 * np.abs(Mfull @ a_solve).max())
            np.testing.assert_allclose(Jt @ a_solve + scales * a0, -mu * lam, atol=1e-9 * np.abs(Jt @ a_solve).max())


def test_the_triangular_solve_refuses_what_is_not_positive_definite():
    nv, nc = 6, 3
    rng = np.random.default_rng(0)
    buffers = KKTBuffers(nv, nc, 2 * nv)
    parents = np.arange(nv, dtype=np.int64) - 1
    nle, tau, Jc = rng.standard_normal(nv), rng.standard_normal(nv), rng.standard_normal((nc, nv))
    B = rng.standard_normal((nv, nv))
    for M in (-np.eye(nv), B @ np.diag([1.0, 1.0, -1.0, 1.0, 1.0, 1.0]) @ B.T, np.full((nv, nv), np.nan)):
        assert not damped_kkt_solve(M, nle, tau, Jc, np.zeros(nc), np.ones(nc), 0.0, parents, np.zeros(nv),
                                    np.zeros(nc), *buffers.solve_buffers())
    # a zero Jacobian and no damping: A J̃ᵀ + μ I = 0
    assert not damped_kkt_solve(np.eye(nv), nle, tau, np.zeros((nc, nv)), np.zeros(nc), np.ones(nc), 0.0, parents,
                                np.zeros(nv), np.zeros(nc), *buffers.solve_buffers())


def test_the_velocity_parents_are_pinocchios_rows_parents():
    for name in ("bolt", "g1"):
        model = load_robot(name).pinocchio_model
        assert np.array_equal(velocity_parents(model), np.asarray(model.createData().parents_fromRow))


def test_bolt_point_contacts_with_moving_references():
    """Point contacts (3 rows, LOCAL_WORLD_ALIGNED) with Kp > 0: their references are read at each call."""
    bolt = load_robot("bolt")
    config = WalkingOCPConfig(dynamics_backend="kkt", evaluation="nodes", baumgarte_gains=(10.0, 20.0),
                              contact_damping=1e-4)
    ocp = WalkingOCP(bolt, config, n_nodes=8, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 8, step_duration=0.05), np.array([0.0, 0.0, 0.3]))
    assert _assert_one_call_is_the_separate_calls(ocp, bolt, seed=1) >= 4
    assert _assert_rollout_solve_is_the_explicit_inverse(ocp, bolt, seed=3) == 8
    assert _assert_compiled_derivatives_are_pinocchios(ocp, bolt, seed=4) >= 4  # the point forces' rotation term


@needs_h1_extra
@pytest.mark.parametrize("moments", ["sole", "corners", "uniform"])
def test_h1_soles(moments):
    """6D soles (Kp = 0, the H1 preset's damping and its variants): single and double support."""
    h1 = load_robot("h1")
    config = load_walking_preset("h1").ocp.node_wise(contact_damping_moments=moments)
    ocp = WalkingOCP(h1, config, n_nodes=10, dt=0.02)
    ocp.update(standing_state(h1), alternating_schedule(0.0, 0.02, 10, step_duration=0.1, foot_y=(0.2, -0.2),
                                                        t_start=0.07), np.array([0.0, 0.0, 0.97]))
    assert _assert_one_call_is_the_separate_calls(ocp, h1, seed=2) == 10
    assert _assert_rollout_solve_is_the_explicit_inverse(ocp, h1, seed=4) == 10
    assert _assert_compiled_derivatives_are_pinocchios(ocp, h1, seed=6) == 10


@needs_h1_extra
def test_h1_soles_with_baumgarte_position_gains_take_the_separate_calls():
    """6D soles with Kp > 0 (positioned soles: the contacts and the KKT solve as separate calls): the
    rollouts' solve there too, and the compiled derivatives (the contacts' derivatives apart)."""
    h1 = load_robot("h1")
    config = load_walking_preset("h1").ocp.node_wise(baumgarte_gains=(10.0, 20.0))
    ocp = WalkingOCP(h1, config, n_nodes=6, dt=0.02)
    ocp.update(standing_state(h1), alternating_schedule(0.0, 0.02, 6, step_duration=0.1, foot_y=(0.2, -0.2),
                                                        t_start=0.05), np.array([0.0, 0.0, 0.97]))
    assert any(m.differential.nc and m.differential.contact_set.has_positioned_soles
               for m in ocp.problem.running_models)
    assert _assert_rollout_solve_is_the_explicit_inverse(ocp, h1, seed=5) == 6
    assert _assert_compiled_derivatives_are_pinocchios(ocp, h1, seed=7) == 6  # the soles' Kp term apart
