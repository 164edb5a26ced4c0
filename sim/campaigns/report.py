"""Summary of a campaign: success rates per variant, per grid axis, over the force grid, per gait phase.

A trial succeeds when its run completes the whole duration without a fall or an error (for push
campaigns the duration ends ``PUSH_RECOVERY_TIME`` after the latest push, so success means the
robot recovered and kept walking, the ALIP paper's criterion: "still walking after being pushed").
Trials that raised count as failures and are also counted apart (``n_error``): an error is a
bug or a solver breakdown, worth reading before trusting the map.

Gait phase: the grid's ``phase`` is nominal (push time = push_after + phase * T_nom). The phase
the push actually hit is measured from the controller's stance switches; it drifts with the gait,
and differently per variant (a step-timing variant changes the gait itself), so the report also
bins success by the measured phase (``phase_measured``).

Obstacle campaigns (scenario ``obstacle``, ``wbmpc campaign obstacles``): a trial succeeds when its
run completes and the robot crossed the box (``sim.obstacle_metrics``: base and both feet beyond
the far edge, no fall, nothing resting on the box); ``obstacle`` reports per height the success,
touch, fall and detection rates, the mean crossing time and height-estimate error, beside the
seed-000 thesis's success rates (``PAPER_OBSTACLE_SUCCESS``, H1-2, 20 trials per height).

Variant comparison (e.g. adaptive against fixed step timing): on the pairs of trials that share a
point and a seed, both recorded,

- ``change_points``: success rate of the variant minus that of the baseline [percentage points];
- ``relative_change_successes``: (successes of the variant - successes of the baseline) /
  successes of the baseline, the figure of the ALIP paper ("increased the number of successful
  recoveries by 36 %", G1, NMPC over ALIP step-to-step dynamics, Fig. 6).
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from sim.campaigns.spec import CampaignSpec
from sim.campaigns.store import SUMMARY_FILE
from sim.campaigns.trial import make_trials
from sim.obstacle_metrics import CROSSING_BALANCE_METRICS

PAPER_TIMING_GAIN = 0.36  # ALIP paper: adaptive step timing, +36 % successful push recoveries (G1)
MAX_ERROR_KINDS = 5
MEASURED_PHASE_BINS = 5  # bins of the measured push phase over [0, 1)
# The seed-000 thesis (Unitree H1-2, MJPC): step-over success by obstacle height [m], Fig. 5.13, 20 trials each
PAPER_OBSTACLE_SUCCESS = {0.1: 1.00, 0.2: 0.85, 0.3: 0.60, 0.4: 0.05}
OBSTACLE_DEPTH_BIN = 0.05  # [m] width of the box-depth bins of an obstacle campaign's per-depth success


def wilson_interval(successes: int, n: int, z: float = 1.959963984540054) -> tuple[float, float] | None:
    """Wilson score interval (lower, upper) of a success rate from ``successes`` of ``n`` trials, at the normal
    quantile ``z`` (default: 95 %); None when ``n`` is 0. Unlike the normal approximation it stays in [0, 1] and is
    not empty at 0 or n successes (0 of 20: [0, 0.161]; 20 of 20: [0.839, 1])."""
    if n <= 0:
        return None
    rate, z2 = successes / n, z * z
    centre = (rate + z2 / (2 * n)) / (1 + z2 / n)
    half = z * np.sqrt(rate * (1 - rate) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return max(0.0, float(centre - half)), min(1.0, float(centre + half))


def _stats(records: list[dict[str, Any]]) -> dict[str, Any]:
    n = len(records)
    n_success = sum(bool(r["success"]) for r in records)
    return {
        "n": n,
        "n_success": n_success,
        "n_fell": sum(r["status"] == "fell" for r in records),
        "n_error": sum(r["status"] == "error" for r in records),
        "n_failed": sum(r["status"] == "failed" for r in records),  # the controller had nothing left to follow
        "success_rate": n_success / n if n else None,
        "success_interval_95": wilson_interval(n_success, n),
    }


def _measured_phase(record: dict[str, Any]) -> float | None:
    """The push's measured gait phase wrapped to [0, 1) (None when not measured)."""
    value = record.get("metrics", {}).get("push_phase_measured")
    return None if value is None else float(value) % 1.0


