"""Figures of the sequencer: the paper's Fig. 3 (feet and DCM in the plane) plus y over time."""

from __future__ import annotations

import numpy as np

from sequencer.horizon import FootstepPlan
from sequencer.params import SequencerParams

FOOT_COLORS = {"left": "tab:red", "right": "tab:blue"}


def plot_plan(plan: FootstepPlan, params: SequencerParams, path: str, com_xy=None, title: str = "") -> None:
    """Write a PNG with the planned footholds, their bound boxes (eqs. 4a-4d, turned with each stance's
    heading) and the LIPM DCM/CoM.

    Args:
        plan: the FootstepPlan to draw.
        params: the parameters it was planned with (for the bound boxes).
        path: output file (PNG).
        com_xy: CoM (x, y) at plan.t0 [m] for the CoM curve; the measured DCM is used if omitted.
        title: figure title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    com0 = plan.dcm_measured if com_xy is None else np.asarray(com_xy, dtype=float)
    times = np.linspace(plan.t0, plan.steps[-1].touchdown_time, 600)
    dcm = plan.dcm_at(times)
    com = plan.lipm_com_at(times, com0)
    fig, (ax_xy, ax_y) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1.6, 1]})

    ax_xy.plot(dcm[:, 0], dcm[:, 1], color="tab:green", lw=1.5, label="DCM (LIPM)")
    ax_xy.plot(com[:, 0], com[:, 1], color="tab:purple", lw=1.0, ls="--", label="CoM (LIPM)")
    ax_xy.plot(*plan.dcm_measured, "o", color="tab:green", mfc="none", ms=9, label="measured DCM")
    ax_xy.plot(*plan.stance_position, "s", color=FOOT_COLORS[plan.stance_foot], ms=9, mfc="none",
               label=f"stance foot ({plan.stance_foot})")
    previous, stance, yaw = plan.stance_position, plan.stance_foot, plan.stance_yaw
    for k, step in enumerate(plan.steps):
        w_lo, w_hi = params.width_bounds(stance)
        c, s = np.cos(yaw), np.sin(yaw)  # the bounds hold in the stance's heading frame
        corner = previous + np.array((c * params.l_min - s * w_lo, s * params.l_min + c * w_lo))
        ax_xy.add_patch(
            Rectangle(tuple(corner), params.l_max - params.l_min, w_hi - w_lo, angle=float(np.degrees(yaw)),
                      fill=False, ls=":", lw=0.7, color=FOOT_COLORS[step.foot], alpha=0.6)
        )
        ax_xy.plot(*step.position, "o", color=FOOT_COLORS[step.foot], ms=7)
        ax_xy.annotate(str(k + 1), step.position, textcoords="offset points", xytext=(4, 4), fontsize=7)
        ax_xy.plot(*step.dcm_at_touchdown, "x", color="tab:green", ms=6)
        previous, stance, yaw = step.position, step.foot, step.yaw
    ax_xy.plot([], [], "o", color=FOOT_COLORS["left"], label="left footholds")
    ax_xy.plot([], [], "o", color=FOOT_COLORS["right"], label="right footholds")
    ax_xy.plot([], [], ":", color="gray", label="step bounds (4a-4d)")
    ax_xy.set_xlabel("x [m]")
    ax_xy.set_ylabel("y [m]")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.legend(fontsize=7, loc="best")
    ax_xy.grid(alpha=0.3)
    speed = plan.mean_velocity()[0] if len(plan.steps) >= 3 else float("nan")
    ax_xy.set_title(title or f"Fig. 3: planned steps, H_u = {plan.horizon:g} s, mean speed {speed:.3f} m/s")

    ax_y.plot(times, dcm[:, 1], color="tab:green", label="DCM y")
    ax_y.plot(times, com[:, 1], color="tab:purple", ls="--", label="CoM y")
    for step in plan.steps:
        ax_y.plot([step.touchdown_time], [step.position[1]], "o", color=FOOT_COLORS[step.foot], ms=5)
    ax_y.axhline(plan.stance_position[1], color=FOOT_COLORS[plan.stance_foot], lw=0.5)
    ax_y.set_xlabel("t [s]")
    ax_y.set_ylabel("y [m]")
    ax_y.grid(alpha=0.3)
    ax_y.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
