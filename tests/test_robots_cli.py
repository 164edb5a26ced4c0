"""``wbmpc robot NAME``: table, JSON and the error for an unknown robot."""

import json

from wbmpc.cli import main


def test_robot_json_and_table(capsys):
    assert main(["robot", "bolt", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["nu"] == 6 and summary["torque_limit_Nm"] == [2.7] * 6
    assert abs(summary["com_height_reference_m"] - 0.2953) < 1e-3
    assert main(["robot", "bolt"]) == 0
    assert "FL_HAA" in capsys.readouterr().out


def test_unknown_robot_is_a_one_line_error(capsys):
    assert main(["robot", "atlas"]) == 2
    assert "available robots: bolt, g1" in capsys.readouterr().err
