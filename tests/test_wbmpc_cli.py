"""``wbmpc ocp``: one walking OCP from the sequencer's plan, JSON report and clear errors."""

from __future__ import annotations

import json

from robot_extras import needs_h1_extra

from wbmpc.cli import main


def test_ocp_command_reports_a_walking_plan(capsys, tmp_path):
    plot = tmp_path / "ocp.png"
    assert main(["ocp", "--nodes", "40", "--iterations", "15", "--json", "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["iterations"] == len(report["log"]) <= 15
    assert report["log"][-1]["cost"] < report["log"][0]["cost"]
    assert set(report["term_costs"]) >= {"state_regularization", "control_regularization", "control_bounds",
                                         "terminal_com_position"}
    assert max(report["swing_apex_height_m"].values()) > 0.02  # a swing foot lifts (H = 0.05 m)
    assert plot.stat().st_size > 0


def test_ocp_command_rejects_bad_iterations(capsys):
    assert main(["ocp", "--nodes", "10", "--iterations", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "argument --iterations: invalid value '0': must be an integer >= 1" in err


def test_bench_loop_reports_the_real_time_factor_against_the_crocoddyl_loop(capsys):
    import pytest

    pytest.importorskip("crocoddyl", reason="the Crocoddyl loop is the baseline (bench extra)")
    assert main(["bench", "loop", "--duration", "0.3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["status"] == "completed" and report["real_time_factor"] > 0
    assert abs(sum(report["shares"].values()) - 1.0) < 1e-9
    base = report["baseline"]
    assert [run["status"] for run in base["runs"]] == ["completed", "completed"]
    assert base["max_torque_difference_Nm"] < 1e-6  # the same closed loop
    assert base["ratio"] == base["ours_real_time_factor_both_runs"] / base["real_time_factor"]
    assert base["mirror_copy_time_excluded"] > 0
    floor = report["pinocchio_floor"]  # Pinocchio's calls alone, timed at the MPC's last solution
    assert floor["dynamics_per_node"] > 0 and floor["derivatives_per_node"] > 0
    assert floor["rollouts_per_update"] >= 1.0  # at least the rollout of the accepted step
    n_nodes = 100
    assert floor["per_update"] == pytest.approx(n_nodes * (floor["dynamics_per_node"] * (1 + floor["rollouts_per_update"])
                                                           + floor["derivatives_per_node"]))
    # (that the MPC takes longer than Pinocchio's calls alone, and the floor's factor is above the loop's, is a
    # comparison of two timings taken at different moments: the benchmark prints it, a test on a shared machine
    # cannot assert it)
    assert floor["mpc_per_update"] > 0 and floor["best_real_time_factor"] > 0
    assert report["setup_time"] > 0  # models and the cold first solve, outside the factor



def test_bench_loop_takes_walking_preset_overrides(capsys):
    """``wbmpc bench loop --set NAME=VALUE``: a walking-preset override for every run, named in the report; a
    bad one is refused in one line before any run."""
    assert main(["bench", "loop", "--baseline", "none", "--set", "ocp.rollout_dynamics=fast"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "rollout_dynamics='fast' must be 'pinocchio' or 'compiled'" in err
    assert main(["bench", "loop", "--duration", "0.1", "--baseline", "none", "--set", "ocp.max_line_search_trials=5",
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["status"] == "completed" and report["preset_overrides"] == {"ocp.max_line_search_trials": 5}


@needs_h1_extra
def test_bench_loop_runs_the_h1_on_its_scenarios_preset_and_takes_the_dynamics_paths_from_set():
    """The walk runs the H1 preset's compiled paths; ``--set ocp.rollout_dynamics=pinocchio`` reaches the MPC
    problem (the two compared in alternated runs, docs/benchmarks.md "H1 loop, session 33"); ``--scenario obstacle``
    runs the preset's ``[scenarios.obstacle]`` table (Pinocchio's paths, the "rollout" fill), as ``wbmpc run`` does."""
    import argparse

    from bench.loop import _run_loop

    def run(scenario, overrides=()):
        args = argparse.Namespace(robot="h1", scenario=scenario, duration=0.05, seed=0, max_iterations=None,
                                  overrides=list(overrides))
        log, controller = _run_loop(args)
        assert log.status == "completed", log.error
        return controller

    walk = run("walk")
    assert walk.mpc.problem.rollout_dynamics == "compiled" and walk.preset.controller.mpc_horizon_end == "phase"
    assert run("walk", [("ocp.rollout_dynamics", "pinocchio")]).mpc.problem.rollout_dynamics == "pinocchio"
    obstacle = run("obstacle")
    assert (obstacle.mpc.problem.rollout_dynamics, obstacle.mpc.problem.derivative_dynamics) == ("pinocchio",) * 2
    assert obstacle.preset.controller.mpc_horizon_end == "rollout"


@needs_h1_extra
def test_bench_loop_takes_the_h1_derivative_path_from_set(capsys):
    """``--set ocp.derivative_dynamics=pinocchio`` reaches the H1's MPC problem (the preset's walk compiles it,
    docs/benchmarks.md "H1 loop, session 25"), the rollouts staying compiled; a bad value is refused in one line
    before any run."""
    import argparse

    from bench.loop import _run_loop

    assert main(["bench", "loop", "--baseline", "none", "--set", "ocp.derivative_dynamics=rnea"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "derivative_dynamics='rnea' must be 'pinocchio' or 'compiled'" in err
    args = argparse.Namespace(robot="h1", scenario="walk", duration=0.05, seed=0, max_iterations=None,
                              overrides=[("ocp.derivative_dynamics", "pinocchio"), ("ocp.rollout_dynamics", "compiled")])
    log, controller = _run_loop(args)
    problem = controller.mpc.problem
    assert log.status == "completed" and (problem.derivative_dynamics, problem.rollout_dynamics) == ("pinocchio",
                                                                                                    "compiled")
