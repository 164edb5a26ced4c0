"""Campaign report: success maps, per-phase rates, the timing-study comparison, figures and the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sim.campaigns import ResultStore, builtin_campaign, make_trials, summarize, write_report
from sim.campaigns.report import PAPER_TIMING_GAIN, format_summary
from wbmpc.cli import main


def synthetic_records(spec, succeeds):
    """Records as run_trial writes them, with success decided by ``succeeds(trial)``."""
    records = []
    for trial in make_trials(spec):
        ok = succeeds(trial)
        records.append({
            "key": trial.key, "index": trial.index, "campaign": spec.name, "variant": trial.variant,
            "params": trial.params, "seed": trial.seed, "success": ok, "status": "completed" if ok else "fell",
            "error": None, "metrics": {"push_phase_measured": trial.params["phase"] + 0.05},
        })
    return records


def timing_study():
    return builtin_campaign("push-map", compare_timing="fixed", force_max_x=8.0, force_max_y=8.0, steps_x=5,
                            steps_y=3, phases=(0.0, 0.5))


def test_force_map_phase_rates_and_timing_comparison():
    spec = timing_study()

    def succeeds(trial):  # adaptive recovers |Fx| <= 4 N; fixed only Fx = 0 and only at phase 0
        fx = abs(trial.params["force_x"])
        if trial.variant == "adaptive":
            return fx <= 4.0
        return fx == 0.0 and trial.params["phase"] == 0.0

    summary = summarize(spec, synthetic_records(spec, succeeds))
    assert summary["complete"] and summary["n_recorded"] == 5 * 3 * 2 * 2
    adaptive = summary["force_map"]["adaptive"]
    assert adaptive["force_x"] == pytest.approx([-8.0, -4.0, 0.0, 4.0, 8.0])
    rate = np.asarray(adaptive["success_rate"])
    assert rate.shape == (3, 5)  # (Fy, Fx)
    np.testing.assert_array_equal(rate, np.tile([0.0, 1.0, 1.0, 1.0, 0.0], (3, 1)))
    np.testing.assert_array_equal(summary["force_map"]["fixed"]["success_rate"], np.tile([0, 0, 0.5, 0, 0], (3, 1)))
    phase = {e["phase"]: e for e in summary["phase"]["fixed"]}
    assert phase[0.0]["success_rate"] == pytest.approx(3 / 15) and phase[0.5]["success_rate"] == 0.0
    assert phase[0.5]["measured_phase_mean"] == pytest.approx(0.55)
    bins = summary["phase_measured"]["fixed"]  # measured 0.05 and 0.55: bins [0, 0.2) and [0.4, 0.6)
    assert [b["n"] for b in bins] == [15, 0, 15, 0, 0]
    assert bins[0]["success_rate"] == pytest.approx(3 / 15) and bins[0]["phase_range"] == [0.0, 0.2]
    (comparison,) = summary["comparisons"]
    assert (comparison["variant"], comparison["baseline"], comparison["n_pairs"]) == ("adaptive", "fixed", 30)
    # 18 adaptive successes against 3 fixed: +15 / 30 pairs = +50 points, +500 % successes
    assert comparison["change_points"] == pytest.approx(50.0)
    assert comparison["relative_change_successes"] == pytest.approx(5.0)
    assert (comparison["only_variant_succeeds"], comparison["only_baseline_succeeds"]) == (15, 0)
    assert comparison["paper_relative_change"] == PAPER_TIMING_GAIN
    text = format_summary(summary)
    assert "adaptive vs fixed on 30 paired trials" in text and "+50.0 points" in text and "+36 %" in text
    # control trials (no push): adaptive always walks on, fixed fails at phase 0.5 -> flagged
    assert summary["unpushed"]["adaptive"]["success_rate"] == 1.0
    assert (summary["unpushed"]["fixed"]["n"], summary["unpushed"]["fixed"]["n_success"]) == (2, 1)
    assert "WARNING fixed: 1/2 trials WITHOUT push failed" in text and "WARNING adaptive" not in text


def test_partial_campaign_compares_paired_trials_only():
    spec = timing_study()
    records = synthetic_records(spec, lambda trial: trial.variant == "adaptive")
    partial = records[:7]  # a stopped campaign: 3 full pairs and one adaptive trial alone
    summary = summarize(spec, partial)
    assert not summary["complete"] and summary["n_recorded"] == 7
    assert summary["comparisons"][0]["n_pairs"] == 3
    assert summary["comparisons"][0]["relative_change_successes"] is None  # no baseline success
    cells = np.asarray(summary["force_map"]["fixed"]["success_rate"], dtype=float)
    assert np.isnan(cells).sum() == cells.size - 2  # unrecorded cells stay empty, not 0


def test_report_writes_summary_and_figures_and_cli_prints_it(tmp_path, capsys):
    out = tmp_path / "campaign"
    # a real (tiny) campaign through the command line, in-process backend
    code = main([
        "campaign", "push-map", "--controller", "pd", "--steps-x", "2", "--steps-y", "1", "--phases", "0.0",
        "--push-after", "0.1", "--duration", "0.4", "--backend", "inline", "--out", str(out), "--json",
    ])
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["run"]["n_run"] == 2 and printed["summary"]["n_recorded"] == 2
    for name in ("force_map.png", "phase.png", "summary.json"):
        assert (out / name).stat().st_size > 0
    assert main(["campaign", "report", str(out)]) == 0
    text = capsys.readouterr().out
    assert "campaign push-map (push, controller pd): 2/2 trials recorded" in text
    summary = write_report(out, plots=False)
    assert summary["variants"]["default"]["n"] == 2
    assert len(ResultStore(out).records()) == 2
    # user errors: one line, exit code 2
    assert main(["campaign", "report", str(tmp_path / "nowhere")]) == 2
    assert "is not a campaign directory" in capsys.readouterr().err
    assert main(["campaign", "push-map", "--controller", "pd", "--out", str(out), "--backend", "inline"]) == 2
    assert "with different settings" in capsys.readouterr().err


def test_terrain_campaign_spans_seeds_and_densities(tmp_path):
    spec = builtin_campaign("terrain", seeds=3, densities=(5.0, 10.0))
    trials = make_trials(spec)
    assert spec.controller == "walking" and len(trials) == 6
    assert sorted({t.seed for t in trials}) == [0, 1, 2]
    assert sorted({t.arguments["density"] for t in trials}) == [5.0, 10.0]
    # a real (short, PD) terrain campaign: the report plots success along the density axis
    code = main([
        "campaign", "terrain", "--controller", "pd", "--seeds", "2", "--densities", "5", "40", "--duration", "0.2",
        "--backend", "inline", "--out", str(tmp_path), "--no-progress",
    ])
    assert code == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["n_recorded"] == 4 and [e["value"] for e in summary["axes"]["density"]["default"]] == [5.0, 40.0]
    assert (tmp_path / "axes.png").stat().st_size > 0 and not (tmp_path / "force_map.png").exists()


def test_measured_phase_wraps_around_the_step():
    from sim.campaigns.report import _circular_mean, _measured_phase

    wrapped = _circular_mean([0.95, 0.05])
    assert min(wrapped, 1.0 - wrapped) < 1e-9  # 0 on the circle, not 0.5
    assert _circular_mean([0.2, 0.4]) == pytest.approx(0.3)
    assert _circular_mean([]) is None
    assert _measured_phase({"metrics": {"push_phase_measured": 1.25}}) == pytest.approx(0.25)  # a late step
    assert _measured_phase({"metrics": {}}) is None


def test_success_by_depth_bins_on_multiples_of_five_centimetres_with_an_edge_in_the_deeper_bin():
    from sim.campaigns.report import _success_by_depth

    metrics = [{"obstacle_depth": 0.15, "success": True}, {"obstacle_depth": 0.1499, "success": False},
               {"obstacle_depth": 0.29, "success": True}, {"success": True}]
    assert _success_by_depth(metrics) == [
        {"depth_range": [0.1, 0.15], "n": 1, "n_success": 0, "success_rate": 0.0},
        {"depth_range": [0.15, 0.2], "n": 1, "n_success": 1, "success_rate": 1.0},
        {"depth_range": [0.25, 0.3], "n": 1, "n_success": 1, "success_rate": 1.0}]
    assert _success_by_depth([]) == []


def test_the_crossing_balance_margins_are_averaged_over_successes_and_failures_and_printed_in_centimetres():
    from types import SimpleNamespace

    from sim.campaigns.report import _obstacle_summary

    trial = SimpleNamespace(variant="default", params={"height": 0.4})
    rows = [(trial, {"status": "completed", "success": True, "metrics": {
                "success": True, "lead_touchdown_dcm_margin": 0.02, "trailing_liftoff_dcm_margin": -0.04,
                "trailing_touchdown_dcm_margin": 0.03}}),
            (trial, {"status": "fell", "success": False, "metrics": {
                "success": False, "fell": True, "feet_across": 1, "lead_touchdown_dcm_margin": -0.05,
                "trailing_liftoff_dcm_margin": -0.10, "trailing_touchdown_dcm_margin": None}}),
            (trial, {"status": "fell", "success": False, "metrics": {
                "success": False, "fell": True, "feet_across": 0, "lead_touchdown_dcm_margin": -0.01}})]
    entry = _obstacle_summary(["default"], [0.4], rows)["default"][0]
    assert entry["dcm_margins"]["lead_touchdown_dcm_margin"] == pytest.approx([0.02, -0.03])
    assert entry["dcm_margins"]["trailing_liftoff_dcm_margin"] == pytest.approx([-0.04, -0.10])
    assert entry["dcm_margins"]["trailing_touchdown_dcm_margin"] == [pytest.approx(0.03), None]
    summary = {"campaign": "c", "scenario": "obstacle", "controller": "walking", "n_recorded": 3, "n_trials": 3,
               "complete": True, "variants": {}, "axes": {}, "obstacle": {"default": [entry]}}
    assert ("DCM margin [cm], successes / others: lead touchdown +2.0 / -3.0, trailing liftoff -4.0 / -10.0, "
            "trailing touchdown +3.0 / n/a") in format_summary(summary)


def test_the_wilson_interval_stays_in_zero_one_and_matches_its_closed_form():
    from sim.campaigns.report import wilson_interval

    assert wilson_interval(0, 0) is None
    lower, upper = wilson_interval(0, 20)
    assert lower == 0.0 and upper == pytest.approx(0.1611, abs=1e-4)
    lower, upper = wilson_interval(20, 20)
    assert upper == 1.0 and lower == pytest.approx(0.8389, abs=1e-4)
    lower, upper = wilson_interval(17, 20)  # 85 %: 64.0-94.8 %
    assert (lower, upper) == pytest.approx((0.6396, 0.9476), abs=1e-4)
    z = 1.959963984540054  # closed form at 1 of 20
    p, n = 0.05, 20
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert wilson_interval(1, 20) == pytest.approx((centre - half, centre + half), rel=1e-12)


def test_obstacle_campaigns_run_apart_combine_into_one_summary_and_refuse_a_trial_counted_twice(tmp_path, capsys):
    """The H1 preset's 30 cm campaign, run as seeds 0-9 and 10-19 (docs/data/), pools to its 17 of 20 with both
    sources listed; the 10 cm one adds a height; the same campaign given twice, a push campaign and a single
    directory are refused in one line."""
    from pathlib import Path

    from sim.campaigns.report import combine_obstacle_campaigns

    data = Path(__file__).resolve().parents[1] / "docs" / "data"
    halves = [data / "h1-obstacles-s26-30cm-lateral-aim-planned-seeds0-9", data / "h1-obstacles-s27-30cm-seeds10-19"]
    ten = data / "h1-obstacles-s26-10cm-lateral-aim-planned"
    summary = combine_obstacle_campaigns([*halves, ten], tmp_path / "pooled", name="pooled")
    entries = summary["obstacle"]["default"]
    assert [e["height"] for e in entries] == [0.1, 0.3]
    assert [(e["n_success"], e["n"]) for e in entries] == [(20, 20), (17, 20)]
    assert entries[1]["success_interval_95"] == pytest.approx((0.6396, 0.9476), abs=1e-4)
    assert entries[1]["paper_success_rate"] == 0.6
    # by the boxes' drawn depths: the 30 cm failures are the shallowest and the deepest boxes
    assert [(b["depth_range"], b["n_success"], b["n"]) for b in entries[1]["by_depth"]] == [
        ([0.1, 0.15], 2, 3), ([0.15, 0.2], 7, 7), ([0.2, 0.25], 2, 2), ([0.25, 0.3], 6, 8)]
    assert [s["seeds"] for s in summary["sources"]] == [list(range(10)), list(range(10, 20)), list(range(20))]
    assert summary["n_recorded"] == 40 and summary["n_trials"] == 40 and summary["complete"] and summary["robot"] == "h1"
    # a source stopped halfway (10 of its 20 trials): counted as recorded, and the pool is not complete
    stopped = combine_obstacle_campaigns([halves[0], data / "h1-obstacles-s34-40cm-preset-apex-0.50"],
                                         tmp_path / "stopped", plots=False)
    assert (stopped["n_recorded"], stopped["n_trials"], stopped["complete"]) == (20, 30, False)
    assert "20/30 trials recorded (incomplete" in format_summary(stopped)
    written = json.loads((tmp_path / "pooled" / "summary.json").read_text())
    assert written["obstacle"]["default"][1]["n_success"] == 17
    assert (tmp_path / "pooled" / "obstacle_success.png").stat().st_size > 0
    text = format_summary(summary)
    assert "obstacle 30 cm, default: success 85.0 % (17/20) [64-95 %] (seed 000: 60.0 %)" in text
    assert "source h1-obstacles-s27-30cm-seeds10-19: heights [0.3] m, seeds 10-19, 10 trials" in text
    assert "by box depth: 10-15 cm 2/3, 15-20 cm 7/7, 20-25 cm 2/2, 25-30 cm 6/8" in text
    # through the command line, and its one-line refusals (exit code 2)
    assert main(["campaign", "combine", *map(str, halves), "--out", str(tmp_path / "cli"), "--no-plots"]) == 0
    assert "obstacle 30 cm, default: success 85.0 % (17/20)" in capsys.readouterr().out
    assert main(["campaign", "combine", str(halves[0]), str(halves[0]), "--out", str(tmp_path / "twice")]) == 2
    err = capsys.readouterr().err.strip()
    assert "seed 0 is in both" in err and len(err.splitlines()) == 1
    push = tmp_path / "push"
    ResultStore(push).write_spec(timing_study().to_dict())
    assert main(["campaign", "combine", str(halves[0]), str(push), "--out", str(tmp_path / "mixed")]) == 2
    assert "is not an obstacle campaign with a height grid" in capsys.readouterr().err
    assert main(["campaign", "combine", str(halves[0]), "--out", str(tmp_path / "one")]) == 2
    assert "must name at least two campaigns" in capsys.readouterr().err
