"""Command line: wbmpc plan / sensitivity (JSON output, plots, error messages)."""

import json

import numpy as np
import pytest

from wbmpc.cli import main


def run_json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_plan_json_and_plot(capsys, tmp_path):
    plot = tmp_path / "plan.png"
    result = run_json(capsys, ["plan", "--vx", "0.33", "--horizon", "3", "--json", "--plot", str(plot)])
    assert plot.stat().st_size > 10_000
    steps = result["plan"]["steps"]
    assert steps[0]["foot"] == "right" and steps[-1]["touchdown_time"] >= 0.229 + 3.0
    assert result["params"]["v_x"] == 0.33
    assert result["mean_velocity"][0] == pytest.approx(0.33, abs=2e-3)


def test_every_field_is_overridable_and_params_file(capsys, tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("alpha2 = 5.0\n")
    result = run_json(capsys, ["plan", "--params", str(path), "--z-c", "0.28", "--w-left-min", "-0.35",
                               "--t-max", "0.8", "--backend", "proxqp", "--json"])
    assert result["params"]["alpha2"] == 5.0 and result["params"]["z_c"] == 0.28
    assert result["params"]["w_left_min"] == -0.35 and result["params"]["t_max"] == 0.8
    assert result["backend"] == "proxqp"


def test_plan_text_output(capsys):
    assert main(["plan", "--preset", "bolt_walking"]) == 0
    out = capsys.readouterr().out
    assert "mean foothold velocity" in out and "touchdown [s]" in out


def test_bad_parameter_is_one_line_error_with_exit_code_2(capsys):
    assert main(["plan", "--l-min", "0.5"]) == 2
    err = capsys.readouterr().err
    assert "wbmpc plan: error: l_min=0.5 m must be <= l_max=0.3 m" in err
    assert main(["sensitivity", "--z-c", "-1"]) == 2
    assert "z_c=-1.0 must be > 0" in capsys.readouterr().err


def test_sensitivity_json_and_fig2(capsys, tmp_path):
    plot = tmp_path / "fig2.png"
    result = run_json(capsys, ["sensitivity", "--samples", "200", "--json", "--plot", str(plot)])
    assert plot.stat().st_size > 10_000
    J = np.array(result["dx_dtheta"])
    assert J.shape == (5, 2)
    assert result["active_set"] == []
    assert result["max_disagreement"] < 1e-5
    assert set(result["jacobians"]) == {"analytic", "casadi", "finite_differences", "proxqp_backward"}
    assert result["monte_carlo"]["samples"] == 200
    # overriding the Table I inputs changes the answer
    other = run_json(capsys, ["sensitivity", "--samples", "10", "--json", "--dcm", "-0.10", "-0.05", "--t", "0.1",
                              "--stance-position", "-0.12", "0.11", "--alpha3", "1e5", "--l-max", "0.25"])
    assert not np.allclose(np.array(other["dx_dtheta"]), J)
