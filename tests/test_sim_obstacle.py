"""The ``obstacle`` scenario: its box, its checks, the contacts with the box, its metrics, the H1 walking
toward a box with its rangefinders on (faults injected), its command line and a tiny campaign through the
real machinery."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
from robot_extras import needs_h1_extra

from robots.conventions import pinocchio_to_mujoco_state
from sim.campaigns import ResultStore
from sim.falls import ContactSensor
from sim.log import RunLog
from sim.obstacle_metrics import obstacle_metrics
from sim.scenarios import make_scenario
from sim.scenarios.obstacle import BOX_GEOM_NAME
from wbmpc.cli import main
from wbmpc.errors import ParameterError
from wbmpc.walking.ocp import SlowPathWarning

# the H1 preset's "sole" contact damping is solved node-wise by the KKT backend (SlowPathWarning, said once per run)
slow_path_ok = pytest.mark.filterwarnings(f"ignore::{SlowPathWarning.__module__}.SlowPathWarning")


# ---------------------------------------------------------------------------------------- scenario


@pytest.mark.parametrize(("params", "message"), [
    ({"height": 0.9}, r"^height=0.9 m must be in \[0.02, 0.6\] m$"),
    ({"height": -0.1}, r"^height=-0.1 m must be in \[0.02, 0.6\] m$"),
    ({"distance_min": 3.0, "distance_max": 2.0}, r"^distance_max=2.0 m must be in \[3.0, 20.0\] m$"),
    ({"distance_min": 0.1}, r"^distance_min=0.1 m must be in \[0.5, 20.0\] m$"),
])
def test_bad_heights_and_distances_are_refused_in_one_line(params, message):
    with pytest.raises(ParameterError, match=message):
        make_scenario("obstacle", **params)


def test_cli_refuses_a_bad_height_with_one_line_and_exit_2(capsys):
    assert main(["run", "obstacle", "--robot", "h1", "--height", "0.9", "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "wbmpc run: error: height=0.9 m must be in [0.02, 0.6] m"
    assert main(["campaign", "obstacles", "--heights", "0.1", "0.9", "--trials", "1"]) == 2
    assert capsys.readouterr().err.strip() == "wbmpc campaign: error: height=0.9 m must be in [0.02, 0.6] m"
    assert main(["run", "obstacle", "--set", "distance_max=0.7", "--duration", "1"]) == 2
    assert "distance_max=0.7 m must be in [2.0, 20.0] m" in capsys.readouterr().err


@pytest.fixture(scope="module")
def h1():
    from robots import load_robot

    return load_robot("h1")


def obstacle_model(h1, seed=0, **params):
    """The obstacle scene's compiled model for the robot ``h1`` (the H1 unless another is given) and its scenario
    (box drawn from ``seed``)."""
    from robots.mujoco_model import build_mujoco_spec

    scenario = make_scenario("obstacle", **params)
    scenario.setup(h1, None)
    spec = build_mujoco_spec(h1, link_collisions=True)
    scenario.modify_spec(spec, np.random.default_rng(seed))
    return spec.compile(), scenario


@needs_h1_extra
def test_the_seed_draws_the_box_across_the_path(h1):
    model, scenario = obstacle_model(h1, seed=4, height=0.25)
    (box,) = scenario.true_obstacles()
    _, again = obstacle_model(h1, seed=4, height=0.25)
    np.testing.assert_array_equal(again.true_obstacles()[0].center, box.center)  # same seed, same box
    near, far = box.interval_along(h1.q_reference[:2], 0.0)
    assert 2.0 <= near <= 3.0 and 0.1 <= far - near <= 0.3 and box.height == 0.25 and box.width == 1.2
    geom = model.geom(BOX_GEOM_NAME)
    np.testing.assert_allclose(geom.size, 0.5 * np.array([box.depth, box.width, box.height]))
    assert 0.5 <= geom.friction[0] <= 1.0 and geom.priority[0] == 1


@needs_h1_extra
def test_contacts_with_the_box_are_obstacle_contacts_not_falls(h1):
    """A sole on the box is a foot contact and an obstacle contact; a shank against the box is an obstacle
    contact, not a ground contact (no fall); neither is silent (sim.falls)."""
    model, scenario = obstacle_model(h1, seed=0, height=0.1, depth_min=0.5, depth_max=0.5)
    (box,) = scenario.true_obstacles()
    data = mujoco.MjData(model)
    sensor = ContactSensor(model, h1)
    q = np.array(h1.q_reference)
    q[0] = box.center[0]  # the robot standing with its soles on the box top (sunk 1 mm into it)
    q[2] += box.height - 0.001
    data.qpos[:], _ = pinocchio_to_mujoco_state(h1, q, np.zeros(h1.nv))
    mujoco.mj_forward(model, data)
    feet, other, obstacle = sensor.classify_with_obstacles(data)
    assert feet.tolist() == [True, True] and other is None and obstacle.tolist() == [True, True, False]
    q = np.array(h1.q_reference)
    q[0] = box.center[0] - 0.5 * box.depth + 0.02  # the box's front face 2 cm behind the pelvis: into the shins
    data.qpos[:], _ = pinocchio_to_mujoco_state(h1, q, np.zeros(h1.nv))
    mujoco.mj_forward(model, data)
    feet, other, obstacle = sensor.classify_with_obstacles(data)
    assert obstacle[-1] and other is None  # the shank guard touches the box: not a fall


def test_the_shank_guard_spans_the_lower_leg_from_knee_to_ankle():
    """Each lower leg's capsule runs from the knee to the foot body: on the G1, whose foot hangs from a 1.8 cm
    ankle link, it is the knee link's and 0.318 m long (the shin), not 1.8 cm; on Bolt the lower leg's."""
    from robots import load_robot
    from sim.scenarios.obstacle import SHANK_GEOM_PREFIX

    for name, body, length in (("g1", "left_knee_link", 0.318), ("bolt", "FL_LOWER_LEG", 0.2)):
        robot = load_robot(name)
        model, _ = obstacle_model(robot, height=0.1)
        geom = model.geom(f"{SHANK_GEOM_PREFIX}left")
        assert model.body(model.geom_bodyid[geom.id]).name == body
        assert 2.0 * model.geom_size[geom.id][1] == pytest.approx(length, abs=2e-3), name


@needs_h1_extra
def test_the_h1_shank_guard_is_its_knee_link(h1):
    from sim.scenarios.obstacle import SHANK_GEOM_PREFIX

    model, _ = obstacle_model(h1, height=0.1)
    geom = model.geom(f"{SHANK_GEOM_PREFIX}right")
    assert model.body(model.geom_bodyid[geom.id]).name == "right_knee_link"
    assert 2.0 * model.geom_size[geom.id][1] == pytest.approx(0.4, abs=1e-9)


# ---------------------------------------------------------------------------------------- metrics


def synthetic_log(base_x, feet_x, contact, status="completed", detections=()):
    """A RunLog of a straight walk (base and feet x per tick) past a 0.2 m deep box, near edge at 1.0 m."""
    n = len(base_x)
    x = np.zeros((n, 51))
    x[:, 0], x[:, 6] = base_x, 1.0
    feet = np.zeros((n, 2, 3))
    feet[:, :, 0] = feet_x
    truth = {"center": [1.1, 0.0], "yaw": 0.0, "depth": 0.2, "width": 1.0, "height": 0.1}
    ticks = {"t": np.arange(n) * 0.1, "x": x, "feet": feet, "obstacle_contact": np.asarray(contact, dtype=bool)}
    params = {"obstacle_truth": [truth], "perception": {"n_scans": 10, "rate": 66.7, "detections": list(detections)}}
    return RunLog(scenario="obstacle", robot="h1", seed=0, params=params, status=status, ticks=ticks)


def test_success_needs_the_base_and_both_feet_beyond_the_far_edge_and_nothing_left_on_the_box():
    no_contact = np.zeros((4, 3), dtype=bool)
    crossed = synthetic_log([0.5, 1.0, 1.3, 1.5], [[0.5, 0.5], [1.0, 1.4], [1.25, 1.4], [1.4, 1.5]], no_contact)
    m = obstacle_metrics(crossed)
    assert m["success"] and m["crossed"] and not m["touched"] and m["crossing_time"] == pytest.approx(0.2)
    assert m["feet_across"] == 2
    back = synthetic_log([0.5, 1.0, 1.3, 1.1], [[0.5, 0.5], [1.0, 1.4], [1.25, 1.4], [1.1, 1.15]], no_contact, "fell")
    assert obstacle_metrics(back)["feet_across"] == 2  # both feet had crossed; it fell back over the box
    trailing = synthetic_log([0.5, 1.0, 1.3, 1.5], [[0.5, 0.5], [1.0, 1.4], [1.0, 1.4], [1.1, 1.5]], no_contact)
    assert not obstacle_metrics(trailing)["success"] and obstacle_metrics(trailing)["crossing_time"] is None
    assert obstacle_metrics(trailing)["feet_across"] == 1  # astride: the right foot beyond the far edge (1.2 m)
    resting = np.zeros((4, 3), dtype=bool)
    resting[2:, 0] = True  # the left foot stands on the box at the end
    m = obstacle_metrics(synthetic_log([0.5, 1.0, 1.3, 1.5], [[0.5, 0.5], [1.0, 1.4], [1.25, 1.4], [1.4, 1.5]], resting))
    assert m["touched"] and m["resting_on_obstacle"] and not m["success"] and m["first_touch_time"] == pytest.approx(0.2)
    brushed = np.zeros((4, 3), dtype=bool)
    brushed[1, 2] = True  # a shank touched the box once, then the robot crossed
    m = obstacle_metrics(synthetic_log([0.5, 1.0, 1.3, 1.5], [[0.5, 0.5], [1.0, 1.4], [1.25, 1.4], [1.4, 1.5]], brushed))
    assert m["touched"] and m["success"]
    fell = synthetic_log([0.5, 1.0, 1.3, 1.5], [[0.5, 0.5], [1.0, 1.4], [1.25, 1.4], [1.4, 1.5]], no_contact, "fell")
    assert not obstacle_metrics(fell)["success"]


def test_the_crossing_balance_is_the_dcm_against_the_lead_and_rear_soles_at_the_three_crossing_events():
    """Box from 1.0 to 1.2 m. Left foot (0) leads: down beyond the box at tick 2; the right foot (1) rises at tick 3
    and is down beyond the box at tick 5. Margins: DCM along x minus the lead sole (ticks 2, 3), minus the rear
    sole (tick 5)."""
    left = [0.8, 1.0, 1.45, 1.45, 1.45, 1.45]
    right = [0.9, 0.9, 0.9, 0.9, 1.1, 1.4]
    log = synthetic_log([0.8, 1.0, 1.2, 1.3, 1.35, 1.4], list(zip(left, right)), np.zeros((6, 3)))
    log.ticks["feet"][:, 1, 2] = [0.0, 0.0, 0.0, 0.3, 0.5, 0.0]
    log.ticks["foot_contact"] = np.array([[1, 1], [0, 1], [1, 1], [1, 0], [1, 0], [1, 1]], dtype=bool)
    log.ticks["dcm"] = np.column_stack([[0.9, 1.1, 1.43, 1.40, 1.42, 1.5], np.zeros(6)])
    m = obstacle_metrics(log)
    assert (m["lead_touchdown_time"], m["trailing_liftoff_time"], m["trailing_touchdown_time"]) == pytest.approx(
        (0.2, 0.3, 0.5))
    assert m["lead_touchdown_dcm_margin"] == pytest.approx(-0.02)
    assert m["trailing_liftoff_dcm_margin"] == pytest.approx(-0.05)
    assert m["trailing_touchdown_dcm_margin"] == pytest.approx(0.1)  # the rear sole is the trailing one, 1.4 m
    # still astride at the end: the trailing touchdown is None; no DCM in the log: all None
    log.ticks["foot_contact"][5, 1] = False
    assert obstacle_metrics(log)["trailing_touchdown_dcm_margin"] is None
    del log.ticks["dcm"]
    assert obstacle_metrics(log)["lead_touchdown_time"] is None


def test_detection_errors_are_estimate_minus_truth():
    estimate = {"center": [1.095, 0.02], "yaw": 0.0, "depth": 0.19, "width": 0.5, "height": 0.103, "first_seen": 0.1}
    log = synthetic_log([0.0, 0.1, 0.2], [[0.0, 0.0]] * 3, np.zeros((3, 3)), detections=[estimate])
    m = obstacle_metrics(log)
    assert m["detected"] and m["detection_time"] == 0.1 and m["detection_distance"] == pytest.approx(0.9)
    assert m["height_error"] == pytest.approx(0.003) and m["near_edge_error"] == pytest.approx(0.0)
    assert m["far_edge_error"] == pytest.approx(-0.01) and m["width_estimate"] == 0.5
    assert not obstacle_metrics(synthetic_log([0.0, 0.1], [[0.0, 0.0]] * 2, np.zeros((2, 3))))["detected"]


# ---------------------------------------------------------------------------------------- closed loop


def recorded_obstacles(monkeypatch):
    """What the walking controller's replans receive in Measurement.obstacles: [(t, obstacles), ...]."""
    from wbmpc.walking.controller import WalkingController

    seen = []
    replan = WalkingController.replan

    def spy(self, t, measurement):
        seen.append((t, measurement.obstacles))
        return replan(self, t, measurement)

    monkeypatch.setattr(WalkingController, "replan", spy)
    return seen


