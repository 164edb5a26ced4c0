"""The one-call KKT contact dynamics of a node (wbmpc/ocp/kernels/contact_dynamics.py) against the
separate calls (the actuation, the contact set's calc, the damped KKT solve): the same
accelerations, forces and KKT factors to the last bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from robot_extras import needs_h1_extra
from wbmpc_fixtures import alternating_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.ocp.kernels.kkt import damped_kkt_dynamics
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


def test_bolt_point_contacts_with_moving_references():
    """Point contacts (3 rows, LOCAL_WORLD_ALIGNED) with Kp > 0: their references are read at each call."""
    bolt = load_robot("bolt")
    config = WalkingOCPConfig(dynamics_backend="kkt", evaluation="nodes", baumgarte_gains=(10.0, 20.0),
                              contact_damping=1e-4)
    ocp = WalkingOCP(bolt, config, n_nodes=8, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 8, step_duration=0.05), np.array([0.0, 0.0, 0.3]))
    assert _assert_one_call_is_the_separate_calls(ocp, bolt, seed=1) >= 4


@needs_h1_extra
@pytest.mark.parametrize("moments", ["sole", "corners", "uniform"])
def test_h1_soles(moments):
    """6D soles (Kp = 0, the H1 preset's damping and its variants): single and double support."""
    h1 = load_robot("h1")
    config = dataclasses.replace(load_walking_preset("h1").ocp, evaluation="nodes", contact_damping_moments=moments)
    ocp = WalkingOCP(h1, config, n_nodes=10, dt=0.02)
    ocp.update(standing_state(h1), alternating_schedule(0.0, 0.02, 10, step_duration=0.1, foot_y=(0.2, -0.2),
                                                        t_start=0.07), np.array([0.0, 0.0, 0.97]))
    assert _assert_one_call_is_the_separate_calls(ocp, h1, seed=2) == 10
