"""Active set of the ALIP NMPC (seed 001 eq. 11) at an IPOPT solution: which bounds are held in the sensitivity.

The NMPC's only inequalities are the boxes on its decision variables w (T, τ, ℓ, x_1..x_K); the S2S
constraints are equalities. IPOPT is an interior-point method: at its solution an inactive bound keeps a
tiny multiplier (≈ μ / distance) and an active one sits a tiny distance inside its bound. On 200 random
G1 instances (scaled variables, below) the active bounds are within 5e-13 of their bound with |λ| >= 1.16,
the inactive ones at least 1.2e-4 away with |λ| <= 5e-9. At a degenerate optimum (a bound touched with a
zero multiplier, e.g. the last step's ℓ^des exactly on its box) IPOPT stops ≈ 2e-8 inside it with
|λ| ≈ 3e-5 (μ / distance). Both are read together, in the NLP's scaled variables
(:attr:`sequencer.alip.nlp.AlipNlp.scale`; T [s], τ / (m g) [m], ℓ [m], p [m], L / (m z) [m/s]):

- *active*: within ``bound_tol`` (1e-6) of the bound; held (dw = d bound / dθ) by every route;
- *weakly active*: active with |λ| <= ``multiplier_tol`` (1e-3): strict complementarity fails, the solution
  map has a kink at the instance and only one-sided derivatives exist; reported, not hidden (held like the
  others: the derivative of the branch on which it stays active).

CasADi's convention: ∇f + J_gᵀ λ_g + λ_w = 0, λ_w < 0 on an active lower bound, > 0 on an active upper one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sequencer.alip.nlp import AlipInstance, AlipNlp, AlipSolution
from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class AlipActiveSet:
    """Which bounds of the NLP's decision vector w are held, shape (n_w,) each.

    Attributes:
        lower, upper: bool, the variable is at its lower / upper bound (both where lb = ub).
        weak: bool, at a bound with |λ| <= multiplier_tol (weakly active).
        names: "T_0:lower", ... of every active bound (nlp.names order).
        weakly_active: names of the weakly active ones.
        min_active_multiplier: smallest |λ| of an active bound (inf when none), scaled NLP.
        max_inactive_multiplier: largest |λ| of an inactive bound (0 when none), scaled NLP.
        min_inactive_distance: smallest distance of an inactive variable to a bound (inf when none), scaled NLP.
    """

    lower: np.ndarray
    upper: np.ndarray
    weak: np.ndarray
    names: tuple[str, ...]
    weakly_active: tuple[str, ...]
    min_active_multiplier: float
    max_inactive_multiplier: float
    min_inactive_distance: float

    @property
    def held(self) -> np.ndarray:
        """bool (n_w,): variables fixed to a bound in the sensitivity."""
        return self.lower | self.upper

    @property
    def differentiable(self) -> bool:
        """False when a bound is weakly active (the derivative is one-sided)."""
        return not bool(np.any(self.weak))

    def clean_multipliers(self, lam_w) -> np.ndarray:
        """IPOPT's bound multipliers with those of the inactive bounds set to exactly 0, shape (n_w,)."""
        return np.where(self.held, np.asarray(lam_w, dtype=float).ravel(), 0.0)


def detect_active_set(nlp: AlipNlp, instance: AlipInstance, solution: AlipSolution, bound_tol: float = 1e-6,
                      multiplier_tol: float = 1e-3) -> AlipActiveSet:
    """The active set of ``solution`` (an IPOPT or SQP optimum of ``instance``), see the module docstring.

    Args:
        bound_tol: distance to a bound counted as on it, NLP's scaled variables [-], > 0.
        multiplier_tol: |λ| at or below which an active bound is weakly active [-], > 0.
    """
    for name, value in (("bound_tol", bound_tol), ("multiplier_tol", multiplier_tol)):
        if not np.isfinite(value) or value <= 0:
            raise ParameterError(f"{name}={value!r} must be a finite number > 0")
    lbw, ubw = nlp.scaled_bounds(instance)
    w = solution.w / nlp.scale
    lam = np.asarray(solution.lam_w, dtype=float).ravel()
    lower, upper = w - lbw <= bound_tol, ubw - w <= bound_tol
    held = lower | upper
    weak = held & (np.abs(lam) <= multiplier_tol)
    names = tuple(f"{nlp.names[i]}:{'lower' if lower[i] else 'upper'}" for i in np.flatnonzero(held))
    weakly = tuple(f"{nlp.names[i]}:{'lower' if lower[i] else 'upper'}" for i in np.flatnonzero(weak))
    distance = np.minimum(w - lbw, ubw - w)
    return AlipActiveSet(
        lower=lower, upper=upper, weak=weak, names=names, weakly_active=weakly,
        min_active_multiplier=float(np.min(np.abs(lam[held]))) if held.any() else float("inf"),
        max_inactive_multiplier=float(np.max(np.abs(lam[~held]))) if (~held).any() else 0.0,
        min_inactive_distance=float(np.min(distance[~held])) if (~held).any() else float("inf"),
    )
