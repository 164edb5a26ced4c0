"""How a push moves the G1's next step in the ALIP NMPC: the sensitivity's linear prediction against the
re-solved NMPC over a range of impulses, the figure of docs/sensitivity.md ("Sensitivity of the ALIP NMPC").

    python docs/scripts/alip_push_sensitivity.py [--vx 0.3] [--t-curr 0.1] [--max-impulse 20]
        [--plot docs/figures/alip_push_sensitivity.png] [--cost-instances 50]

The instance: the G1 preset walking at (vx, 0) on its orbit, t_curr into a left stance, pushed by Δp
[N·s] forward (x) or to the left (y), heading frame. Prints one JSON line per axis (the slopes, the
largest prediction error within the base active set, the impulses where the active set changes) and,
with --cost-instances N, the median cost of each route over N random instances.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from sensitivity.alip_crosscheck import AlipSensitivityAnalysis
from sensitivity.studies.alip_push import OUTPUTS, run_push_study
from sequencer.alip.instances import orbit_instance, random_instances
from sequencer.alip.params import AlipParams

LABELS = {"l_x_0": "next step length ℓ_x,0 [m]", "l_y_0": "next step width ℓ_y,0 [m]", "T_0": "current period T_0 [s]"}


def plot(studies, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for row, (study, step) in enumerate(((studies["x"], "l_x_0"), (studies["y"], "l_y_0"))):
        same = study.same_active_set
        for ax, name in zip(axes[row], (step, "T_0")):
            ax.plot(study.impulses, study.predicted[name], "k--", lw=1.2, label="linear prediction (IFT)")
            ax.plot(study.impulses[same], study.truth[name][same], "o", color="tab:blue", ms=4,
                    label="re-solved, unpushed active set")
            ax.plot(study.impulses[~same], study.truth[name][~same], "o", mfc="none", color="tab:red", ms=4,
                    label="re-solved, other active set")
            low, high = np.nanmin(study.truth[name]), np.nanmax(study.truth[name])
            ax.set_ylim(low - 0.1 * (high - low), high + 0.1 * (high - low))  # the prediction runs off beyond
            ax.set_ylabel(LABELS[name])
            ax.grid(alpha=0.3)
        axes[row][0].set_title(f"push along {study.axis} (heading frame)", loc="left", fontsize=10)
    for ax in axes[1]:
        ax.set_xlabel("impulse Δp [N·s]")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("G1 ALIP NMPC: the next step after a push, first-order prediction vs re-solved")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def route_costs(analysis: AlipSensitivityAnalysis, n: int) -> dict:
    """Median wall-clock cost [ms] of the IPOPT solve and of each route over ``n`` random instances."""
    costs = [analysis.crosscheck(instance).cost for instance in random_instances(analysis.params, n, seed=11)]
    return {key.removesuffix("_s") + "_ms": float(np.median([c[key] for c in costs]) * 1e3) for key in costs[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vx", type=float, default=0.3)
    parser.add_argument("--t-curr", type=float, default=0.1)
    parser.add_argument("--max-impulse", type=float, default=20.0)
    parser.add_argument("--points", type=int, default=41)
    parser.add_argument("--plot", default="docs/figures/alip_push_sensitivity.png")
    parser.add_argument("--cost-instances", type=int, default=0)
    args = parser.parse_args()
    params = AlipParams.preset("g1")
    analysis = AlipSensitivityAnalysis(params)
    instance = orbit_instance(params, args.vx, 0.0, "left", args.t_curr)
    impulses = np.linspace(-args.max_impulse, args.max_impulse, args.points)
    studies = {axis: run_push_study(analysis, instance, axis, impulses) for axis in ("x", "y")}
    for axis, study in studies.items():
        same = study.same_active_set
        slopes = {name: float((study.predicted[name][-1] - study.predicted[name][0]) / (impulses[-1] - impulses[0]))
                  for name in OUTPUTS}
        print(json.dumps({
            "axis": axis, "state_jump_per_Ns": study.state_jump.tolist(), "slope_per_Ns": slopes,
            "base_active_set_range_Ns": [float(impulses[same].min()), float(impulses[same].max())],
            "max_error_base_active_set": {name: study.max_error(name) for name in OUTPUTS},
            "max_error_within_2Ns": {name: study.max_error(name, within=2.0) for name in OUTPUTS},
            "first_changes": sorted({a for a, s in zip(study.active, same) if not s}, key=len)[:3],
        }))
    if args.plot:
        plot(studies, args.plot)
        print(f"wrote {args.plot}")
    if args.cost_instances:
        print(json.dumps({"route_costs_median": route_costs(analysis, args.cost_instances),
                          "instances": args.cost_instances}))


if __name__ == "__main__":
    main()
