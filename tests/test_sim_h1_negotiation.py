"""The H1 in closed loop towards a 10 cm box it is told about (``Measurement.obstacles`` filled with the true
box, tests/negotiation_scene.py): it switches to negotiation at once, walks up to the box with every sole
outside it and places its last step before the box, short (3.6 s). Stepping over it is measured in docs/ocp.md
("Obstacle clearance": the lead foot crosses, the trailing foot does not yet)."""

from __future__ import annotations

import numpy as np
import pytest
from negotiation_scene import BoxContacts, KnownObstacleController, StepOverBox
from robot_extras import needs_h1_extra

from sim.runner import run_scenario
from wbmpc.walking.negotiation import NEGOTIATION
from wbmpc.walking.ocp import SlowPathWarning
from wbmpc.walking.preset import load_walking_preset

pytestmark = [needs_h1_extra, pytest.mark.filterwarnings(f"ignore::{SlowPathWarning.__module__}.SlowPathWarning")]


@pytest.fixture(scope="module")
def approach():
    box = StepOverBox(height=0.1, depth=0.1, distance=1.0, speed=0.3)
    preset = load_walking_preset("h1", scenario="obstacle")
    controller = KnownObstacleController(preset, (box.obstacle(),))
    contacts = BoxContacts(box)
    log = run_scenario("step_over_box", robot="h1", duration=3.6, controller=controller, on_tick=contacts,
                       progress=False, height=box.height, depth=box.depth, distance=box.distance, speed=box.speed)
    return box, preset, controller, contacts, log


def test_h1_negotiates_a_perceived_box_from_the_first_replan(approach):
    box, preset, controller, contacts, log = approach
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    assert controller.negotiation_switches == [(0.0, NEGOTIATION)]  # 1 m ahead: within the 1.5 m lookahead
    replans = log.replans
    assert np.all(replans["negotiation_mode"] == NEGOTIATION) and replans["negotiation_switch"][0] == 1.0
    assert np.all(replans["obstacles_planned"] == 1.0)
    # the planned box as the planner saw it, along the stance heading (here the true box, crossed along world x)
    truth = box.obstacle()
    np.testing.assert_allclose(replans["obstacle_near"], truth.center[0] - truth.depth / 2, atol=0.02)
    np.testing.assert_allclose(replans["obstacle_far"], truth.center[0] + truth.depth / 2, atol=0.02)
    np.testing.assert_allclose(replans["obstacle_height"], box.height)
    assert np.all(replans["sequencer_v_x"] <= preset.controller.negotiation_speed_max + 1e-12)
    assert replans["crossing_nodes"].max() > 0  # the OCP's horizon held crossing swings


def test_h1_walks_up_to_the_box_with_every_foothold_before_it_and_without_touching_it(approach):
    box, preset, controller, contacts, log = approach
    assert contacts.touches == []
    replans = log.replans
    landed = replans["stance_switched"] > 0
    stance_x = replans["stance_x"][landed]
    assert stance_x.size >= 6 and stance_x.max() > 0.6  # it walked towards the box
    # every foothold so far before the box: the whole sole (its toe) before the near edge by half the margin at
    # least (the closed loop lands short steps up to 6 cm beyond the plan)
    planner = preset.planner
    assert np.all(stance_x + planner.sole_front < box.distance - 0.5 * planner.obstacle_margin)


@pytest.mark.parametrize("distance, negotiating", [(1.0, True), (4.0, False)])
def test_h1_gives_the_negotiation_its_own_fddp_iterations(distance, negotiating):
    """``negotiation_max_iterations``: while negotiating (the box within the 1.5 m lookahead) every warm-started
    update runs up to that many FDDP iterations, and the preset's ``max_iterations`` otherwise."""
    box = StepOverBox(height=0.1, depth=0.1, distance=distance, speed=0.3)
    preset = load_walking_preset("h1", {"negotiation_max_iterations": 4}, scenario="obstacle")
    assert preset.controller.max_iterations == 2
    controller = KnownObstacleController(preset, (box.obstacle(),))
    log = run_scenario("step_over_box", robot="h1", duration=0.1, controller=controller, progress=False,
                       height=box.height, depth=box.depth, distance=box.distance, speed=box.speed)
    assert log.status == "completed", log.error
    replans = log.replans
    assert np.all(replans["negotiation_mode"] == (NEGOTIATION if negotiating else 0))
    warm = replans["mpc_iterations"][1:]  # the first update is the cold start
    assert warm.size >= 4 and warm.max() == (4 if negotiating else 2), warm


def test_the_updates_that_see_a_crossing_get_their_own_fddp_iterations():
    """``crossing_max_iterations``: an update whose horizon holds a crossing swing runs up to that many FDDP iterations
    (before ``negotiation_max_iterations``); the others the negotiation's while negotiating, else the preset's."""
    from wbmpc.walking.controller import WalkingController

    for crossing, negotiation in ((5, 3), (5, 0), (0, 3), (0, 0)):
        preset = load_walking_preset("h1", {"crossing_max_iterations": crossing,
                                            "negotiation_max_iterations": negotiation})
        budget = WalkingController(preset)._iteration_budget
        assert budget({"crossing_nodes": 12.0, "negotiation_mode": NEGOTIATION}) == (crossing or negotiation or None)
        assert budget({"crossing_nodes": 0.0, "negotiation_mode": NEGOTIATION}) == (negotiation or None)
        assert budget({"crossing_nodes": 0.0, "negotiation_mode": 0.0}) is None
    # crossing_iterations_hold: the crossing's budget kept that long after the last update that saw a crossing
    preset = load_walking_preset("h1", {"crossing_max_iterations": 5, "crossing_iterations_hold": 0.1})
    budget = WalkingController(preset)._iteration_budget
    walking = {"crossing_nodes": 0.0, "negotiation_mode": 0.0}
    assert budget(walking, 1.0) is None  # no crossing seen yet
    assert budget({"crossing_nodes": 3.0, "negotiation_mode": 0.0}, 1.0) == 5
    assert budget(walking, 1.1) == 5 and budget(walking, 1.12) is None


def test_crossing_iterations_hold_is_a_duration():
    from wbmpc.errors import ParameterError
    from wbmpc.walking.controller_config import WalkingControllerConfig

    for bad in (-0.1, float("nan"), True, 11.0):
        with pytest.raises(ParameterError, match=f"crossing_iterations_hold={bad!r} s must be in"):
            WalkingControllerConfig(crossing_iterations_hold=bad)


@pytest.mark.parametrize("name", ["negotiation_max_iterations", "crossing_max_iterations"])
def test_the_iteration_budgets_are_zero_or_a_positive_integer(name):
    from wbmpc.errors import ParameterError
    from wbmpc.walking.controller_config import WalkingControllerConfig

    assert getattr(WalkingControllerConfig(**{name: 0}), name) == 0
    for bad in (-1, 2.5, True):
        with pytest.raises(ParameterError, match=f"{name}={bad!r} must be 0"):
            WalkingControllerConfig(**{name: bad})