@needs_h1_extra
@slow_path_ok
def test_h1_walking_toward_a_box_reports_it_through_noise_dropouts_and_a_blackout(monkeypatch):
    """3 s of walking at 0.4 m/s toward a 10 cm box 1.5-1.6 m ahead, 5 mm range noise, 30 % of the rays
    lost at random and all of them for 0.6 s: the box is reported within 1 cm of its height (measured:
    docs/perception.md), the controller receives it, the run completes."""
    from sim.runner import run_scenario

    seen = recorded_obstacles(monkeypatch)
    log = run_scenario("obstacle", robot="h1", duration=3.0, seed=1, height=0.1, distance_min=1.5, distance_max=1.6,
                       progress=False, **{"perception.noise_std": 0.005, "perception.dropout_probability": 0.3,
                                          "perception.blackouts": [[1.0, 1.6]]})
    assert log.status == "completed", (log.fall_reason, log.error)
    m, perception = log.metrics, log.params["perception"]
    assert m["detected"] and m["detection_time"] < 0.1 and abs(m["height_error"]) < 0.01
    assert -0.05 < m["near_edge_error"] < 0.01  # noise pushes the near edge toward the robot
    assert not m["touched"] and not m["success"]  # 3 s: not there yet
    assert perception["n_scans"] == 200 and perception["n_empty_scans"] == 40  # 0.6 s of blackout at 66.7 Hz
    assert len(perception["detections"]) == 1 and log.params["obstacle_truth"][0]["height"] == 0.1
    assert seen[0][1] == () or len(seen[0][1]) == 1
    reported = [obstacles for t, obstacles in seen if t > 0.2]
    assert all(len(obstacles) == 1 for obstacles in reported)  # held through the blackout
    assert abs(reported[-1][0].height - 0.1) < 0.01
    assert m["real_time_factor"] is not None and log.timing["perception"] > 0


