"""``wbmpc robot NAME``: table, JSON and the error for an unknown robot."""

import json

from robot_extras import needs_h1_extra

from wbmpc.cli import main


def test_robot_json_and_table(capsys):
    assert main(["robot", "bolt", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["nu"] == 6 and summary["torque_limit_Nm"] == [2.7] * 6
    assert abs(summary["com_height_reference_m"] - 0.2953) < 1e-3
    assert main(["robot", "bolt"]) == 0
    assert "FL_HAA" in capsys.readouterr().out


@needs_h1_extra
def test_robot_h1_is_listed_and_described(capsys):
    assert main(["robot", "h1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["nu"] == 19 and summary["model_format"] == "mjcf" and summary["contact_type"] == "flat6d"
    assert abs(summary["mass_kg"] - 51.437) < 1e-6
    assert main(["robot", "h1"]) == 0
    assert "left_knee" in capsys.readouterr().out


def test_unknown_robot_is_a_one_line_error(capsys):
    assert main(["robot", "atlas"]) == 2
    assert "available robots: bolt, g1, h1" in capsys.readouterr().err
