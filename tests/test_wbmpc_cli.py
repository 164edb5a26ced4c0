"""``wbmpc ocp``: one walking OCP from the sequencer's plan, JSON report and clear errors."""

from __future__ import annotations

import json

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
    assert "iterations=0" in capsys.readouterr().err
