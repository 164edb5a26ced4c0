"""Figure of an ALIP plan: footholds and CoM in the plane, step periods, ankle torques, ALIP state over time."""

from __future__ import annotations

import numpy as np

from sequencer.alip.nlp import AlipSolution
from sequencer.horizon import FootstepPlan

FOOT_COLORS = {"left": "tab:red", "right": "tab:blue"}


def plot_alip_plan(plan: FootstepPlan, solution: AlipSolution, com_xy, path: str, model, title: str = "") -> None:
    """Write a PNG: (a) footholds (optimised: filled, nominal tail: open) and the ALIP CoM, world frame;
    (b) the periods T_k; (c) the ankle torques τ_k; (d) the pre-impact ALIP states x_1..x_K."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    K = len(solution.periods)
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    ax = axes[0, 0]
    times = np.linspace(plan.t0, plan.steps[-1].touchdown_time, 600)
    com = plan.com_reference(times, np.asarray(com_xy, dtype=float))
    ax.plot(com[:, 0], com[:, 1], color="tab:purple", lw=1.2, label="CoM (ALIP, with the CoP shift)")
    ax.plot(*plan.stance_position, "s", color=FOOT_COLORS[plan.stance_foot], ms=10, mfc="none", label="stance")
    for k, step in enumerate(plan.steps):
        ax.plot(*step.position, "o", color=FOOT_COLORS[step.foot], mfc=FOOT_COLORS[step.foot] if k < K else "none")
        ax.annotate(str(k + 1), step.position, textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("x [m]"), ax.set_ylabel("y [m]"), ax.axis("equal"), ax.legend(fontsize=8)
    ax.set_title("footholds (filled: NMPC, open: nominal tail)")
    steps = np.arange(K)
    axes[0, 1].bar(steps, solution.periods, color="tab:gray")
    axes[0, 1].set_xlabel("step k"), axes[0, 1].set_ylabel("T_k [s]"), axes[0, 1].set_title("step periods")
    axes[1, 0].step(steps, solution.torques[:, 0], where="mid", label="τ_y (sagittal)")
    axes[1, 0].step(steps, solution.torques[:, 1], where="mid", label="τ_x (frontal)")
    axes[1, 0].set_xlabel("step k"), axes[1, 0].set_ylabel("[N·m]"), axes[1, 0].legend(), axes[1, 0].set_title("ankle torques")
    ax = axes[1, 1]
    mz = model.mz
    ax.plot(steps + 1, solution.states[:, 0], "o-", label="p_x [m]")
    ax.plot(steps + 1, solution.states[:, 2], "o-", label="p_y [m]")
    ax.plot(steps + 1, solution.states[:, 1] / mz, "s--", label="L_y / (m z) [m/s]")
    ax.plot(steps + 1, solution.states[:, 3] / mz, "s--", label="L_x / (m z) [m/s]")
    ax.set_xlabel("pre-impact state k"), ax.legend(fontsize=8), ax.set_title("ALIP trajectory (pre-impact, heading frame)")
    fig.suptitle(title or f"ALIP NMPC plan at t0 = {plan.t0:.3f} s")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