@needs_h1_extra
@slow_path_ok
def test_h1_with_a_box_its_rays_miss_walks_on_without_a_report(monkeypatch):
    from sim.runner import run_scenario

    seen = recorded_obstacles(monkeypatch)
    log = run_scenario("obstacle", robot="h1", duration=1.0, seed=1, height=0.1, perceivable=False, progress=False)
    assert log.status == "completed" and log.metrics["detected"] is False
    assert all(obstacles == () for _, obstacles in seen) and log.params["perception"]["n_scans"] == 67


def test_a_robot_without_perception_reports_nothing():
    from sim.runner import run_scenario

    log = run_scenario("obstacle", robot="bolt", controller="pd", duration=0.05, progress=False, stop_on_fall=False)
    assert "perception" not in log.params and "detected" not in log.metrics and log.metrics["touched"] is False


def test_an_obstacle_run_without_negotiation_says_so(capsys):
    """The G1 walks with the ALIP planner, which plans no obstacle; its obstacle runs negotiate with the DCM planner of
    its preset's [scenarios.obstacle]. An obstacle run or campaign whose settings negotiate nothing (the ALIP planner
    asked for, Bolt's preset) says so in one line; the H1's and the G1's presets negotiate."""
    from wbmpc.cli.walk import obstacle_negotiation_note

    assert obstacle_negotiation_note("g1", {}) is None and obstacle_negotiation_note("h1", {}) is None
    note = obstacle_negotiation_note("g1", {"footstep_planner.kind": "alip", "controller.negotiation_lookahead": 0.0})
    assert note is not None and "\n" not in note and "negotiation_lookahead = 0" in note and "ALIP" in note
    bolt = obstacle_negotiation_note("bolt", {})
    assert bolt is not None and "ALIP" not in bolt
    assert main(["run", "obstacle", "--robot", "bolt", "--controller", "pd", "--duration", "0.02"]) in (0, 1)
    assert "note:" not in capsys.readouterr().err  # the PD controller plans nothing: no note
    assert main(["run", "obstacle", "--robot", "bolt", "--duration", "0.02"]) in (0, 1)
    assert capsys.readouterr().err.strip().splitlines()[-1] == bolt


