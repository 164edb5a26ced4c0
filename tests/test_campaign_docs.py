"""docs/campaigns.md: its python example runs as written and its campaign file is valid."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from sim.campaigns import CampaignSpec, make_trials

PAGE = Path(__file__).resolve().parents[1] / "docs" / "campaigns.md"


def blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", PAGE.read_text(), re.MULTILINE | re.DOTALL)


def test_python_example_runs(tmp_path, monkeypatch, capsys):
    (example,) = blocks("python")
    monkeypatch.chdir(tmp_path)
    exec(compile(example, "docs/campaigns.md", "exec"), {"__name__": "docs_campaigns"})
    n_run, _, counts = capsys.readouterr().out.split(" ", 2)
    assert int(n_run) == 8
    assert (tmp_path / "runs" / "tiny" / "force_map.png").exists()


def test_campaign_file_example_is_valid():
    (text,) = blocks("toml")
    spec = CampaignSpec.from_dict(tomllib.loads(text), source="docs/campaigns.md")
    assert len(make_trials(spec)) == 7 * 3 * 5 * 2


def g1_commands() -> list[list[str]]:
    """The ``wbmpc campaign push-map --robot g1`` commands of the page (continuation lines joined, comments cut)."""
    import shlex

    commands = []
    for block in blocks("bash"):
        text = block.replace("\\\n", " ")
        for line in text.splitlines():
            if line.startswith("wbmpc campaign push-map --robot g1"):
                commands.append(shlex.split(line.split("#", 1)[0])[1:])
    return commands


def test_the_g1_planner_commands_build_the_grids_the_page_reports():

    from wbmpc.cli import build_parser
    from wbmpc.cli.campaign import _spec_from_args

    small, full = g1_commands()
    spec = _spec_from_args(build_parser().parse_args(small))
    trials = make_trials(spec)
    assert len(trials) == 12 and spec.params["footstep_planner.kind"] == "alip" and spec.params["base_body"] == "pelvis"
    assert spec.duration == 5.0 and max(t.arguments["force"] for t in trials) < 200.0
    spec = _spec_from_args(build_parser().parse_args(full))
    assert spec.n_trials == 7 * 5 * 5 * 2
    assert max(t.arguments["force"] for t in make_trials(spec)) < 1000.0  # within the scenario's bound (page)
