"""Campaign specs (grid, random sample, variants, seeds, TOML) and the translation of trial parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sequencer import SequencerParams
from sequencer.alip import AlipParams
from sim.campaigns import CampaignSpec, RandomSample, builtin_campaign, make_trials
from sim.campaigns.trial import (
    ALIP_FIXED_STEP_PERIOD,
    STIFF_TIMING_WEIGHT,
    measured_gait_phase,
    resolve_arguments,
    trial_key,
)
from wbmpc.errors import ParameterError


def test_push_map_covers_the_force_grid_phases_and_variants():
    spec = builtin_campaign("push-map", force_max_x=10.0, force_max_y=6.0, steps_x=5, steps_y=3, compare_timing="fixed")
    assert spec.grid["force_x"] == pytest.approx([-10.0, -5.0, 0.0, 5.0, 10.0])
    assert spec.grid["force_y"] == pytest.approx([0.0, 3.0, 6.0])
    assert spec.grid["phase"] == [0.0, 0.2, 0.4, 0.6, 0.8]
    assert list(spec.variants) == ["adaptive", "fixed"]
    assert spec.controller == "walking"  # campaigns judge the walking controller by default
    trials = make_trials(spec)
    assert len(trials) == spec.n_trials == 5 * 3 * 5 * 2
    # variants are innermost: consecutive trials share the point and the seed
    assert [t.variant for t in trials[:4]] == ["adaptive", "fixed", "adaptive", "fixed"]
    assert trials[0].params["force_x"] == trials[1].params["force_x"]
    assert len({t.key for t in trials}) == len(trials)
    # the default duration leaves the recovery time after the latest push
    t_nom = SequencerParams.bolt_walking().t_nom
    latest_push_end = spec.params["push_after"] + 0.8 * t_nom + 0.1
    assert spec.duration == pytest.approx(latest_push_end + 2.5)


def test_trial_arguments_translate_force_components_phase_and_step_timing():
    params = {"force_x": -3.0, "force_y": 4.0, "phase": 0.5, "push_after": 3.0, "step_timing": "fixed"}
    arguments = resolve_arguments("push", "walking", 6.0, params)
    assert arguments["force"] == pytest.approx(5.0)
    assert arguments["direction"] == pytest.approx(math.degrees(math.atan2(4.0, -3.0)))
    from wbmpc.walking.preset import load_walking_preset

    base = load_walking_preset("bolt").planner  # the walking controller's own parameters: 'adaptive' is the default controller
    assert arguments["push_time"] == pytest.approx(3.0 + 0.5 * base.t_nom)
    fixed = arguments["sequencer_params"]
    assert fixed.t_min == fixed.t_max == fixed.t_nom == base.t_nom
    assert fixed.alpha2 == base.alpha2 and fixed.l_max == base.l_max
    stiff = resolve_arguments("push", "walking", 6.0, {**params, "step_timing": "stiff"})["sequencer_params"]
    assert stiff.alpha2 == STIFF_TIMING_WEIGHT and (stiff.t_min, stiff.t_max) == (base.t_min, base.t_max)
    adaptive = resolve_arguments("push", "walking", 6.0, {**params, "step_timing": "adaptive"})["sequencer_params"]
    assert adaptive == base
    # campaign files give sequencer parameters as a preset name or a table
    from_preset = resolve_arguments("push", "walking", 6.0, {"sequencer_params": "table_i", "step_timing": "fixed"})
    assert from_preset["sequencer_params"].pelvis_width == SequencerParams.table_i().pelvis_width
    assert from_preset["sequencer_params"].t_min == from_preset["sequencer_params"].t_max
    table = resolve_arguments("push", "walking", 6.0, {"sequencer_params": {"alpha2": 5.0}})["sequencer_params"]
    assert table.alpha2 == 5.0 and table.pelvis_width == base.pelvis_width  # the rest: Bolt preset
    with pytest.raises(ParameterError, match=r"unknown sequencer parameter\(s\) \['alpha9'\]"):
        resolve_arguments("push", "walking", 6.0, {"sequencer_params": {"alpha9": 5.0}})
    # no push: a zero force has a well-defined direction
    zero = resolve_arguments("push", "pd", 6.0, {"force_x": 0.0, "force_y": 0.0})
    assert zero["force"] == 0.0 and zero["direction"] == 0.0
    assert zero["progress"] is False  # no nested progress bars in workers


@pytest.mark.parametrize(
    "params, message",
    [
        ({"phase": 1.0, "push_after": 1.0}, r"phase=1.0 must be in \[0, 1\)"),
        ({"phase": 0.2, "push_time": 1.0}, "phase and push_time both set"),
        ({"force_x": 1.0, "force": 2.0}, r"force_x/force_y and \['force'\]"),
        ({"push_after": 1.0}, "push_after needs a phase"),
        ({"step_timing": "sometimes"}, "step_timing='sometimes' must be one of"),
        ({"push_time": 5.95}, r"the push ends at t = 6.050 s, not before the end of the trial \(duration=6.0 s\)"),
        ({"force": 1500.0}, r"force=1500.0 N must be in \[0.0, 1000.0\] N"),
    ],
)
def test_invalid_trial_parameters_are_named(params, message):
    with pytest.raises(ParameterError, match=message):
        resolve_arguments("push", "walking", 6.0, params)


def test_spec_validation_names_the_problem():
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) \['forse_x'\]"):
        make_trials(CampaignSpec(name="c", scenario="push", grid={"forse_x": [1.0]}))
    with pytest.raises(ParameterError, match=r"step_timing"):  # pd has no sequencer
        make_trials(CampaignSpec(name="c", scenario="push", controller="pd", params={"step_timing": "fixed"}))
    with pytest.raises(ParameterError, match=r"\['speed'\] are set both in params and in grid"):
        CampaignSpec(name="c", scenario="walk", params={"speed": 0.1}, grid={"speed": [0.2]})
    with pytest.raises(ParameterError, match="variant 'v' overrides grid/random axis"):
        CampaignSpec(name="c", scenario="walk", grid={"speed": [0.2]}, variants={"v": {"speed": 0.1}})
    with pytest.raises(ParameterError, match="scenario='swim' is unknown"):
        CampaignSpec(name="c", scenario="swim")
    with pytest.raises(ParameterError, match="holds duplicates"):
        CampaignSpec(name="c", scenario="walk", seeds=[1, 1])
    with pytest.raises(ParameterError, match=r"unknown campaign key\(s\) \['grids'\]"):
        CampaignSpec.from_dict({"name": "c", "scenario": "walk", "grids": {}})
    with pytest.raises(ParameterError, match="the push ends"):
        make_trials(builtin_campaign("push-map", controller="pd", push_after=3.0, duration=3.0))


def test_random_sample_is_seeded_and_crossed_with_the_grid():
    sample = RandomSample(n=4, ranges={"force_x": (-5.0, 5.0), "force_y": (0.0, 3.0)}, sample_seed=3)
    spec = CampaignSpec(name="r", scenario="push", controller="pd", grid={"phase": [0.0, 0.5]}, random=sample,
                        params={"push_after": 1.0}, seeds=[0, 1])
    points = spec.points()
    assert len(points) == 8 and spec.n_trials == 16
    assert [{k: p[k] for k in ("force_x", "force_y")} for p in points[:4]] == RandomSample(
        n=4, ranges=sample.ranges, sample_seed=3
    ).points()
    assert [p["phase"] for p in points] == [0.0] * 4 + [0.5] * 4
    assert all(-5.0 <= p["force_x"] <= 5.0 and 0.0 <= p["force_y"] <= 3.0 for p in points)
    assert points[4:] != [{**p, "phase": 0.5} for p in RandomSample(n=4, ranges=sample.ranges, sample_seed=4).points()]


def test_toml_file_round_trips(tmp_path):
    path = tmp_path / "campaign.toml"
    path.write_text(
        """
