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
    return run_scenario("walk", robot="g1", duration=2.5, velocity_command=(0.0, 0.0, 0.0), progress=False)


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