# ---------------------------------------------------------------------------------------- campaign


@needs_h1_extra
def test_the_obstacle_summary_counts_the_falls_by_the_feet_across_the_box(tmp_path):
    """Session 19's 10 cm campaign (docs/data/) with ``feet_across`` added as the runs ended (0 where the trial never
    crossed, 2 where it fell after crossing): the summary splits its 15 falls 8 / 0 / 7, the report says so; records
    without the metric are not counted."""
    from pathlib import Path

    from sim.campaigns.report import format_summary, write_report

    source = Path(__file__).resolve().parents[1] / "docs" / "data" / "h1-obstacles-s19-10cm"
    (tmp_path / "campaign.json").write_text((source / "campaign.json").read_text())
    records = [json.loads(line) for line in (source / "trials.jsonl").read_text().splitlines()]
    for record in records:
        record["metrics"]["feet_across"] = 0 if record["metrics"]["crossing_time"] is None else 2
    (tmp_path / "trials.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    entry = write_report(tmp_path, plots=False)["obstacle"]["default"][0]
    assert entry["n_fell"] == 15 and entry["falls_by_feet_across"] == [8, 0, 7]
    assert "fell 15/20 (before the box 8, astride 0, across 7)" in format_summary(write_report(tmp_path, plots=False))
    for record in records:
        del record["metrics"]["feet_across"]
    (tmp_path / "trials.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    entry = write_report(tmp_path, plots=False)["obstacle"]["default"][0]
    assert entry["falls_by_feet_across"] == [0, 0, 0] and "fell 15/20, detected" in format_summary(
        write_report(tmp_path, plots=False))


def test_a_tiny_obstacle_campaign_runs_through_the_real_machinery(tmp_path, capsys):
    """One 0.3 s trial per height (the PD controller: the run is short, the robot does not cross), the
    summary by height beside seed 000's table, and its figure."""
    out = tmp_path / "obstacles"
    code = main(["campaign", "obstacles", "--robot", "h1", "--controller", "pd", "--heights", "0.1", "0.4",
                 "--trials", "1", "--duration", "0.3", "--backend", "inline", "--no-progress", "--out", str(out),
                 "--set", "stop_on_fall=False"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    entries = summary["obstacle"]["default"]
    assert [e["height"] for e in entries] == [0.1, 0.4] and [e["paper_success_rate"] for e in entries] == [1.0, 0.05]
    assert all(e["n"] == 1 and e["success_rate"] == 0.0 and e["detected_rate"] == 1.0 for e in entries)
    assert (out / "obstacle_success.png").stat().st_size > 0
    assert "obstacle 10 cm, default: success 0.0 % (0/1) [0-79 %] (seed 000: 100.0 %)" in capsys.readouterr().out
    records = ResultStore(out).records()
    assert len(records) == 2 and all(r["success"] is False and r["metrics"]["crossed"] is False for r in records)


def test_the_run_table_shows_the_obstacle_outcome_and_the_perception():
    from wbmpc.cli.walk import format_metrics

    metrics = {"simulated_time": 12.0, "success": False, "crossed": False, "touched": True,
               "resting_on_obstacle": True, "crossing_time": None, "detected": True, "detection_time": 0.06,
               "detection_distance": 2.64, "height_error": 2e-4, "near_edge_error": -7e-4}
    text = format_metrics({"scenario": "obstacle", "seed": 0, "status": "fell", "fall_time": 9.1,
                           "fall_reason": "base tilt 45.0 deg > max_tilt=45.0 deg", "metrics": metrics})
    assert "obstacle success             False (crossed False, touched True, resting on it True)" in text
    assert "detection distance           2.64 m" in text and "height estimate error        0.2 mm" in text
    assert "crossing time                n/a" in text
    assert "preset [scenarios" not in text  # no table applied: no line
    table = {"ocp.rollout_dynamics": "pinocchio", "controller.mpc_horizon_end": "rollout"}
    text = format_metrics({"scenario": "obstacle", "seed": 0, "status": "completed", "metrics": metrics,
                           "params": {"preset_scenario_overrides": table}})
    assert ("  preset [scenarios.obstacle]  ocp.rollout_dynamics=pinocchio, controller.mpc_horizon_end=rollout"
            in text.splitlines())
