"""Figures of a campaign summary (:func:`sim.campaigns.report.summarize`), PNG files.

- :func:`plot_force_maps`: success rate over the push-force grid (Fx from -F to F, Fy from 0 to F,
  world frame [N]) per variant, as in Fig. 6 of the ALIP paper, plus the difference map;
- :func:`plot_success_by_phase`: success rate per gait phase of the push, per variant;
- :func:`plot_success_by_axis`: success rate along other grid axes (terrain density...);
- :func:`plot_obstacle_success`: step-over success by box height, beside the seed-000 thesis's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_force_maps(summary: dict[str, Any], path: str | Path) -> str:
    """Success heatmap over (Fx, Fy) per variant (+ variant minus baseline when there are two)."""
    plt = _pyplot()
    maps = summary["force_map"]
    panels = list(maps.items())
    comparison = summary.get("comparisons", [None])[0]
    n_panels = len(panels) + (comparison is not None)
    fig, axes = plt.subplots(1, n_panels, figsize=(5.0 * n_panels, 4.0), squeeze=False, layout="constrained")
    axes = axes[0]

    def draw(ax, data, fx, fy, title, cmap, vmin, vmax, fmt):
        # cells by index (grid values need not be evenly spaced), labelled with the forces
        image = ax.imshow(np.ma.masked_invalid(data), origin="lower", aspect="auto", cmap=cmap, vmin=vmin, vmax=vmax)
        for i in range(data.shape[0]):
            for j in range(data.shape[1]):
                if np.isfinite(data[i, j]):
                    ax.text(j, i, format(data[i, j], fmt), ha="center", va="center", fontsize=7)
        ax.set_xticks(np.arange(len(fx)), [f"{x:g}" for x in fx])
        ax.set_yticks(np.arange(len(fy)), [f"{y:g}" for y in fy])
        ax.set_xlabel("push force Fx [N] (world)")
        ax.set_ylabel("push force Fy [N] (world)")
        ax.set_title(title, fontsize=10)
        return image

    for ax, (variant, m) in zip(axes, panels):
        rate = np.asarray(m["success_rate"], dtype=float)
        stats = summary["variants"][variant]
        title = f"{variant}: success {_percent(stats['success_rate'])} ({stats['n']} trials)"
        image = draw(ax, rate, m["force_x"], m["force_y"], title, "RdYlGn", 0.0, 1.0, ".2f")
    fig.colorbar(image, ax=axes[: len(panels)].tolist(), label="success rate")
    if comparison is not None:
        a, b = maps[comparison["variant"]], maps[comparison["baseline"]]
        difference = np.asarray(a["success_rate"], float) - np.asarray(b["success_rate"], float)
        title = f"{comparison['variant']} - {comparison['baseline']}"
        if comparison["change_points"] is not None:
            title += f": {comparison['change_points']:+.1f} points"
        image = draw(axes[-1], difference, a["force_x"], a["force_y"], title, "PiYG", -1.0, 1.0, "+.2f")
        fig.colorbar(image, ax=axes[-1], label="success rate difference")
    fig.suptitle(f"{summary['campaign']}: success = still walking at the end", fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_success_by_phase(summary: dict[str, Any], path: str | Path) -> str:
    """Success rate per gait phase of the push, one colour per variant: by the nominal phase (left)
    and, when measured, by bins of the measured phase (right, with the trial counts)."""
    plt = _pyplot()
    measured = summary.get("phase_measured")
    fig, axes = plt.subplots(1, 2 if measured else 1, figsize=(12.0 if measured else 6.4, 3.6), squeeze=False)
    phases = summary["phase"]
    variants = list(phases)
    width = 0.8 / len(variants)

    def bars(ax, labels, rates_by_variant, counts_by_variant=None):
        for k, variant in enumerate(variants):
            rates = [np.nan if r is None else r for r in rates_by_variant[variant]]
            x = np.arange(len(labels)) + (k - (len(variants) - 1) / 2) * width
            ax.bar(x, rates, width, label=variant)
            if counts_by_variant is not None:
                for xi, n in zip(x, counts_by_variant[variant]):
                    ax.text(xi, 0.02, str(n), ha="center", fontsize=7)
        ax.set_xticks(np.arange(len(labels)), labels)
        ax.set_ylabel("success rate")
        ax.set_ylim(0.0, 1.05)
        ax.legend(fontsize=8)

    nominal = [f"{e['phase']:.2f}" for e in phases[variants[0]]]
    bars(axes[0][0], nominal, {v: [e["success_rate"] for e in phases[v]] for v in variants})
    axes[0][0].set_xlabel("nominal gait phase of the push (fraction of T_nom)")
    axes[0][0].set_title(f"{summary['campaign']}: success per gait phase", fontsize=10)
    if measured:
        labels = [f"[{e['phase_range'][0]:.1f}, {e['phase_range'][1]:.1f})" for e in measured[variants[0]]]
        bars(
            axes[0][1], labels, {v: [e["success_rate"] for e in measured[v]] for v in variants},
            {v: [e["n"] for e in measured[v]] for v in variants},
        )
        axes[0][1].set_xlabel("measured gait phase at the push (bins; numbers: trials)")
        axes[0][1].set_title("success per measured phase", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_success_by_axis(summary: dict[str, Any], axes_names: list[str], path: str | Path) -> str:
    """One panel per grid axis: success rate per value, one colour per variant."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(axes_names), figsize=(5.0 * len(axes_names), 3.4), squeeze=False)
    for ax, name in zip(axes[0], axes_names):
        by_variant = summary["axes"][name]
        variants = list(by_variant)
        width = 0.8 / len(variants)
        labels = [str(e["value"]) for e in by_variant[variants[0]]]
        for k, variant in enumerate(variants):
            rates = [np.nan if e["success_rate"] is None else e["success_rate"] for e in by_variant[variant]]
            ax.bar(np.arange(len(labels)) + (k - (len(variants) - 1) / 2) * width, rates, width, label=variant)
        ax.set_xticks(np.arange(len(labels)), labels)
        ax.set_xlabel(name)
        ax.set_ylabel("success rate")
        ax.set_ylim(0.0, 1.05)
        ax.legend(fontsize=8)
    fig.suptitle(f"campaign {summary['campaign']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_obstacle_success(summary: dict[str, Any], path: str | Path) -> str:
    """Step-over success rate by box height [cm], one bar per variant, beside the seed-000 thesis's
    (H1-2, Fig. 5.13), with the 95 % Wilson interval of each rate as an error bar, the touched rate as a dot and the
    trial counts."""
    plt = _pyplot()
    by_variant = summary["obstacle"]
    variants = list(by_variant)
    entries = by_variant[variants[0]]
    labels = [f"{100 * e['height']:.0f}" for e in entries]
    n_bars = len(variants) + 1
    width = 0.8 / n_bars
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    x = np.arange(len(labels))
    for k, variant in enumerate(variants):
        offset = (k - (n_bars - 1) / 2) * width
        rates = [np.nan if e["success_rate"] is None else e["success_rate"] for e in by_variant[variant]]
        ax.bar(x + offset, rates, width, label=f"ours ({variant})" if len(variants) > 1 else "ours")
        bounds = np.array([e.get("success_interval_95") or (np.nan, np.nan) for e in by_variant[variant]], float)
        ax.errorbar(x + offset, rates, yerr=np.abs(bounds.T - np.asarray(rates, float)), fmt="none", ecolor="0.25",
                    elinewidth=1, capsize=3, label="95 % interval" if k == 0 else None)
        touched = [np.nan if e["touched_rate"] is None else e["touched_rate"] for e in by_variant[variant]]
        ax.plot(x + offset, touched, "kv", markersize=5, label="touched the box" if k == 0 else None)
        for xi, e in zip(x + offset, by_variant[variant]):
            ax.text(xi, 0.02, f"n={e['n']}", ha="center", fontsize=7)
    paper = [np.nan if e["paper_success_rate"] is None else e["paper_success_rate"] for e in entries]
    ax.bar(x + (n_bars - 1) / 2 * width, paper, width, color="0.6", label="seed 000 (H1-2, MJPC, Fig. 5.13)")
    ax.set_xticks(x, labels)
    ax.set_xlabel("box height [cm]")
    ax.set_ylabel("step-over success rate")
    ax.set_ylim(0.0, 1.3)
    ax.set_yticks(np.linspace(0.0, 1.0, 6))
    ax.legend(fontsize=8, loc="upper center", ncol=3)
    ax.set_title(f"{summary['campaign']}: step-over success by box height", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def _percent(rate: float | None) -> str:
    return "n/a" if rate is None else f"{100 * rate:.0f} %"
