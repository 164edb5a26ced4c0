"""Running campaigns: results store, resume, a real kill, and the local pool against in-process runs.

Trials use the posture-holding PD controller on short pushes: real closed-loop runs (Bolt falls
within about a second) that take a fraction of a second each.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from sim.campaigns import (
    CampaignDirectoryError,
    ResultStore,
    builtin_campaign,
    make_trials,
    run_campaign,
)
from wbmpc.cli import main


def small_push_map(**options):
    """8 PD trials of 0.6 s (2 x 2 forces, 2 phases), recorded whether they fall or not."""
    return builtin_campaign(
        "push-map", controller="pd", steps_x=2, steps_y=2, phases=(0.0, 0.5), push_after=0.2, duration=0.6,
        params={"stop_on_fall": False}, **options,
    )


def outcome(records):
    """What must not depend on the backend: key -> (success, status, fall time)."""
    return {r["key"]: (r["success"], r["status"], r["fall_time"]) for r in records}


@pytest.fixture(scope="module")
def inline_reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("inline")
    run = run_campaign(small_push_map(), out, backend="inline", progress=False)
    return run, ResultStore(out).records()


def test_inline_campaign_records_every_trial(inline_reference):
    run, records = inline_reference
    spec = small_push_map()
    assert (run.n_trials, run.n_run, run.n_skipped, run.n_remaining, run.n_error) == (8, 8, 0, 0, 0)
    assert {r["key"] for r in records} == {t.key for t in make_trials(spec)}
    for record in records:
        assert record["status"] in ("completed", "fell")
        assert record["success"] == (record["status"] == "completed")
        assert record["metrics"]["simulated_time"] == pytest.approx(0.6, abs=2e-3)  # stop_on_fall=False
        assert record["metrics"]["push_applied"] is True
        assert record["params"]["push_after"] == 0.2 and "force_x" in record["params"]
    # the PD controller cannot balance: most trials fall
    assert sum(r["status"] == "fell" for r in records) >= 4


def test_store_skips_a_line_cut_by_a_kill_and_appends_on_a_fresh_line(tmp_path):
    store = ResultStore(tmp_path)
    store.append({"key": "a", "value": 1})
    store.close()
    with open(store.results_path, "a") as stream:
        stream.write('{"key": "b", "val')  # killed in the middle of a write
    assert ResultStore(tmp_path).completed_keys() == {"a"}
    with ResultStore(tmp_path) as again:
        again.append({"key": "c", "value": 3})
        again.append({"key": "a", "value": 4})  # recorded twice: the last record wins
    reader = ResultStore(tmp_path)
    assert {r["key"]: r["value"] for r in reader.records()} == {"a": 4, "c": 3}
    assert reader.skipped_lines == 1


def test_resume_runs_only_the_missing_trials_and_refuses_mixing_campaigns(tmp_path, inline_reference):
    _, reference = inline_reference
    spec = small_push_map()
    first = run_campaign(spec, tmp_path, backend="inline", max_trials=3, progress=False)
    assert (first.n_run, first.n_remaining) == (3, 5)
    with pytest.raises(CampaignDirectoryError, match=r"already holds 3 trial record\(s\).*--resume"):
        run_campaign(spec, tmp_path, backend="inline", progress=False)
    other = small_push_map(seeds=(0, 1))
    with pytest.raises(CampaignDirectoryError, match=r"different settings \['seeds'\]"):
        run_campaign(other, tmp_path, backend="inline", resume=True, progress=False)
    second = run_campaign(spec, tmp_path, backend="inline", resume=True, progress=False)
    assert (second.n_skipped, second.n_run, second.n_remaining) == (3, 5, 0)
    assert outcome(ResultStore(tmp_path).records()) == outcome(reference)
    third = run_campaign(spec, tmp_path, backend="inline", resume=True, progress=False)
    assert (third.n_skipped, third.n_run) == (8, 0)


def test_killed_campaign_resumes_on_the_local_pool_and_loses_nothing(tmp_path, inline_reference):
    """SIGKILL the whole campaign (parent and workers) mid-run, then --resume with 2 local workers."""
    _, reference = inline_reference
    out = tmp_path / "killed"
    argv = [
        "campaign", "push-map", "--controller", "pd", "--steps-x", "2", "--steps-y", "2", "--phases", "0", "0.5",
        "--push-after", "0.2", "--duration", "0.6", "--set", "stop_on_fall=False", "--out", str(out),
        "--no-progress", "--no-plots",
    ]
    process = subprocess.Popen(
        [sys.executable, "-m", "wbmpc.cli", *argv, "--workers", "2"],
        start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    store = ResultStore(out)
    deadline = time.monotonic() + 60.0
    try:
        while len(store.completed_keys()) < 2:
            if process.poll() is not None:
                pytest.fail(f"campaign ended before the kill: {process.stderr.read().decode()[-2000:]}")
            if time.monotonic() > deadline:
                pytest.fail("no trial finished within 60 s")
            time.sleep(0.05)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)  # the campaign's own session: parent, forkserver, workers
        process.wait()
    before = {r["key"]: r for r in store.records()}
    assert 2 <= len(before) < 8
    with open(store.results_path, "a") as stream:
        stream.write('{"key": "half-writ')  # as if the kill had cut a line

    assert main([*argv, "--resume", "--workers", "2"]) == 0
    after = {r["key"]: r for r in store.records()}
    assert store.skipped_lines == 1
    assert set(after) == {t.key for t in make_trials(small_push_map())}
    for key, record in before.items():  # recorded trials were kept, not run again
        assert after[key]["finished_at"] == record["finished_at"] and after[key]["pid"] == record["pid"]
    # the pool's worker processes give the same outcomes as in-process runs
    assert outcome(after.values()) == outcome(reference)
    assert len({r["pid"] for r in after.values()} - {r["pid"] for r in before.values()}) >= 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] and summary["n_recorded"] == 8


def test_a_trial_that_raises_is_recorded_with_its_error_and_the_campaign_goes_on(tmp_path):
    from sim.campaigns import CampaignSpec, summarize

    spec = CampaignSpec(
        name="bodies", scenario="push", controller="pd", duration=0.3,
        params={"push_time": 0.1, "force": 1.0}, grid={"base_body": ["base_link", "no_such_body"]},
    )
    run = run_campaign(spec, tmp_path, backend="inline", progress=False)
    assert (run.n_run, run.n_error) == (2, 1)
    records = {r["params"]["base_body"]: r for r in ResultStore(tmp_path).records()}
    bad = records["no_such_body"]
    assert (bad["success"], bad["status"]) == (False, "error")
    assert bad["error"].startswith("ValueError: base_body='no_such_body' is not a body of the model")
    assert "initialize_episode" in bad["traceback"]
    assert records["base_link"]["status"] in ("completed", "fell") and records["base_link"]["error"] is None
    summary = summarize(spec, list(records.values()))
    assert summary["variants"]["default"]["n_error"] == 1
    assert summary["errors"][0]["count"] == 1 and "no_such_body" in summary["errors"][0]["error"]


def test_a_record_names_the_code_at_the_start_of_its_trial(monkeypatch):
    """The record's code is read before the trial runs (a commit made during a long trial is not what it ran)."""
    import sim.campaigns.trial as trial_module
    import sim.runner

    checkout = {"head": "a" * 40}

    def run_scenario(*args, **kwargs):
        checkout["head"] = "b" * 40  # a commit while the trial runs
        raise ValueError("stopped after the commit")

    monkeypatch.setattr(trial_module, "code_version", lambda: checkout["head"])
    monkeypatch.setattr(sim.runner, "run_scenario", run_scenario)
    trial = trial_module.make_trials(small_push_map())[0]
    record = trial_module.run_trial(trial)
    assert record["status"] == "error" and record["code"] == "a" * 40


def test_every_record_names_the_code_it_ran_and_the_report_warns_on_a_mix(tmp_path, inline_reference):
    from sim.campaigns.report import format_summary, summarize
    from sim.campaigns.trial import code_version

    _, records = inline_reference
    head = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
    assert code_version().split("-")[0] == head  # the checkout the tests import from (maybe "-dirty")
    assert {r["code"] for r in records} == {code_version()}
    store = ResultStore(tmp_path)
    store.write_spec(small_push_map().to_dict())
    for i, record in enumerate(records):  # half of them as if written by an older session's code
        store.append({**record, "code": "0" * 40} if i % 2 else {k: v for k, v in record.items() if k != "code"})
    summary = summarize(small_push_map(), store.records())
    assert {v["code"]: v["count"] for v in summary["code_versions"]} == {"0" * 40: 4, "not recorded": 4}
    assert "WARNING the trials ran on 2 code versions" in format_summary(summary)
