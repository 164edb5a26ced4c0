"""The G1 in closed loop (MuJoCo, 1 kHz Riccati feedback, the library's MPC): the milestones of its
walking, each short (the long runs are in docs/scripts and benchmarks)."""

from __future__ import annotations

import numpy as np
import pytest

from sim.runner import run_scenario

# the G1 preset's OCP is evaluated batched: the node-wise fallback would warn, here an error
pytestmark = pytest.mark.filterwarnings("error::wbmpc.walking.ocp.SlowPathWarning")


@pytest.fixture(scope="module")
def in_place():
    """The DCM step QP (the preset's ALIP planner is the other fixture), without the ALIP's speed integral."""
    return run_scenario("walk", robot="g1", duration=2.5, velocity_command=(0.0, 0.0, 0.0), progress=False,
                        **{"footstep_planner.kind": "dcm", "controller.velocity_integral_gain": 0.0})


def test_g1_starts_from_standing_and_steps_in_place(in_place):
    log = in_place
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    switched = log.replans["stance_switched"] > 0
    assert switched.sum() >= 3  # steps taken, not a stand
    # both feet on the ground until the first stance begins (start_double_support of the preset)
    contacts = log.ticks["foot_contact"][log.ticks["t"] < 0.55]
    assert contacts.all()
    assert log.replans["mpc_ok"].mean() > 0.95
    # the soles stay where they landed, flat: no sliding of the stance foot beyond a few millimetres
    assert np.nanmax(log.replans["stance_slide"]) < 0.01


def test_g1_stepping_in_place_stays_in_place(in_place):
    com = in_place.ticks["com"]
    assert np.max(np.abs(com[-1, :2] - com[0, :2])) < 0.08


@pytest.fixture(scope="module")
def in_place_alip():
    return run_scenario("walk", robot="g1", duration=2.5, velocity_command=(0.0, 0.0, 0.0), progress=False,
                        **{"footstep_planner.kind": "alip"})


def test_g1_steps_in_place_with_the_alip_planner(in_place_alip):
    log = in_place_alip
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    assert log.params["omega"] == pytest.approx(np.sqrt(9.81 / 0.64))  # the ALIP's, not the DCM planner's
    r = log.replans
    assert (r["stance_switched"] > 0).sum() >= 3
    assert log.ticks["foot_contact"][log.ticks["t"] < 0.55].all()  # the start from standing
    assert r["sequencer_ok"].min() == 1.0 and r["mpc_ok"].mean() > 0.95
    # the planner got the whole body's angular momentum about the stance contact (logged), and stepping in place
    # it stays small: |L_y| < m z * 0.1 m/s
    assert np.all(np.isfinite(r["angular_momentum_contact_y"]))
    assert np.max(np.abs(r["angular_momentum_contact_y"])) < 33.34 * 0.64 * 0.1
    # the steps alternate about the start, the ALIP's width apart
    switched = np.flatnonzero(r["stance_switched"] > 0)
    widths = np.abs(np.diff(r["stance_y"][switched]))
    assert np.all(np.abs(widths - 0.22) < 0.05), widths
    com = log.ticks["com"]
    assert np.max(np.abs(com[-1, :2] - com[0, :2])) < 0.08
