"""Every numeric option of every subcommand is checked while parsing; user errors are one line, exit code 2."""

from __future__ import annotations

import argparse

import pytest

from wbmpc.cli import build_parser, main
from wbmpc.cli.arguments import COUNT, PHASE, POSITIVE, SEED, number, plain_numeric_options
from wbmpc.errors import ParameterError, SolverError


def test_every_numeric_option_of_every_subcommand_has_a_checked_type():
    assert plain_numeric_options(build_parser()) == []


def test_number_types_refuse_what_they_do_not_allow():
    assert COUNT("3") == 3 and POSITIVE("0.5") == 0.5 and PHASE("0") == 0.0 and SEED("0") == 0
    with pytest.raises(argparse.ArgumentTypeError, match=r"invalid value '-1': must be an integer >= 1"):
        COUNT("-1")
    with pytest.raises(argparse.ArgumentTypeError, match=r"invalid value '1.5': must be an integer >= 1"):
        COUNT("1.5")
    with pytest.raises(argparse.ArgumentTypeError, match=r"invalid value 'nan': must be a finite number > 0"):
        POSITIVE("nan")
    with pytest.raises(argparse.ArgumentTypeError, match=r"invalid value '1': must be a finite number in \[0, 1\)"):
        PHASE("1")
    with pytest.raises(argparse.ArgumentTypeError, match=r"invalid value 'fast': must be a finite number <= 2"):
        number(float, high=2.0)("fast")
    with pytest.raises(argparse.ArgumentTypeError, match=r"must be an integer in \[0, 4294967295\]"):
        SEED("-1")


@pytest.mark.parametrize("argv, option, value", [
    (["walk", "--duration", "1e400"], "--duration", "1e400"),
    (["walk", "--duration", "0"], "--duration", "0"),
    (["walk", "--seed", "-1"], "--seed", "-1"),
    (["walk", "--mpc-failure-at", "nan"], "--mpc-failure-at", "nan"),
    (["walk", "--vx", "inf"], "--vx/--speed", "inf"),
    (["run", "push", "--force", "nan"], "--force", "nan"),
    (["sensitivity", "--samples", "-1"], "--samples", "-1"),
    (["sensitivity", "--sigma", "nan"], "--sigma", "nan"),
    (["plan", "--alpha1", "nan"], "--alpha1", "nan"),
    (["plan", "--t", "-0.1"], "--t", "-0.1"),
    (["demo", "--duration", "-5"], "--duration", "-5"),
    (["ocp", "--dt", "0"], "--dt", "0"),
    (["bench", "sequencer", "--repeats", "0"], "--repeats", "0"),
    (["bench", "loop", "--duration", "nan"], "--duration", "nan"),
    (["bench", "ddp", "--nodes", "50", "-3"], "--nodes", "-3"),
    (["campaign", "push-map", "--workers", "0"], "--workers", "0"),
    (["campaign", "push-map", "--phases", "0", "1.2"], "--phases", "1.2"),
    (["campaign", "terrain", "--densities", "-1"], "--densities", "-1"),
])
def test_a_bad_number_is_one_line_naming_the_option_the_value_and_what_is_allowed(capsys, argv, option, value):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"argument {option}: invalid value '{value}': must be " in err