def _circular_mean(phases: list[float]) -> float | None:
    """Mean of phases in [0, 1) on the circle (0.95 and 0.05 average to 0.0, not 0.5)."""
    if not phases:
        return None
    angle = 2 * np.pi * np.asarray(phases)
    return float(np.arctan2(np.sin(angle).mean(), np.cos(angle).mean()) / (2 * np.pi) % 1.0)


def summarize(spec: CampaignSpec, records: list[dict[str, Any]]) -> dict[str, Any]:
    """Summary of the ``records`` of campaign ``spec`` (records of other specs are ignored).

    Returns:
        A JSON-able dict: ``variants`` (stats per variant), ``axes`` (per grid axis, per variant, per
        value), ``force_map`` (when the grid has force_x and force_y: success rate, shape
        (n_force_y, n_force_x), None where nothing is recorded), ``unpushed`` (stats of the
        zero-force cell, the control trials: below 100 % the map mixes walking failures with
        push failures), ``phase`` (when the grid has
        phase, with the circular mean of the measured phase), ``phase_measured`` (success per bin
        of the measured phase, wrapped to [0, 1)), ``comparisons`` (each other variant against the
        first one, on paired trials) and ``errors`` (most frequent error texts).
    """
    trials = make_trials(spec)
    variants = list(spec.variants)
    rows = _recorded(trials, records)
    summary: dict[str, Any] = {
        "campaign": spec.name,
        "scenario": spec.scenario,
        "controller": spec.controller,
        "duration": spec.duration,
        "n_trials": len(trials),
        "n_recorded": len(rows),
        "complete": len(rows) == len(trials),
        "variants": {v: _stats([r for t, r in rows if t.variant == v]) for v in variants},
    }

    axes: dict[str, Any] = {}
    for axis, values in spec.grid.items():
        axes[axis] = {
            v: [
                {"value": value, **_stats([r for t, r in rows if t.variant == v and t.params.get(axis) == value])}
                for value in values
            ]
            for v in variants
        }
    summary["axes"] = axes

    if "force_x" in spec.grid and "force_y" in spec.grid:
        fx, fy = spec.grid["force_x"], spec.grid["force_y"]
        maps = {}
        for v in variants:
            rate = np.full((len(fy), len(fx)), np.nan)
            count = np.zeros((len(fy), len(fx)), dtype=int)
            cells: dict[tuple[int, int], list[bool]] = defaultdict(list)
            for t, r in rows:
                if t.variant == v:
                    cells[(fy.index(t.params["force_y"]), fx.index(t.params["force_x"]))].append(bool(r["success"]))
            for (i, j), outcomes in cells.items():
                rate[i, j], count[i, j] = np.mean(outcomes), len(outcomes)
            maps[v] = {"force_x": fx, "force_y": fy, "success_rate": rate, "n": count}
        summary["force_map"] = maps
        if 0.0 in fx and 0.0 in fy:  # the control trials: no push at all
            summary["unpushed"] = {
                v: _stats([r for t, r in rows if t.variant == v and t.params["force_x"] == 0 and t.params["force_y"] == 0])
                for v in variants
            }

    if "phase" in spec.grid:
        phases, measured_bins = {}, {}
        for v in variants:
            entries = []
            for value in spec.grid["phase"]:
                selected = [r for t, r in rows if t.variant == v and t.params.get("phase") == value]
                measured = [_measured_phase(r) for r in selected if _measured_phase(r) is not None]
                entries.append({"phase": value, **_stats(selected), "measured_phase_mean": _circular_mean(measured)})
            phases[v] = entries
            with_phase = [r for t, r in rows if t.variant == v and _measured_phase(r) is not None]
            measured_bins[v] = [
                {
                    "phase_range": [k / MEASURED_PHASE_BINS, (k + 1) / MEASURED_PHASE_BINS],
                    **_stats([r for r in with_phase if int(_measured_phase(r) * MEASURED_PHASE_BINS) == k]),
                }
                for k in range(MEASURED_PHASE_BINS)
            ]
        summary["phase"] = phases
        if any(entry["n"] for entries in measured_bins.values() for entry in entries):
            summary["phase_measured"] = measured_bins

    if len(variants) > 1:
        pairs: dict[int, dict[str, bool]] = defaultdict(dict)
        for t, r in rows:
            pairs[t.index // len(variants)][t.variant] = bool(r["success"])
        reference = variants[0]
        timing_study = all("step_timing" in spec.variants[v] for v in variants)
        comparisons = []
        for baseline in variants[1:]:
            paired = [p for p in pairs.values() if reference in p and baseline in p]
            s_ref = sum(p[reference] for p in paired)
            s_base = sum(p[baseline] for p in paired)
            n = len(paired)
            comparisons.append(
                {
                    "variant": reference,
                    "baseline": baseline,
                    "n_pairs": n,
                    "success_rate": s_ref / n if n else None,
                    "baseline_success_rate": s_base / n if n else None,
                    "change_points": 100.0 * (s_ref - s_base) / n if n else None,
                    "relative_change_successes": (s_ref - s_base) / s_base if s_base else None,
                    "only_variant_succeeds": sum(p[reference] and not p[baseline] for p in paired),
                    "only_baseline_succeeds": sum(p[baseline] and not p[reference] for p in paired),
                    "paper_relative_change": PAPER_TIMING_GAIN if timing_study else None,
                }
            )
        summary["comparisons"] = comparisons

    if spec.scenario == "obstacle" and "height" in spec.grid:
        summary["obstacle"] = _obstacle_summary(variants, spec.grid["height"], rows)
    summary.update(_errors_and_versions(rows))
    return summary


def _recorded(trials, records: list[dict[str, Any]]) -> list[tuple[Any, dict[str, Any]]]:
    """(trial, record) of each of ``trials`` (:func:`sim.campaigns.trial.make_trials`) that ``records`` holds, in the
    trials' order (records of other trials are ignored)."""
    by_key = {r["key"]: r for r in records}
    return [(trial, by_key[trial.key]) for trial in trials if trial.key in by_key]


def _errors_and_versions(rows) -> dict[str, Any]:
    """``errors`` (the most frequent error texts of the (trial, record) ``rows``) and ``code_versions`` (the code each
    trial ran, :func:`sim.campaigns.trial.code_version`; records written before it have none)."""
    errors = Counter(r["error"] for _, r in rows if r["status"] == "error")
    versions = Counter(r.get("code", "not recorded") for _, r in rows)
    return {"errors": [{"error": text, "count": count} for text, count in errors.most_common(MAX_ERROR_KINDS)],
            "code_versions": [{"code": code, "count": count} for code, count in versions.most_common()]}


def _mean(values: list[Any]) -> float | None:
    values = [float(v) for v in values if v is not None]
    return float(np.mean(values)) if values else None


def _obstacle_summary(variants, heights, rows) -> dict[str, Any]:
    """Per variant of ``variants`` and box height of ``heights`` [m], over the (trial, record) ``rows``: success,
    touched, fell and detected rates, mean crossing time [s],
    mean |height estimate error| [m], the falls by the most feet that got across the box before them
    (``falls_by_feet_across``: [0, 1, 2], from the ``feet_across`` metric: before the box, astride it, after
    crossing; records without it are not counted), the success by the box's drawn depth (``by_depth``, see
    :func:`_success_by_depth`), the mean DCM margins of the crossing's balance (``dcm_margins``: per metric of
    :data:`sim.obstacle_metrics.CROSSING_BALANCE_METRICS` [m], [mean over the successes, mean over the others], None
    where no trial has it) and the seed-000 thesis's success rate (None where it has none)."""
    out: dict[str, Any] = {}
    for variant in variants:
        entries = []
        for height in heights:
            selected = [r for t, r in rows if t.variant == variant and t.params.get("height") == height]
            metrics = [r.get("metrics", {}) for r in selected]
            n = len(selected)
            rate = {key: sum(bool(m.get(key)) for m in metrics) / n if n else None for key in ("touched", "detected")}
            errors = [abs(m["height_error"]) for m in metrics if m.get("height_error") is not None]
            entries.append({
                "height": height, **_stats(selected),
                "touched_rate": rate["touched"], "detected_rate": rate["detected"],
                "crossing_time_mean": _mean([m.get("crossing_time") for m in metrics]),
                "falls_by_feet_across": [sum(1 for m in metrics if m.get("fell") and m.get("feet_across") == k)
                                         for k in range(3)],
                "height_error_abs_mean": _mean(errors),
                "by_depth": _success_by_depth(metrics),
                "dcm_margins": {name: [_mean([m.get(name) for m in metrics if bool(m.get("success")) == ok])
                                       for ok in (True, False)] for name in CROSSING_BALANCE_METRICS},
                "paper_success_rate": PAPER_OBSTACLE_SUCCESS.get(round(float(height), 3)),
            })
        out[variant] = entries
    return out


def _success_by_depth(metrics: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Success by the box's depth along the path (the ``obstacle_depth`` metric [m], drawn per seed), in bins of
    ``OBSTACLE_DEPTH_BIN`` aligned on its multiples: [{"depth_range": [lo, hi] [m], "n", "n_success",
    "success_rate"}] for the bins holding a trial, shallowest first (a depth on a bin edge counts in the deeper bin;
    trials without the metric are left out)."""
    bins: dict[int, list[bool]] = {}
    for m in metrics:
        depth = m.get("obstacle_depth")
        if depth is not None:
            # the 1e-9 keeps a depth on an edge (0.15 / 0.05 = 2.9999999999999996) in the deeper bin
            bins.setdefault(int(np.floor(float(depth) / OBSTACLE_DEPTH_BIN + 1e-9)), []).append(bool(m.get("success")))
    return [{"depth_range": [round(k * OBSTACLE_DEPTH_BIN, 6), round((k + 1) * OBSTACLE_DEPTH_BIN, 6)],
             "n": len(outcomes), "n_success": sum(outcomes), "success_rate": sum(outcomes) / len(outcomes)}
            for k, outcomes in sorted(bins.items())]


def _fall_phases(entry: dict[str, Any]) -> str:
    """" (before the box B, astride A, after it C)" of an obstacle entry's falls, or "" when no fall has the count."""
    before, astride, after = entry.get("falls_by_feet_across") or (0, 0, 0)
    if before + astride + after == 0:
        return ""
    return f" (before the box {before}, astride {astride}, across {after})"


def _ranges(values: list[int]) -> str:
    """Sorted integers as runs: [0, 1, 2, 5, 7, 8] -> "0-2, 5, 7-8"."""
    runs: list[list[int]] = []
    for value in values:
        if runs and value == runs[-1][1] + 1:
            runs[-1][1] = value
        else:
            runs.append([value, value])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs) or "none"


def format_summary(summary: dict[str, Any]) -> str:
    """Human-readable report of :func:`summarize`'s result."""

    def pct(x: float | None) -> str:
        return "  n/a" if x is None else f"{100 * x:5.1f} %"

    def cm(value: float | None) -> str:  # a signed length [m] in centimetres
        return "n/a" if value is None else f"{100 * value:+.1f}"

    lines = [
        f"campaign {summary['campaign']} ({summary['scenario']}, controller {summary['controller']}): "
        f"{summary['n_recorded']}/{summary['n_trials']} trials recorded"
        + ("" if summary["complete"] else " (incomplete: run again with --resume)")
    ]
    for variant, s in summary["variants"].items():
        lines.append(
            f"  {variant:<12} success {pct(s['success_rate'])}  ({s['n_success']}/{s['n']}; fell {s['n_fell']}, "
            f"failed {s['n_failed']}, errors {s['n_error']})"
        )
    for variant, s in summary.get("unpushed", {}).items():
        if s["n"] and s["n_success"] < s["n"]:
            lines.append(
                f"  WARNING {variant}: {s['n'] - s['n_success']}/{s['n']} trials WITHOUT push failed: the map mixes "
                "walking failures with push failures (check the controller on the plain walk first)"
            )
    for variant, entries in summary.get("phase", {}).items():
        cells = "  ".join(
            f"{e['phase']:.2f}:{pct(e['success_rate']).strip()}"
            + ("" if e["measured_phase_mean"] is None else f" (measured {e['measured_phase_mean']:.2f})")
            for e in entries
        )
        lines.append(f"  per phase, {variant}: {cells}")
    for variant, entries in summary.get("phase_measured", {}).items():
        cells = "  ".join(
            f"[{e['phase_range'][0]:.1f},{e['phase_range'][1]:.1f}):{pct(e['success_rate']).strip()} ({e['n']})"
            for e in entries
        )
        lines.append(f"  per measured phase, {variant}: {cells}")
    for axis, by_variant in summary["axes"].items():
        if axis in ("phase", "force_x", "force_y") or len(next(iter(by_variant.values()))) < 2:
            continue
        for variant, entries in by_variant.items():
            cells = "  ".join(f"{e['value']}:{pct(e['success_rate']).strip()}" for e in entries)
            lines.append(f"  per {axis}, {variant}: {cells}")
    for c in summary.get("comparisons", []):
        line = (
            f"  {c['variant']} vs {c['baseline']} on {c['n_pairs']} paired trials: success "
            f"{pct(c['success_rate']).strip()} vs {pct(c['baseline_success_rate']).strip()}"
        )
        if c["change_points"] is not None:
            line += f", {c['change_points']:+.1f} points"
        if c["relative_change_successes"] is not None:
            line += f", successes {100 * c['relative_change_successes']:+.0f} %"
        if c["paper_relative_change"] is not None:
            line += f" (ALIP paper, G1, other controller: {100 * c['paper_relative_change']:+.0f} %)"
        lines.append(line)
    for variant, entries in summary.get("obstacle", {}).items():
        for e in entries:
            paper = "" if e["paper_success_rate"] is None else f" (seed 000: {pct(e['paper_success_rate']).strip()})"
            interval = e.get("success_interval_95")
            within = "" if interval is None else f" [{100 * interval[0]:.0f}-{100 * interval[1]:.0f} %]"
            lines.append(
                f"  obstacle {100 * e['height']:.0f} cm, {variant}: success {pct(e['success_rate']).strip()}"
                f" ({e['n_success']}/{e['n']}){within}{paper}, "
                f"touched {pct(e['touched_rate']).strip()}, fell {e['n_fell']}/{e['n']}{_fall_phases(e)}, detected "
                f"{pct(e['detected_rate']).strip()}"
            )
            if e.get("by_depth"):
                lines.append("    by box depth: " + ", ".join(
                    f"{100 * b['depth_range'][0]:.0f}-{100 * b['depth_range'][1]:.0f} cm {b['n_success']}/{b['n']}"
                    for b in e["by_depth"]))
            margins = e.get("dcm_margins") or {}
            if any(v is not None for pair in margins.values() for v in pair):
                lines.append("    DCM margin [cm], successes / others: " + ", ".join(
                    f"{name.removesuffix('_dcm_margin').replace('_', ' ')} {cm(ok)} / {cm(not_ok)}"
                    for name, (ok, not_ok) in margins.items()))
    for e in summary.get("errors", []):
        lines.append(f"  error x{e['count']}: {e['error']}")
    for source in summary.get("sources", []):
        params = ", ".join(f"{k}={v}" for k, v in source["params"].items()) or "no params"
        codes = ", ".join(v["code"][:7] for v in source["code_versions"])
        lines.append(f"  source {source['campaign']}: heights {source['heights']} m, seeds {_ranges(source['seeds'])}, "
                     f"{source['n_recorded']} trials, {params}, code {codes}")
    versions = summary.get("code_versions", [])
    if len(versions) > 1 and "sources" not in summary:
        lines.append("  WARNING the trials ran on " + str(len(versions)) + " code versions: "
                     + ", ".join(f"{v['code']} x{v['count']}" for v in versions))
    for path in summary.get("files", []):
        lines.append(f"  wrote {path}")
    return "\n".join(lines)


def _write_summary(summary: dict[str, Any], directory: Path, files: list[str]) -> dict[str, Any]:
    """Write ``summary`` as ``directory``/summary.json, with ``files`` (the figures written) and that file listed
    under ``files``; returns the summary."""
    from wbmpc.jsonable import to_jsonable

    summary["files"] = [*files, str(directory / SUMMARY_FILE)]
    (directory / SUMMARY_FILE).write_text(json.dumps(to_jsonable(summary), indent=2) + "\n")
    return summary


def write_report(directory: str | Path, plots: bool = True) -> dict[str, Any]:
    """Summarize the campaign stored in ``directory``: write ``summary.json`` and the figures.

    Figures: ``force_map.png`` (success heatmap over the force grid, one panel per variant, plus
    the difference when there are two), ``phase.png`` (success rate per gait phase),
    ``obstacle_success.png`` (obstacle campaigns: success by box height beside seed 000's) and
    ``axes.png`` (success rate along each other grid axis), each when the grid has the axes.

    Returns:
        The summary, with ``files`` listing what was written.
    """
    from sim.campaigns.run import load_campaign

    directory = Path(directory)
    spec, records = load_campaign(directory)
    summary = summarize(spec, records)
    files: list[str] = []
    if plots and summary["n_recorded"]:
        from sim.campaigns import plots as campaign_plots

        if "force_map" in summary:
            files.append(campaign_plots.plot_force_maps(summary, directory / "force_map.png"))
        if "phase" in summary:
            files.append(campaign_plots.plot_success_by_phase(summary, directory / "phase.png"))
        if "obstacle" in summary:
            files.append(campaign_plots.plot_obstacle_success(summary, directory / "obstacle_success.png"))
        other_axes = [a for a in summary["axes"] if a not in ("force_x", "force_y", "phase")]
        if other_axes:
            files.append(campaign_plots.plot_success_by_axis(summary, other_axes, directory / "axes.png"))
    return _write_summary(summary, directory, files)


def combine_obstacle_campaigns(directories: list[str | Path], out: str | Path, name: str | None = None,
                               plots: bool = True) -> dict[str, Any]:
    """One step-over summary from several obstacle campaigns of one robot (heights or seeds run apart, as a preset's
    20 trials per height often are): ``summary.json`` and ``obstacle_success.png`` written into ``out``.

    The trials are pooled by variant and box height; each source is listed under ``sources`` (its campaign, directory,
    heights, seeds, shared ``params`` and code versions), so a reader sees what was pooled. A (variant, height, seed)
    recorded by two sources is refused: it would be counted twice.

    Raises:
        ParameterError: fewer than two directories, a source that is not an obstacle campaign with a ``height`` grid,
            sources of different robots or controllers, or a trial in two sources.
        CampaignDirectoryError: a directory holds no campaign.
    """
    from sim.campaigns.run import load_campaign
    from wbmpc.errors import ParameterError

    if len(directories) < 2:
        raise ParameterError(f"directories={[str(d) for d in directories]} must name at least two campaigns to combine")
    sources, rows, owner = [], [], {}
    for directory in directories:
        spec, records = load_campaign(directory)
        if spec.scenario != "obstacle" or "height" not in spec.grid:
            raise ParameterError(f"campaign {spec.name!r} ({directory}) is not an obstacle campaign with a height grid "
                                 f"(scenario {spec.scenario!r}, grid {sorted(spec.grid)})")
        trials = make_trials(spec)
        mine = _recorded(trials, records)
        for trial, _ in mine:
            point = (trial.variant, float(trial.params["height"]), trial.seed)
            if point in owner:
                raise ParameterError(f"variant {point[0]!r}, height {point[1]} m, seed {point[2]} is in both "
                                     f"{owner[point]} and {spec.name!r}: combine campaigns of disjoint trials")
            owner[point] = repr(spec.name)
        rows.extend(mine)
        sources.append({"campaign": spec.name, "directory": str(directory), "robot": spec.robot,
                        "controller": spec.controller, "heights": sorted(spec.grid["height"]),
                        "seeds": sorted({t.seed for t, _ in mine}), "n_trials": len(trials), "n_recorded": len(mine),
                        "params": spec.params,
                        "code_versions": _errors_and_versions(mine)["code_versions"]})
    for key in ("robot", "controller"):
        values = sorted({source[key] for source in sources})
        if len(values) > 1:
            raise ParameterError(f"the campaigns' {key}s {values} differ: combine campaigns of one {key}")
    out = Path(out)
    variants = list(dict.fromkeys(t.variant for t, _ in rows))
    heights = sorted({float(t.params["height"]) for t, _ in rows})
    summary: dict[str, Any] = {
        "campaign": name or out.name, "scenario": "obstacle", "controller": sources[0]["controller"],
        "robot": sources[0]["robot"], "duration": None, "n_trials": sum(s["n_trials"] for s in sources),
        "n_recorded": len(rows), "complete": all(s["n_recorded"] == s["n_trials"] for s in sources),
        "sources": sources,
        "variants": {v: _stats([r for t, r in rows if t.variant == v]) for v in variants},
        "axes": {}, "obstacle": _obstacle_summary(variants, heights, rows), **_errors_and_versions(rows)}
    out.mkdir(parents=True, exist_ok=True)
    files: list[str] = []
    if plots and rows:
        from sim.campaigns import plots as campaign_plots

        files.append(campaign_plots.plot_obstacle_success(summary, out / "obstacle_success.png"))
    return _write_summary(summary, out, files)
