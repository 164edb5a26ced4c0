"""Fig. 2 of Roux et al. 2024: p_T,y and b_T,y over DCM disturbances theta ~ N(0, sigma^2 I).

Samples theta, re-solves the footstep QP exactly for each sample, and compares the re-solves with
the first-order (Fiacco) prediction x* + dx*/dtheta theta. The paper writes N(0, 0.005); we read
0.005 m as the standard deviation of each component.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sensitivity.kkt import DcmSensitivity, fiacco_sensitivity
from sequencer.step_qp import ExactBackend, StepProblem


@dataclass(frozen=True)
class MonteCarloStudy:
    """Re-solves over sampled disturbances and the analytic planes.

    Attributes:
        theta: sampled disturbances [m], shape (n, 2).
        x: re-solved primal solutions, shape (n, 5).
        x_linear: first-order predictions x* + dx*/dtheta theta, shape (n, 5).
        sensitivity: the analytic DcmSensitivity at theta = 0.
        max_linearisation_error: max |x - x_linear| over samples for p_T,y and b_T,y [m], shape (2,).
        n_active_changed: number of samples whose active set differs from the nominal one.
    """

    theta: np.ndarray
    x: np.ndarray
    x_linear: np.ndarray
    sensitivity: DcmSensitivity
    max_linearisation_error: np.ndarray
    n_active_changed: int


def run_monte_carlo(problem: StepProblem, samples: int = 1000, sigma: float = 0.005, seed: int = 0) -> MonteCarloStudy:
    """Sample theta ~ N(0, sigma^2 I) (seeded), re-solve exactly, compare with the analytic planes."""
    sensitivity = fiacco_sensitivity(problem)
    rng = np.random.default_rng(seed)
    theta = rng.normal(0.0, sigma, size=(int(samples), 2))
    solver = ExactBackend()
    x = np.empty((theta.shape[0], 5))
    changed = 0
    for k, th in enumerate(theta):
        solution = solver.solve(problem.with_dcm_disturbance(th))
        x[k] = solution.x
        changed += int(not np.array_equal(solution.active, sensitivity.active))
    x_linear = sensitivity.x + theta @ sensitivity.dx_dtheta.T
    error = np.max(np.abs(x - x_linear), axis=0)[[1, 4]]
    return MonteCarloStudy(theta, x, x_linear, sensitivity, error, changed)


def plot_fig2(study: MonteCarloStudy, path: str, title: str = "") -> None:
    """Draw p_T,y (left) and b_T,y (right) over (theta_x, theta_y): re-solves and analytic planes.

    theta is drawn in mm and each solution as its deviation from the optimum at theta = 0, in mm or
    in µm (whichever keeps the tick labels short): the optima are given in the panel titles.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig = plt.figure(figsize=(12, 5.4))
    theta_mm = 1e3 * study.theta
    grid = np.linspace(theta_mm.min(), theta_mm.max(), 12)
    tx, ty = np.meshgrid(grid, grid)
    for col, (index, name) in enumerate(((1, "p_{T,y}"), (4, "b_{T,y}"))):
        ax = fig.add_subplot(1, 2, col + 1, projection="3d")
        optimum = study.sensitivity.x[index]
        slope = study.sensitivity.dx_dtheta[index]
        deviation = study.x[:, index] - optimum
        scale, unit = (1e3, "mm") if np.max(np.abs(deviation)) >= 1e-4 else (1e6, "µm")
        ax.scatter(theta_mm[:, 0], theta_mm[:, 1], scale * deviation, s=3, c="tab:blue", alpha=0.5,
                   label="re-solved QP")
        plane = scale * 1e-3 * (slope[0] * tx + slope[1] * ty)  # theta in mm -> m, then to the z unit
        ax.plot_surface(tx, ty, plane, color="tab:orange", alpha=0.35)
        ax.scatter([0.0], [0.0], [0.0], c="red", s=40, label="optimum (theta = 0)")
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.set_major_locator(MaxNLocator(5))
        ax.tick_params(axis="z", pad=6)
        ax.set_xlabel(r"$\theta_x$ [mm]", labelpad=6)
        ax.set_ylabel(r"$\theta_y$ [mm]", labelpad=6)
        ax.set_zlabel(rf"${name} - {name}^*$ [{unit}]", labelpad=14)
        ax.set_title(rf"${name}^*$ = {optimum:.4f} m, d/dθ = ({slope[0]:.4g}, {slope[1]:.4g})", fontsize=10)
        ax.set_box_aspect(None, zoom=0.88)  # room for the z label inside the panel
        if col == 0:
            ax.legend(loc="upper left", fontsize=8)
    fig.suptitle(title or "Fig. 2: footstep QP solutions over DCM disturbances, analytic planes (orange)")
    fig.subplots_adjust(left=0.02, right=0.95, bottom=0.04, top=0.88, wspace=0.12)
    fig.savefig(path, dpi=120)
    plt.close(fig)
