"""How the whole-body MPC's first torques move when the next touchdown is advanced or delayed by up
to ±30 ms: the linear prediction u0 + du0/dτ1 Δτ (Riccati sweep) against re-solved OCPs, the
figure of docs/sensitivity.md ("Sensitivity of the whole-body MPC to the contact timings").

    python docs/scripts/timing_sensitivity_study.py [--nodes 100] [--plot docs/figures/sensitivity_timing_study.png]

Prints one JSON line per shift (Δτ [ms], re-solved u0, predicted u0, their gap [N·m]).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from wbmpc.walking.timing import contact_timing_sensitivity, standing_start_timing_ocp


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--max-shift-ms", type=float, default=30.0)
    parser.add_argument("--points", type=int, default=13)
    parser.add_argument("--plot", default="docs/figures/sensitivity_timing_study.png")
    args = parser.parse_args()
    timed = standing_start_timing_ocp("bolt", n_nodes=args.nodes)
    base = timed.solve(th_stop=1e-17)
    report = contact_timing_sensitivity(timed, base, routes=("riccati",), gauss_newton=True)
    slope = report.routes["riccati"]["u0"][:, 0]
    slope_gn = report.gauss_newton["outputs"]["u0"][:, 0]
    tau = timed.touchdown_times
    shifts = np.linspace(-args.max_shift_ms, args.max_shift_ms, args.points) * 1e-3
    truth = []
    for shift in shifts:
        moved = tau.copy()
        moved[0] += shift
        timed.set_parameters(moved)
        truth.append(timed.solve(base.xs, base.us, th_stop=1e-14, maxiter=1000).us[0].copy())
        predicted = base.us[0] + slope * shift
        print(json.dumps({"shift_ms": round(shift * 1e3, 2), "u0_resolved": np.round(truth[-1], 4).tolist(),
                          "u0_linear": np.round(predicted, 4).tolist(),
                          "max_gap_Nm": float(np.max(np.abs(truth[-1] - predicted)))}), flush=True)
    timed.set_parameters(tau)
    truth = np.array(truth)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    joints = list(timed.ocp.state.pinocchio.names[2:])
    fig, axes = plt.subplots(2, 3, figsize=(11, 6), sharex=True)
    for i, ax in enumerate(axes.ravel()):
        ax.plot(shifts * 1e3, truth[:, i], "o-", ms=3, label="re-solved OCP")
        ax.plot(shifts * 1e3, base.us[0, i] + slope[i] * shifts, "--", label="linear (exact Hessian)")
        ax.plot(shifts * 1e3, base.us[0, i] + slope_gn[i] * shifts, ":", label="linear (Gauss-Newton)")
        ax.set_title(joints[i])
        ax.axvline(0.0, color="k", lw=0.5)
        if i % 3 == 0:
            ax.set_ylabel("u0 [N·m]")
        if i >= 3:
            ax.set_xlabel(f"shift of touchdown 1 ({tau[0]:.3f} s) [ms]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Bolt: first torques of the whole-body MPC vs the next touchdown time")
    fig.tight_layout()
    fig.savefig(args.plot, dpi=120)
    print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