def test_out_pointing_at_an_existing_file_names_out(capsys, tmp_path):
    existing = tmp_path / "log.txt"
    existing.write_text("")
    for argv in (["walk", "--out", str(existing)], ["demo", "--out", str(existing)],
                 ["campaign", "push-map", "--out", str(existing)], ["plan", "--plot", str(tmp_path)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and ("argument --out:" in err or "argument --plot:" in err), err


def test_set_with_a_word_for_a_number_is_one_line(capsys):
    assert main(["walk", "--set", "speed=fast", "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err == "wbmpc walk: error: --set speed='fast': speed is a number (scenario 'walk'), got str 'fast'\n"
    assert main(["walk", "--set", "robot=g1"]) == 2
    assert "--set robot=...: robot is not a scenario/runner/controller parameter; use --robot" in capsys.readouterr().err


def test_set_reads_values_as_the_presets_write_them():
    from wbmpc.cli.arguments import parse_assignment

    # TOML values (the presets' syntax), as a user copies them from a preset file
    assert parse_assignment("perception.enabled=false") == ("perception.enabled", False)
    assert parse_assignment("command.v_x=[-0.2, 1.0]") == ("command.v_x", [-0.2, 1.0])
    assert parse_assignment("planner.alpha3=1e6") == ("planner.alpha3", 1e6)
    assert parse_assignment('footstep_planner.kind="alip"') == ("footstep_planner.kind", "alip")
    # Python literals and bare words as before
    assert parse_assignment("perception.enabled=True") == ("perception.enabled", True)
    assert parse_assignment("ramp_time=.5") == ("ramp_time", 0.5)
    assert parse_assignment("footstep_planner.alip_preset=h1") == ("footstep_planner.alip_preset", "h1")


def test_unknown_robot_is_one_line_on_every_subcommand_that_takes_one(capsys):
    for argv in (["walk", "--robot", "robby", "--duration", "0.05"], ["run", "push", "--robot", "robby"],
                 ["plan", "--robot", "robby"], ["ocp", "--robot", "robby"], ["demo", "--robot", "robby"],
                 ["campaign", "push-map", "--robot", "robby", "--backend", "inline"],
                 ["bench", "loop", "--robot", "robby", "--baseline", "none"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "robot='robby' is not known; available robots: bolt" in err, err


def test_demo_refuses_a_speed_outside_the_robots_command_range_before_running(capsys, tmp_path):
    assert main(["demo", "--robot", "g1", "--speed", "1.0", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err == "wbmpc demo: error: velocity command v_x=1.0 m/s for robot 'g1' must be in [-0.2, 0.5] m/s\n"


def test_library_errors_reach_the_user_as_one_line_with_exit_code_2(capsys, monkeypatch):
    import wbmpc.cli.robots as robots_cli

    for error in (SolverError("FDDP diverged at iteration 3"), ParameterError("alpha=-1 must be > 0"),
                  ValueError("bad\nvalue")):
        def boom(args, error=error):
            raise error

        monkeypatch.setattr(robots_cli, "run", boom)
        assert main(["robot", "bolt"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("wbmpc robot: error: ")


def test_plan_for_a_robot_starts_from_its_standing_pose(capsys):
    import json

    from robots import load_robot

    assert main(["plan", "--robot", "bolt", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    bolt = load_robot("bolt")
    assert result["params"]["name"] == "bolt"  # the planner of its walking preset
    assert result["plan"]["stance_position"] == pytest.approx(bolt.foot_positions_reference()["left"][:2])
    assert result["plan"]["dcm_measured"] == pytest.approx(bolt.com_position_reference[:2])
    assert main(["plan", "--robot", "g1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["params"]["name"] == "g1"


def test_walk_passes_robot_and_a_velocity_command_only_when_asked(monkeypatch):
    import sim.runner

    calls = []

    def fake_run_scenario(name, **kwargs):
        calls.append((name, kwargs))
        raise ParameterError("stop here")

    monkeypatch.setattr(sim.runner, "run_scenario", fake_run_scenario)
    assert main(["walk", "--robot", "g1"]) == 2
    assert calls[-1][0] == "walk" and calls[-1][1]["robot"] == "g1" and "velocity_command" not in calls[-1][1]
    assert main(["walk", "--vx", "0.3", "--yaw-rate", "0.2"]) == 2
    assert calls[-1][1]["velocity_command"] == (0.3, 0.0, 0.2)
    assert main(["run", "push", "--speed", "0.25"]) == 2  # --speed is --vx
    assert calls[-1][0] == "push" and calls[-1][1]["velocity_command"] == (0.25, 0.0, 0.0)
    assert main(["walk", "--vy", "0.1"]) == 2  # v_x left out: the scenario's speed
    assert calls[-1][1]["velocity_command"] == (0.33, 0.1, 0.0)


def test_planner_option_selects_the_walking_presets_footstep_planner(monkeypatch, capsys):
    import sim.campaigns.run
    import sim.runner

    calls = []

    def fake_run_scenario(name, **kwargs):
        calls.append(kwargs)
        raise ParameterError("stop here")

    monkeypatch.setattr(sim.runner, "run_scenario", fake_run_scenario)
    assert main(["walk", "--robot", "g1"]) == 2
    assert not any(key.startswith("footstep_planner") for key in calls[-1])  # the preset's own choice
    assert main(["walk", "--robot", "g1", "--planner", "alip", "--alip-solver", "ipopt"]) == 2
    assert calls[-1]["footstep_planner.kind"] == "alip" and calls[-1]["footstep_planner.alip_solver"] == "ipopt"
    assert main(["run", "push", "--robot", "g1", "--planner", "dcm"]) == 2
    assert calls[-1]["footstep_planner.kind"] == "dcm"
    capsys.readouterr()
    assert main(["walk", "--planner", "alip", "--set", "footstep_planner.kind=dcm"]) == 2
    assert "--set footstep_planner.kind=... and its option" in capsys.readouterr().err
    assert main(["walk", "--planner", "lipm"]) == 2
    assert "argument --planner: invalid choice: 'lipm'" in capsys.readouterr().err

    specs = []

    def fake_run_campaign(spec, out, **kwargs):
        specs.append(spec)
        raise ParameterError("stop here")

    monkeypatch.setattr(sim.campaigns.run, "run_campaign", fake_run_campaign)
    assert main(["campaign", "push-map", "--robot", "g1", "--planner", "alip", "--steps-x", "1", "--steps-y", "1",
                 "--phases", "0", "--compare-timing", "fixed"]) == 2
    spec = specs[-1]
    assert spec.robot == "g1" and spec.params["footstep_planner.kind"] == "alip" and spec.params["base_body"] == "pelvis"
    assert spec.duration == pytest.approx(3.0 + 0.1 + 2.5)  # phase 0 only