name = "small"
scenario = "push"
controller = "pd"
duration = 2.0
seeds = [0, 1]

[params]
push_after = 1.0

[grid]
force_x = {start = -4.0, stop = 4.0, num = 3}
phase = [0.0, 0.5]

[random]
n = 2
sample_seed = 5
force_y = [0.0, 2.0]

[variants.soft]
kp = 2.0
[variants.stiff]
kp = 6.0
"""
    )
    spec = CampaignSpec.from_toml(path)
    assert spec.grid["force_x"] == [-4.0, 0.0, 4.0]
    assert spec.random.ranges == {"force_y": (0.0, 2.0)}
    assert spec.n_trials == 3 * 2 * 2 * 2 * 2
    again = CampaignSpec.from_dict(spec.to_dict())
    assert again == spec
    assert [t.key for t in make_trials(again)] == [t.key for t in make_trials(spec)]
    with pytest.raises(ParameterError, match="does not exist"):
        CampaignSpec.from_toml(tmp_path / "missing.toml")


def test_trial_key_depends_on_variant_params_and_seed_only():
    key = trial_key("a", {"x": 1.0, "y": 2}, 0)
    assert key == trial_key("a", {"y": 2, "x": 1.0}, 0)
    assert len({key, trial_key("b", {"x": 1.0, "y": 2}, 0), trial_key("a", {"x": 1.5, "y": 2}, 0),
                trial_key("a", {"x": 1.0, "y": 2}, 1)}) == 4


def test_measured_gait_phase_uses_the_previous_step_duration():
    t = np.arange(0.0, 1.0, 0.01)
    starts = np.where(t < 0.3, 0.0, np.where(t < 0.55, 0.3, 0.55))  # steps of 0.3 s then 0.25 s
    replans = {"t": t, "t_stance_start": starts}
    assert measured_gait_phase(replans, 0.4) == pytest.approx(0.1 / 0.3)
    assert measured_gait_phase(replans, 0.6) == pytest.approx(0.05 / 0.25)
    assert measured_gait_phase(replans, 0.15, t_nom=0.3) == pytest.approx(0.5)  # first step: nominal
    assert measured_gait_phase(replans, 0.15) is None
    assert measured_gait_phase({"t": t}, 0.5, t_nom=0.3) is None  # no stance information (PD)


def test_example_campaign_file_loads():
    from pathlib import Path

    import sim.campaigns

    path = Path(sim.campaigns.__file__).parent / "examples" / "timing_study_small.toml"
    spec = CampaignSpec.from_toml(path)
    trials = make_trials(spec)
    assert len(trials) == 3 * 4 * 2 * 2
    fixed = [t for t in trials if t.variant == "fixed"]
    # both variants start adaptive; the fixed timing applies from step_timing_from, before every push
    assert {t.arguments["sequencer_params_from"][1].t_max for t in fixed} == {0.3}
    assert all(t.arguments["sequencer_params"].t_max > 0.3 for t in trials)
    assert all(t.arguments["sequencer_params_from"][0] < t.arguments["push_time"] for t in fixed)
    assert max(t.arguments["push_time"] for t in trials) + 0.1 < spec.duration


def test_every_example_campaign_file_loads_and_expands():
    """Each file under sim/campaigns/examples/ (the G1's and the H1's push protocols, the G1's obstacles, the timing
    study) is a valid spec whose grid expands into its trials, each with a robot the library knows."""
    from pathlib import Path

    import sim.campaigns

    paths = sorted((Path(sim.campaigns.__file__).parent / "examples").glob("*.toml"))
    assert len(paths) >= 5
    for path in paths:
        spec = CampaignSpec.from_toml(path)
        trials = make_trials(spec)
        assert trials and spec.robot in ("bolt", "g1", "h1"), path.name
    h1_forward = make_trials(CampaignSpec.from_toml(paths[[p.name for p in paths].index("h1_push_forward.toml")]))
    assert len(h1_forward) == 5 * 5  # five forces at five phases


def test_the_campaign_times_the_planner_the_trial_runs():
    common = {"force_y": 100.0, "phase": 0.5, "push_after": 2.0, "speed": 0.0}
    alip = {**common, "footstep_planner.kind": "alip"}
    fixed = resolve_arguments("push", "walking", 6.0, {**alip, "step_timing": "fixed"}, robot="g1")
    assert fixed["push_time"] == pytest.approx(2.0 + 0.5 * AlipParams.preset("g1").t_des)  # the ALIP's T_des
    from wbmpc.walking.preset import load_walking_preset

    params = load_walking_preset("g1", {k: v for k, v in fixed.items() if k.startswith("footstep_planner")})
    timed = params.footstep_planner.alip
    assert timed.t_min == timed.t_des == timed.t_max == ALIP_FIXED_STEP_PERIOD and timed.double_support == 0.1
    later = resolve_arguments("push", "walking", 6.0, {**alip, "step_timing": "stiff", "step_timing_from": 1.0},
                              robot="g1")
    t_switch, stiff = later["sequencer_params_from"]
    assert t_switch == 1.0 and isinstance(stiff, AlipParams) and stiff.r_period == STIFF_TIMING_WEIGHT
    # the DCM variant of the G1 starts from the G1's [planner], not Bolt's
    dcm = resolve_arguments("push", "walking", 6.0, {**common, "footstep_planner.kind": "dcm", "step_timing": "fixed",
                                                      "step_timing_from": 1.0}, robot="g1")
    g1_planner = load_walking_preset("g1").planner
    assert dcm["sequencer_params"] == g1_planner and dcm["push_time"] == pytest.approx(2.0 + 0.5 * g1_planner.t_nom)
    assert dcm["sequencer_params_from"][1].t_min == dcm["sequencer_params_from"][1].t_max == g1_planner.t_nom
    # the walking steps' timing is fixed, a step over an obstacle keeps its duration range (0.6-0.8 s on the G1)
    crossing = dcm["sequencer_params_from"][1].foothold_geometry()
    assert (crossing.step_duration_min, crossing.step_duration_max) == (g1_planner.obstacle_step_duration_min,
                                                                       g1_planner.t_max)
