"""Route (a) to the ALIP NMPC's sensitivity: the implicit-function theorem on its KKT system at IPOPT's solution.

The NLP is :class:`sequencer.alip.nlp.AlipNlp` (seed 001 eq. 11, decision vector w in its scaled variables
w_s = w / scale, parameter vector p). θ = :data:`sequencer.alip.nlp.SENSITIVITY_PARAMETERS` (the measured
ALIP state x0, t_curr and the command v_x, v_y, yaw_rate) enters through p (affine, dp/dθ = P) and through
the lower bound of T_0 (max(t_min, t_curr); d lb/dθ = D), both from :meth:`AlipNlp.parameter_jacobian`.

With the Lagrangian L = f + λ_gᵀ g + λ_wᵀ w_s (CasADi's signs), the active set A of
:mod:`sensitivity.alip_active_set` held (dw_A = D_A / scale_A on a lower bound, 0 on an upper one) and the
free variables F, differentiating ∇_w L = 0, g = 0 in θ gives::

    [ H_FF   J_Fᵀ ] [ dw_F  ]     [ H_FA dw_A + ∇²_wp L_F P ]
    [ J_F     0   ] [ dλ_g  ] = − [ J_A dw_A  + ∇_p g P     ]          (H = ∇²_ww L, J = ∇_w g)

The matrix is nonsingular when the free columns of J have full row rank (LICQ) and the reduced Hessian
Zᵀ H_FF Z (Z a null-space basis of J_F) is positive definite (second-order sufficiency); both are checked,
:class:`~sensitivity.kkt.DegenerateSensitivity` names the failure. A weakly active bound (zero multiplier)
is held and reported (``active.weakly_active``): the result is then the derivative of the branch on which it
stays active.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.linalg

from sensitivity.alip_active_set import AlipActiveSet, detect_active_set
from sensitivity.kkt import DegenerateSensitivity
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import SENSITIVITY_PARAMETERS, AlipInstance, AlipNlp, AlipSolution


@dataclass(frozen=True)
class AlipSensitivity:
    """Derivatives of the ALIP NMPC's optimum with respect to θ = SENSITIVITY_PARAMETERS, physical units.

    Attributes:
        instance, solution: the instance and its optimum (IPOPT) at which they are taken.
        dw_dtheta: shape (n_w, 8): row i is d w_i / dθ for w = (T (K) [s], τ (2K) [N·m], ℓ (2K) [m],
            x_1..x_K (4K)), columns θ = (p_x [m], L_y [kg·m²/s], p_y [m], L_x [kg·m²/s], t_curr [s], v_x, v_y
            [m/s], yaw_rate [rad/s]); e.g. dℓ_x,0/dL_y in m/(kg·m²/s). Each step k's quantities in its heading
            frame (the current stance's for k = 0). NaN in a column a route could not give (see the route).
        active: the active set held (:class:`~sensitivity.alip_active_set.AlipActiveSet`).
        method: "kkt", "casadi" or "finite_differences".
        names: names of the rows of dw_dtheta (``nlp.names``).
        dlam_g_dtheta: derivative of the S2S constraints' multipliers (scaled NLP), shape (n_g, 8), or None.
        reduced_hessian_min_eigenvalue: smallest eigenvalue of Zᵀ H_FF Z (route (a)), else None.
    """

    instance: AlipInstance
    solution: AlipSolution
    dw_dtheta: np.ndarray
    active: AlipActiveSet
    method: str
    names: tuple[str, ...]
    dlam_g_dtheta: np.ndarray | None = None
    reduced_hessian_min_eigenvalue: float | None = None

    @property
    def steps_count(self) -> int:
        """K."""
        return len(self.solution.periods)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Column names."""
        return SENSITIVITY_PARAMETERS

    @property
    def dperiods_dtheta(self) -> np.ndarray:
        """dT_k/dθ, shape (K, 8)."""
        return self.dw_dtheta[:self.steps_count]

    @property
    def dtorques_dtheta(self) -> np.ndarray:
        """dτ_k/dθ (rows τ_y, τ_x), shape (K, 2, 8)."""
        K = self.steps_count
        return self.dw_dtheta[K:3 * K].reshape(K, 2, -1)

    @property
    def dsteps_dtheta(self) -> np.ndarray:
        """dℓ_k/dθ (rows ℓ_x, ℓ_y), shape (K, 2, 8)."""
        K = self.steps_count
        return self.dw_dtheta[3 * K:5 * K].reshape(K, 2, -1)

    @property
    def decision_jacobian(self) -> np.ndarray:
        """d(T, τ, ℓ)/dθ, the planner's outputs, shape (5K, 8) (rows ``names[:5K]``)."""
        return self.dw_dtheta[:5 * self.steps_count]


def held_bound_derivative(nlp: AlipNlp, instance: AlipInstance, active: AlipActiveSet) -> tuple[np.ndarray, np.ndarray]:
    """(dp/dθ shape (n_p, 8), dw_s/dθ of the held variables shape (n_w, 8), zero on free rows; scaled NLP)."""
    dp, dlb = nlp.parameter_jacobian(instance)
    dw_held = np.where(active.lower[:, None], dlb / nlp.scale[:, None], 0.0)  # ubw does not move with θ
    return dp, dw_held


class AlipKktRoute:
    """Route (a): builds the KKT derivatives of ``nlp`` once (CasADi AD on the NLP's own expressions)."""

    name = "kkt"

    def __init__(self, nlp: AlipNlp) -> None:
        self.nlp = nlp
        w, p, f, g = (nlp.nlp[key] for key in ("x", "p", "f", "g"))
        lam_g = ca.SX.sym("lam_g", nlp.n_g)
        gradient = ca.gradient(f + ca.dot(lam_g, g), w)
        self._derivatives = ca.Function("alip_kkt_derivatives", [w, p, lam_g], [
            ca.jacobian(gradient, w), ca.jacobian(gradient, p), ca.jacobian(g, w), ca.jacobian(g, p)])

    def sensitivity(self, instance: AlipInstance, solution: AlipSolution, active: AlipActiveSet | None = None,
                    rank_tol: float = 1e-10) -> AlipSensitivity:
        """dw*/dθ at ``solution`` (a converged optimum of ``instance``; IPOPT's multipliers).

        Args:
            active: the active set (detected with its defaults when omitted).
            rank_tol: relative singular-value threshold of the LICQ and second-order checks.

        Raises:
            DegenerateSensitivity: LICQ or second-order sufficiency fails (names which).
        """
        nlp = self.nlp
        if active is None:
            active = detect_active_set(nlp, instance, solution)
        dp, dw_held = held_bound_derivative(nlp, instance, active)
        w_s = solution.w / nlp.scale
        H, Lwp, Jw, Jp = (np.asarray(m) for m in self._derivatives(w_s, nlp.parameters(instance), solution.lam_g))
        free, held = ~active.held, active.held
        J_free = Jw[:, free]
        singular = np.linalg.svd(J_free, compute_uv=False)
        if singular.size < nlp.n_g or singular[-1] <= rank_tol * max(1.0, singular[0]):
            raise DegenerateSensitivity(f"the S2S constraints' gradients over the free variables are dependent "
                                        f"(LICQ fails) with the active bounds {list(active.names)}")
        Z = scipy.linalg.null_space(J_free, rcond=rank_tol)
        reduced = Z.T @ H[np.ix_(free, free)] @ Z
        min_eig = float(np.min(np.linalg.eigvalsh(0.5 * (reduced + reduced.T)))) if Z.size else float("inf")
        if min_eig <= rank_tol * max(1.0, float(np.max(np.abs(reduced))) if Z.size else 1.0):
            raise DegenerateSensitivity(f"the reduced Hessian is not positive definite (smallest eigenvalue "
                                        f"{min_eig:.3g}): no strict local minimum, no derivative")
        n_free = int(free.sum())
        matrix = np.block([[H[np.ix_(free, free)], J_free.T], [J_free, np.zeros((nlp.n_g, nlp.n_g))]])
        rhs = -np.vstack([H[np.ix_(free, held)] @ dw_held[held] + Lwp[free] @ dp,
                          Jw[:, held] @ dw_held[held] + Jp @ dp])
        step = np.linalg.solve(matrix, rhs)
        dw_s = dw_held.copy()
        dw_s[free] = step[:n_free]
        return AlipSensitivity(instance=instance, solution=solution, dw_dtheta=dw_s * nlp.scale[:, None],
                               active=active, method=self.name, names=tuple(nlp.names),
                               dlam_g_dtheta=step[n_free:], reduced_hessian_min_eigenvalue=min_eig)


def alip_kkt_sensitivity(nlp: AlipNlp, instance: AlipInstance, solution: AlipSolution | None = None) -> AlipSensitivity:
    """Route (a) in one call: IPOPT's optimum of ``instance`` (solved when omitted), its active set, dw*/dθ.

    Builds the CasADi derivative functions each call; keep an :class:`AlipKktRoute` for repeated use.
    """
    if solution is None:
        solution = IpoptSolver(nlp).solve(instance)
    return AlipKktRoute(nlp).sensitivity(instance, solution)
