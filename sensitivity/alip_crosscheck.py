"""The ALIP NMPC's sensitivity by its three routes, their disagreement and their cost.

Routes (one module each): ``kkt`` (a, :mod:`sensitivity.alip_kkt`, the reference of the comparison),
``casadi`` (b, :mod:`sensitivity.alip_casadi`), ``finite_differences`` (c,
:mod:`sensitivity.alip_finite_differences`). All three start from one IPOPT optimum and one active set.

Disagreement is measured on the planner's outputs (T, τ, ℓ of the K steps) in the NLP's scaled units
(T [s], τ / (m g) [m], ℓ [m]; θ in :attr:`~sequencer.alip.nlp.AlipNlp.parameter_scale` units), per
parameter θ_j relative to the largest entry of route (a)'s column::

    d_j = max_i |J_route,ij − J_kkt,ij| / max_i |J_kkt,ij|

Columns where the finite differences saw an active-set change have no central difference (NaN) and are
left out of route (c)'s maximum, and listed (``fd_changes``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from sensitivity.alip_active_set import AlipActiveSet, detect_active_set
from sensitivity.alip_casadi import AlipCasadiRoute
from sensitivity.alip_finite_differences import DEFAULT_FD_STEP, ActiveSetChange, AlipFiniteDifferenceRoute
from sensitivity.alip_kkt import AlipKktRoute, AlipSensitivity
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import SENSITIVITY_PARAMETERS, AlipInstance, AlipNlp, AlipSolution
from sequencer.alip.params import AlipParams
from wbmpc.errors import ParameterError

ALIP_ROUTES = ("kkt", "casadi", "finite_differences")


def relative_disagreement(nlp: AlipNlp, jacobian: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """d_j (shape (8,)) of two dw/dθ (shape (n_w, 8), physical units) on the rows (T, τ, ℓ); NaN stays NaN."""
    rows = 5 * nlp.K
    to_scaled = nlp.parameter_scale[None, :] / nlp.scale[:rows, None]
    a, b = jacobian[:rows] * to_scaled, reference[:rows] * to_scaled
    return np.max(np.abs(a - b), axis=0) / np.maximum(np.max(np.abs(b), axis=0), np.finfo(float).tiny)


@dataclass(frozen=True)
class AlipCrosscheck:
    """Every route's sensitivity of one instance.

    Attributes:
        instance, solution: the instance and its IPOPT optimum; active: the active set held.
        routes: route name -> :class:`~sensitivity.alip_kkt.AlipSensitivity`.
        disagreement: route name ("casadi", "finite_differences") -> d_j vs route (a), shape (8,).
        max_relative_disagreement: largest finite d_j over both routes.
        fd_changes: active-set changes seen by route (c); fd_steps: its steps h_j (physical units), shape (8,).
        cost: seconds of the IPOPT solve and of each route (one run, wall clock).
    """

    instance: AlipInstance
    solution: AlipSolution
    active: AlipActiveSet
    routes: dict
    disagreement: dict
    max_relative_disagreement: float
    fd_changes: tuple[ActiveSetChange, ...]
    fd_steps: np.ndarray
    cost: dict

    @property
    def parameters(self) -> tuple[str, ...]:
        return SENSITIVITY_PARAMETERS


class AlipSensitivityAnalysis:
    """The NLP, IPOPT and the three routes of one parameter set, built once (CasADi functions).

    Args:
        params: AlipParams (e.g. ``AlipParams.preset("g1")``).
        fd_step: route (c)'s relative step (see :mod:`sensitivity.alip_finite_differences`), > 0.
    """

    def __init__(self, params: AlipParams, fd_step: float = DEFAULT_FD_STEP) -> None:
        if not isinstance(params, AlipParams):
            raise ParameterError(f"params must be an AlipParams, got {type(params).__name__}")
        self.params = params
        self.nlp = AlipNlp(params)
        self.ipopt = IpoptSolver(self.nlp)
        self.kkt = AlipKktRoute(self.nlp)
        self.casadi = AlipCasadiRoute(self.ipopt)
        self.finite_differences = AlipFiniteDifferenceRoute(self.ipopt, fd_step)

    def solve(self, instance: AlipInstance) -> AlipSolution:
        """IPOPT's optimum of ``instance`` (raises AlipSolverError)."""
        return self.ipopt.solve(instance)

    def sensitivity(self, instance: AlipInstance, solution: AlipSolution | None = None) -> AlipSensitivity:
        """Route (a) alone (IPOPT's optimum solved when omitted)."""
        return self.kkt.sensitivity(instance, self.solve(instance) if solution is None else solution)

    def crosscheck(self, instance: AlipInstance) -> AlipCrosscheck:
        """IPOPT's optimum of ``instance``, its active set, the three routes and their disagreement.

        Raises:
            DegenerateSensitivity: route (a)'s LICQ / second-order check fails.
            AlipSolverError: IPOPT failed (at the instance or a perturbed one).
        """
        clock = time.perf_counter
        start = clock()
        solution = self.solve(instance)
        cost = {"ipopt_solve_s": clock() - start}
        active = detect_active_set(self.nlp, instance, solution)
        routes = {}
        start = clock()
        routes["kkt"] = self.kkt.sensitivity(instance, solution, active)
        cost["kkt_s"] = clock() - start
        start = clock()
        routes["casadi"] = self.casadi.sensitivity(instance, solution, active)
        cost["casadi_s"] = clock() - start
        start = clock()
        fd = self.finite_differences.sensitivity(instance, solution, active)
        cost["finite_differences_s"] = clock() - start
        routes["finite_differences"] = fd.sensitivity
        reference = routes["kkt"].dw_dtheta
        disagreement = {name: relative_disagreement(self.nlp, routes[name].dw_dtheta, reference)
                        for name in ("casadi", "finite_differences")}
        finite = np.concatenate([d[np.isfinite(d)] for d in disagreement.values()])
        return AlipCrosscheck(instance=instance, solution=solution, active=active, routes=routes,
                              disagreement=disagreement, max_relative_disagreement=float(np.max(finite)),
                              fd_changes=fd.changes, fd_steps=fd.steps, cost=cost)
