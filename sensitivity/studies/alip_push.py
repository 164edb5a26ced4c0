"""How a push moves the ALIP NMPC's next step: the linear prediction of the sensitivity against re-solves.

An impulse Δp [N·s] on the CoM changes the ALIP state by :meth:`AlipModel.impulse_state_change`
(ΔL_y = z Δp_x, ΔL_x = −z Δp_y for a horizontal push, heading frame; the CoM does not move), so the
first-order prediction of the optimum is w(Δp) ≈ w* + dw*/dx0 · Δx(Δp), with dw*/dx0 the x0 columns of
route (a) (:mod:`sensitivity.alip_kkt`). The truth is the NMPC re-solved by IPOPT at every impulse; the
active set of each re-solve is recorded, so where the prediction stops holding because a bound was hit
is visible rather than averaged into an error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sensitivity.alip_active_set import detect_active_set
from sensitivity.alip_crosscheck import AlipSensitivityAnalysis
from sensitivity.alip_kkt import AlipSensitivity
from sequencer.alip.nlp import AlipInstance, AlipSolverError
from wbmpc.errors import ParameterError

OUTPUTS = ("l_x_0", "l_y_0", "T_0")


@dataclass(frozen=True)
class PushStudy:
    """Re-solved and predicted first step over a range of impulses along one horizontal axis.

    Attributes:
        axis: "x" (forward push, heading frame) or "y" (to the left).
        impulses: Δp [N·s], shape (n,).
        truth, predicted: output name (:data:`OUTPUTS`: ℓ_x,0, ℓ_y,0 [m], T_0 [s]) -> shape (n,); truth NaN where
            IPOPT failed (no feasible step, or it gave up).
        active: the active bounds of each re-solve (("failed: <status>",) where it failed); base_active: those of
            the unpushed optimum.
        sensitivity: route (a) at the unpushed instance.
        state_jump: Δx0 per N·s of impulse, shape (4,).
    """

    axis: str
    impulses: np.ndarray
    truth: dict
    predicted: dict
    active: tuple[tuple[str, ...], ...]
    base_active: tuple[str, ...]
    sensitivity: AlipSensitivity
    state_jump: np.ndarray

    @property
    def same_active_set(self) -> np.ndarray:
        """bool (n,): the re-solve has the unpushed active set."""
        return np.array([a == self.base_active for a in self.active])

    def max_error(self, name: str, within: float | None = None) -> float:
        """max |truth − predicted| of output ``name`` over the impulses with the base active set (and |Δp| <= within)."""
        keep = self.same_active_set & (np.abs(self.impulses) <= (np.inf if within is None else within))
        return float(np.max(np.abs(self.truth[name] - self.predicted[name])[keep])) if keep.any() else float("nan")


def run_push_study(analysis: AlipSensitivityAnalysis, instance: AlipInstance, axis: str, impulses) -> PushStudy:
    """Re-solve ``instance`` pushed by each impulse [N·s] along ``axis`` and predict it from the sensitivity."""
    if axis not in ("x", "y"):
        raise ParameterError(f"axis={axis!r} must be 'x' or 'y'")
    impulses = np.asarray(impulses, dtype=float).reshape(-1)
    nlp = analysis.nlp
    model = analysis.params.model
    solution = analysis.solve(instance)
    sens = analysis.sensitivity(instance, solution)
    unit = np.array([1.0, 0.0]) if axis == "x" else np.array([0.0, 1.0])
    jump = model.impulse_state_change(unit, (instance.x0[0], instance.x0[2]))  # linear in the impulse
    rows = [nlp.names.index(name) for name in OUTPUTS]
    slope = sens.dw_dtheta[rows, :4] @ jump
    truth = {name: [] for name in OUTPUTS}
    active = []
    for impulse in impulses:
        pushed = instance.with_theta(instance.theta + np.concatenate([impulse * jump, np.zeros(4)]))
        try:
            solved = analysis.solve(pushed)
        except AlipSolverError as err:  # no step catches this push (or IPOPT gave up): a gap in the curve
            for name in OUTPUTS:
                truth[name].append(np.nan)
            active.append((f"failed: {err.status}",))
            continue
        for name, row in zip(OUTPUTS, rows):
            truth[name].append(solved.w[row])
        active.append(detect_active_set(nlp, pushed, solved).names)
    predicted = {name: solution.w[row] + slope[i] * impulses for i, (name, row) in enumerate(zip(OUTPUTS, rows))}
    return PushStudy(axis=axis, impulses=impulses, truth={k: np.array(v) for k, v in truth.items()}, predicted=predicted,
                     active=tuple(active), base_active=sens.active.names, sensitivity=sens, state_jump=jump)
