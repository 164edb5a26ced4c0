"""The H1 in closed loop (MuJoCo, 1 kHz Riccati feedback, the library's MPC): it starts from
standing and steps in place, short (the long runs are in docs/closed_loop.md, "The H1")."""

from __future__ import annotations

import numpy as np
import pytest
from robot_extras import needs_h1_extra

from sim.runner import run_scenario
from wbmpc.walking.ocp import SlowPathWarning

# the H1 preset's "sole" contact damping is solved node-wise by the KKT backend (SlowPathWarning, said once per run)
pytestmark = [needs_h1_extra, pytest.mark.filterwarnings(f"ignore::{SlowPathWarning.__module__}.SlowPathWarning")]


@pytest.fixture(scope="module")
def in_place():
    return run_scenario("walk", robot="h1", duration=2.0, velocity_command=(0.0, 0.0, 0.0), progress=False)


def test_h1_starts_from_standing_and_steps_in_place(in_place):
    log = in_place
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    switched = log.replans["stance_switched"] > 0
    assert switched.sum() >= 2  # steps taken, not a stand
    t = log.ticks["t"]
    # both feet down until the first stance (start_double_support), once the sole spheres, which
    # start exactly on the floor, have settled into contact (the first 2 ms)
    contacts = log.ticks["foot_contact"][(t > 0.01) & (t < 0.55)]
    assert contacts.all()
    assert log.replans["mpc_ok"].mean() > 0.95
    assert np.nanmax(log.replans["stance_slide"]) < 0.01  # the soles stay where they landed


def test_h1_stepping_in_place_stays_in_place(in_place):
    com = in_place.ticks["com"]
    # every swing on its path (the preset's swing_path_weight, for the obstacle crossings) holds the swing foot back
    # against the step QP's timing: 8.8 cm of drift in these 2 s (4.9 cm without; docs/ocp.md "Every swing on its path")
    assert np.max(np.abs(com[-1, :2] - com[0, :2])) < 0.10
    pelvis_height = in_place.ticks["qpos"][:, 2]
    assert pelvis_height.min() > 0.85  # it stands at 1.00 m; the fall threshold is 0.60 m


def test_a_walk_at_speed_gets_its_own_fddp_iterations():
    """``fast_max_iterations``: an update whose planned |v_x| is at least ``fast_speed`` runs up to that many FDDP
    iterations (the crossing's budget first); slower ones the preset's."""
    from wbmpc.errors import ParameterError
    from wbmpc.walking.controller import WalkingController
    from wbmpc.walking.controller_config import WalkingControllerConfig
    from wbmpc.walking.preset import load_walking_preset

    preset = load_walking_preset("h1", {"fast_max_iterations": 4, "fast_speed": 0.8, "crossing_max_iterations": 30})
    budget = WalkingController(preset)._iteration_budget
    walking = {"crossing_nodes": 0.0, "negotiation_mode": 0.0}
    assert budget({**walking, "sequencer_v_x": 0.5}) is None
    assert budget({**walking, "sequencer_v_x": 0.8}) == budget({**walking, "sequencer_v_x": -1.0}) == 4
    assert budget({**walking, "crossing_nodes": 5.0, "sequencer_v_x": 1.0}) == 30
    for bad, message in (({"fast_max_iterations": 4}, r"fast_speed=0.0 m/s must be > 0 with fast_max_iterations=4"),
                         ({"fast_speed": 0.8}, r"fast_speed=0.8 m/s must be > 0 with fast_max_iterations=0 or "
                                               r"fast_swing_path_weight=0.0 set \(0 without\)"),
                         ({"fast_swing_path_weight": -1.0}, r"fast_swing_path_weight=-1.0 must be finite and >= 0"),
                         ({"fast_max_iterations": 2.5, "fast_speed": 0.8}, r"fast_max_iterations=2.5 must be 0"),
                         ({"fast_swing_path_speed": 0.4}, r"fast_swing_path_speed=0.4 m/s must be >= 0 \(0: fast_speed\) "
                                                          r"with fast_swing_path_weight=0.0 set, 0 without"),
                         ({"fast_swing_path_weight": 1e3, "fast_swing_path_speed": -0.1},
                          r"fast_swing_path_speed=-0.1 m/s must be >= 0"),
                         ({"fast_swing_path_weight": 1e3, "fast_swing_path_speed": float("nan")},
                          r"fast_swing_path_speed=nan m/s must be >= 0"),
                         ({"fast_max_iterations": 4, "fast_swing_path_weight": 1e3, "fast_swing_path_speed": 0.4},
                          r"fast_speed=0.0 m/s must be > 0 with fast_max_iterations=4")):
        with pytest.raises(ParameterError, match=message):
            WalkingControllerConfig(**bad)


