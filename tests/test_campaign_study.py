"""The step-timing study (adaptive against fixed timing) runs end to end with the walking controller.

A tiny grid and very short trials: this checks the machinery (variants reach the controller, both
are recorded and compared on the same trials), not the study's result, which needs the full grid
(``wbmpc campaign push-map --compare-timing fixed``, see docs/campaigns.md).
"""

from __future__ import annotations

import pytest

from sequencer import SequencerParams
from sim.campaigns import ResultStore, builtin_campaign, run_campaign, write_report


@pytest.mark.slow
def test_timing_study_runs_both_variants_with_the_walking_controller(tmp_path):
    spec = builtin_campaign(
        "push-map", compare_timing="fixed", steps_x=1, steps_y=1, force_max_x=2.0, force_max_y=2.0, phases=(0.0,),
        push_after=0.05, duration=0.25, timing_from=0.0,  # fixed timing from the start (tiny run)
    )
    run = run_campaign(spec, tmp_path, backend="inline", progress=False)
    assert (run.n_run, run.n_error) == (2, 0)
    records = {r["variant"]: r for r in ResultStore(tmp_path).records()}
    assert set(records) == {"adaptive", "fixed"}
    t_nom = SequencerParams.bolt_walking().t_nom
    fixed = records["fixed"]["arguments"]["sequencer_params"]
    assert fixed["t_min"] == fixed["t_max"] == t_nom
    adaptive = records["adaptive"]["arguments"]["sequencer_params"]
    assert adaptive["t_min"] < t_nom < adaptive["t_max"]
    for record in records.values():
        assert record["status"] in ("completed", "fell"), record["error"]
        assert record["metrics"]["mpc_updates"] >= 20  # the walking controller really ran (100 Hz)
        # first stance from t = 0 and no step finished yet: phase measured against T_nom
        assert record["metrics"]["push_phase_measured"] == pytest.approx(0.05 / t_nom, abs=0.02)
    summary = write_report(tmp_path, plots=False)
    (comparison,) = summary["comparisons"]
    assert comparison["n_pairs"] == 1 and comparison["paper_relative_change"] == 0.36
