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
