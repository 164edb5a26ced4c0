"""``wbmpc plan --planner alip`` and ``wbmpc bench planner``."""

import json

import pytest

from wbmpc.cli import main


def test_plan_alip_json_and_plot(tmp_path, capsys):
    pytest.importorskip("pinocchio")
    figure = tmp_path / "alip.png"
    assert main(["plan", "--planner", "alip", "--robot", "g1", "--vx", "0.2", "--yaw-rate", "0.1", "--json",
                 "--plot", str(figure)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["planner"] == "alip" and len(result["solution"]["periods"]) == 4
    assert len(result["solution"]["torques"]) == 4 and len(result["plan"]["steps"]) >= 4
    assert figure.stat().st_size > 10_000


def test_plan_alip_rejects_dcm_options(capsys):
    assert main(["plan", "--planner", "alip", "--alpha1", "3"]) != 0
    assert "--alpha1" in capsys.readouterr().err


def test_bench_planner(capsys):
    assert main(["bench", "planner", "--planner", "alip", "--repeats", "10", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["instances"] == 10 and result["max_abs_difference"] < 1e-6
    assert result["ipopt"]["median_ms"] > 0 and result["sqp_warm"]["p99_ms"] > 0