def test_a_walk_at_speed_tracks_the_swing_path_of_fast_swing_path_weight():
    """``fast_swing_path_weight``: from a planned |v_x| of ``fast_speed`` on, the OCP's ``{foot}_swing_path`` terms (the
    H1 has them for its crossings, off while walking) track every swing's path with that weight."""
    from wbmpc.walking.controller import WalkingController
    from wbmpc.walking.preset import load_walking_preset

    def active_weights(options):
        controller = WalkingController(load_walking_preset("h1", {"negotiation_lookahead": 0.0, "ocp.swing_path_weight": 0.0,
                                                                  "perception.enabled": False, **options}))
        log = run_scenario("walk", robot="h1", duration=0.9, velocity_command=(0.3, 0.0, 0.0), ramp_time=0.0,
                           controller=controller, progress=False)
        assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
        return {item.weight for node in controller.mpc.ocp._swing_path_terms for item in node if item.active}

    assert active_weights({"fast_swing_path_weight": 1e3, "fast_speed": 0.2}) == {1e3}
    assert active_weights({"fast_swing_path_weight": 1e3, "fast_speed": 0.4}) == set()  # below fast_speed
    # fast_swing_path_speed: the swing path from its own speed, the iterations from fast_speed
    assert active_weights({"fast_swing_path_weight": 1e3, "fast_swing_path_speed": 0.2, "fast_max_iterations": 4,
                           "fast_speed": 0.8}) == {1e3}
    assert active_weights({"fast_swing_path_weight": 1e3, "fast_swing_path_speed": 0.4, "fast_max_iterations": 4,
                           "fast_speed": 0.2}) == set()


def test_negotiation_swing_path_weight_applies_while_negotiating_only():
    """``negotiation_swing_path_weight``: the OCP's swing path weight of a replan in negotiation mode (before the fast
    gait's), the OCP's own (None) while walking; refused when negative, not finite, or without swing path terms."""
    from wbmpc.errors import ParameterError
    from wbmpc.walking.controller import WalkingController
    from wbmpc.walking.controller_config import WalkingControllerConfig
    from wbmpc.walking.negotiation import NEGOTIATION, WALKING
    from wbmpc.walking.preset import load_walking_preset

    weight = WalkingController(load_walking_preset("h1", {"negotiation_swing_path_weight": 3e3}))._swing_path_weight
    assert weight({"negotiation_mode": float(NEGOTIATION), "sequencer_v_x": 0.3}) == 3e3
    assert weight({"negotiation_mode": float(WALKING), "sequencer_v_x": 0.3}) is None
    assert weight({"negotiation_mode": float(WALKING), "sequencer_v_x": 1.0}) == 3e3  # the preset's fast gait's
    assert WalkingController(load_walking_preset("h1"))._swing_path_weight(
        {"negotiation_mode": float(NEGOTIATION), "sequencer_v_x": 0.3}) is None  # off in the preset
    for value in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match=r"negotiation_swing_path_weight=.* must be finite and >= 0"):
            WalkingControllerConfig(negotiation_swing_path_weight=value)
    with pytest.raises(ParameterError, match=r"negotiation_swing_path_weight=1000.0 needs the OCP's swing path terms"):
        WalkingController(load_walking_preset("h1", {"negotiation_swing_path_weight": 1e3, "fast_swing_path_weight": 0.0,
                                                     "fast_swing_path_speed": 0.0, "ocp.swing_path_weight": 0.0,
                                                     "ocp.obstacle_swing_path_weight": 0.0}))


def test_fast_swing_path_speed_sets_the_swing_path_threshold_apart_from_fast_speed():
    """``fast_swing_path_speed``: the planned |v_x| from which ``fast_swing_path_weight`` applies (0: ``fast_speed``);
    the FDDP iterations keep ``fast_speed``; without ``fast_max_iterations`` ``fast_speed`` may stay 0."""
    from wbmpc.walking.controller import WalkingController
    from wbmpc.walking.controller_config import WalkingControllerConfig
    from wbmpc.walking.preset import load_walking_preset

    controller = WalkingController(load_walking_preset("h1", {"fast_max_iterations": 4, "fast_speed": 0.6,
                                                              "fast_swing_path_weight": 1e3,
                                                              "fast_swing_path_speed": 0.4}))
    walking = {"crossing_nodes": 0.0, "negotiation_mode": 0.0}
    for v_x, path, budget in ((0.3, None, None), (0.4, 1e3, None), (-0.5, 1e3, None), (0.6, 1e3, 4)):
        record = {**walking, "sequencer_v_x": v_x}
        assert controller._swing_path_weight(record) == path, v_x
        assert controller._iteration_budget(record) == budget, v_x
    WalkingControllerConfig(fast_swing_path_weight=1e3, fast_swing_path_speed=0.4)  # no fast_speed needed
