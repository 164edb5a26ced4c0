"""Closed-loop runner machinery, exercised with the posture-holding PD controller (no planning).

Bolt has point feet: holding a posture with a joint PD it falls within about a second, which
exercises fall detection, partial logs and metrics on a real simulation.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from sim import load_run, run_scenario
from sim.falls import FallCriteria, base_tilt
from wbmpc.errors import ParameterError
from wbmpc.walking import JointPDController


@pytest.fixture(scope="module")
def pd_fall(tmp_path_factory):
    out = tmp_path_factory.mktemp("pd_fall")
    log = run_scenario("walk", controller="pd", duration=3.0, seed=0, out=str(out), progress=False)
    return log, out


def test_pd_controller_falls_and_the_fall_is_detected(pd_fall):
    log, _ = pd_fall
    assert log.status == "fell"
    assert log.fall_reason
    assert 0.2 < log.fall_time < 1.5
    # the run stopped at the fall: the log ends there
    assert log.ticks["t"][-1] == pytest.approx(log.fall_time)
    assert log.metrics["fell"] is True
    # at start both feet stand on the floor, the base at the reference height
    assert log.ticks["foot_contact"][0].all()
    assert log.ticks["feet"][0, :, 2] == pytest.approx(0.016, abs=2e-3)


def test_fall_without_stopping_is_recorded_once(tmp_path):
    log = run_scenario("walk", controller="pd", duration=1.5, seed=0, stop_on_fall=False, progress=False)
    assert log.status == "fell"
    assert log.ticks["t"][-1] == pytest.approx(1.5 - 0.001)
    assert log.fall_time < 1.5


def test_logged_com_velocity_matches_the_derivative_of_the_logged_com(pd_fall):
    """Checks the MuJoCo -> Pinocchio state conversion (base velocity frame) inside the loop."""
    log, _ = pd_fall
    t, com, com_velocity = log.ticks["t"], log.ticks["com"], log.ticks["com_velocity"]
    # MuJoCo's semi-implicit Euler: q[i+1] = q[i] + dt v[i+1]; skip the last 20 ms (impact on the floor)
    derivative = (com[1:] - com[:-1]) / (t[1:, None] - t[:-1, None])
    before_impact = slice(0, len(t) - 21)
    assert np.max(np.abs(com_velocity[1:][before_impact] - derivative[before_impact])) < 2e-3
    assert np.max(np.abs(com_velocity)) > 0.3  # the robot really moved (falling)
    # the Pinocchio state holds the same base position as MuJoCo and a unit quaternion
    assert np.allclose(log.ticks["x"][:, :3], log.ticks["qpos"][:, :3])
    assert np.allclose(np.linalg.norm(log.ticks["x"][:, 3:7], axis=1), 1.0)


def test_logs_are_written_and_read_back(pd_fall):
    log, out = pd_fall
    with open(os.path.join(out, "metrics.json")) as stream:
        summary = json.load(stream)
    assert summary["status"] == "fell"
    assert summary["metrics"]["fall_time"] == pytest.approx(log.fall_time)
    again = load_run(out)
    for key, value in log.ticks.items():
        np.testing.assert_array_equal(again.ticks[key], value)
    assert again.fall_reason == log.fall_reason


def test_same_seed_gives_the_same_log_and_another_seed_does_not():
    kwargs = dict(controller="pd", duration=0.4, noise_q=1e-3, noise_v=1e-2, progress=False)
    a = run_scenario("walk", seed=7, **kwargs)
    b = run_scenario("walk", seed=7, **kwargs)
    c = run_scenario("walk", seed=8, **kwargs)
    for key in a.ticks:
        np.testing.assert_array_equal(a.ticks[key], b.ticks[key], err_msg=key)
    assert not np.array_equal(a.ticks["tau"], c.ticks["tau"])


class _FailingController(JointPDController):
    """Raises mid-run, to check that the log is still written."""

    def compute(self, t, measurement):
        if t >= 0.05:
            raise RuntimeError("controller exploded")
        return super().compute(t, measurement)


def test_log_is_written_when_the_run_ends_with_an_exception(tmp_path):
    with pytest.raises(RuntimeError, match="controller exploded"):
        run_scenario("walk", controller=_FailingController(), duration=1.0, out=str(tmp_path), progress=False)
    log = load_run(tmp_path)
    assert log.status == "error"
    assert "controller exploded" in log.error
    assert log.ticks["t"][-1] == pytest.approx(0.05)


def test_push_applies_the_force_to_the_base():
    common = dict(controller="pd", duration=0.25, progress=False, push_time=0.05, push_duration=0.1)
    pushed = run_scenario("push", force=20.0, direction=90.0, **common)
    free = run_scenario("push", force=0.0, **common)
    i = np.searchsorted(pushed.ticks["t"], 0.15)
    dv = pushed.ticks["com_velocity"][i, 1] - free.ticks["com_velocity"][i, 1]
    # impulse 2 N·s on 1.25 kg, minus what the feet resist: clearly positive along +y
    assert dv > 0.3


def test_unknown_names_raise_clear_errors():
    with pytest.raises(ParameterError, match="scenario='jump' is unknown"):
        run_scenario("jump")
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) \['sped'\]"):
        run_scenario("walk", controller="pd", sped=0.3)
    with pytest.raises(ParameterError, match="controller='mpc' must be one of"):
        run_scenario("walk", controller="mpc")
    with pytest.raises(ParameterError, match="duration=-1.0 s"):
        run_scenario("walk", controller="pd", duration=-1.0)
    with pytest.raises(ParameterError, match="noise_q=-0.1"):
        run_scenario("walk", controller="pd", noise_q=-0.1)


def test_fall_criteria():
    q = np.zeros(13)
    q[2], q[6] = 0.3, 1.0
    assert base_tilt(q[3:7]) == pytest.approx(0.0)
    angle = np.deg2rad(60.0)
    q[3], q[6] = np.sin(angle / 2), np.cos(angle / 2)
    assert base_tilt(q[3:7]) == pytest.approx(angle)
    with pytest.raises(ParameterError, match="max_tilt"):
        FallCriteria(max_tilt=0.0)


class _InterruptedController(JointPDController):
    """Emulates Ctrl-C in the middle of a run."""

    def compute(self, t, measurement):
        if t >= 0.03:
            raise KeyboardInterrupt
        return super().compute(t, measurement)


def test_log_is_written_on_ctrl_c(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        run_scenario("walk", controller=_InterruptedController(), duration=1.0, out=str(tmp_path), progress=False)
    log = load_run(tmp_path)
    assert log.status == "interrupted"
    assert log.ticks["t"][-1] == pytest.approx(0.03)


def test_run_log_pickles_for_worker_processes(pd_fall):
    import pickle

    log, _ = pd_fall
    again = pickle.loads(pickle.dumps(log))
    np.testing.assert_array_equal(again.ticks["x"], log.ticks["x"])
    assert again.metrics == log.metrics


def test_cli_run_prints_metrics_as_json(capsys, tmp_path):
    from wbmpc.cli import main

    code = main(["run", "walk", "--controller", "pd", "--duration", "0.2", "--json", "--out", str(tmp_path)])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["status"] == "completed"
    assert summary["metrics"]["simulated_time"] == pytest.approx(0.2)
    assert {os.path.basename(p) for p in summary["files"]} == {"figures.png", "log.npz", "metrics.json"}
    code = main(["run", "walk", "--controller", "pd", "--set", "sped=0.3", "--duration", "0.1"])
    assert code == 2  # unknown parameter: one-line error, exit code 2
    assert "unknown parameter(s) ['sped']" in capsys.readouterr().err


def test_the_fall_detector_knows_each_robots_feet():
    """The G1's sole spheres are its feet (not a body contact, which would be a fall at t = 0)."""
    log = run_scenario("walk", robot="g1", controller="pd", duration=0.1, seed=0, progress=False, kp=200.0, kd=5.0)
    assert log.status == "completed", log.fall_reason
    assert log.ticks["foot_contact"][-1].tolist() == [True, True]
