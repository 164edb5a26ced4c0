"""Route (c) to the ALIP NMPC's sensitivity: central finite differences of re-solved NLPs.

Each parameter θ_j of :data:`sequencer.alip.nlp.SENSITIVITY_PARAMETERS` is moved by ±h_j, h_j = fd_step ·
s_j with s_j its natural unit (1 m, m z kg·m²/s, i.e. 1 m/s of CoM velocity, for L_y and L_x, 1 s, 1 m/s,
1 rad/s: :attr:`sequencer.alip.nlp.AlipNlp.parameter_scale`); the perturbed instance goes through the whole
public path (:meth:`AlipInstance.with_theta`, the NLP's parameters and bounds) and is re-solved by IPOPT
to ``ipopt_tolerance`` (1e-12 on the G1 preset), so this route also checks :meth:`AlipNlp.parameter_jacobian`.
The re-solves start from the base optimum's primal point (clipped to the moved bounds): from the cold start
IPOPT stopped on 2 of 960 perturbed instances (60 random ones, h = 1e-6) with
``Search_Direction_Becomes_Too_Small`` at this tolerance, from the base optimum on none.
Error: truncation O(h²) plus the solves' error (≈ tol / h).

An active-set change within the step is detected (the active bounds of the ± solutions, read by
:func:`~sensitivity.alip_active_set.detect_active_set`, differ from the base's) and reported per parameter:
that column of the central difference is NaN, the one-sided differences (w(θ + h) − w(θ)) / h and
(w(θ) − w(θ − h)) / h are kept, and which bounds entered or left the set on which side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sensitivity.alip_active_set import AlipActiveSet, detect_active_set
from sensitivity.alip_kkt import AlipSensitivity
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import SENSITIVITY_PARAMETERS, AlipInstance, AlipSolution
from wbmpc.errors import ParameterError

DEFAULT_FD_STEP = 1e-6


@dataclass(frozen=True)
class ActiveSetChange:
    """The active set differs within the FD step of one parameter.

    Attributes:
        parameter: name of θ_j; step: h_j (physical units of θ_j).
        plus_entered, plus_left: bounds active at θ + h and not at θ, and the converse.
        minus_entered, minus_left: the same at θ − h.
        forward, backward: one-sided differences of w, shape (n_w,), physical units.
    """

    parameter: str
    step: float
    plus_entered: tuple[str, ...]
    plus_left: tuple[str, ...]
    minus_entered: tuple[str, ...]
    minus_left: tuple[str, ...]
    forward: np.ndarray
    backward: np.ndarray


@dataclass(frozen=True)
class FiniteDifferenceSensitivity:
    """Route (c)'s result: ``sensitivity`` (NaN columns where the active set changed) and ``changes``."""

    sensitivity: AlipSensitivity
    changes: tuple[ActiveSetChange, ...]
    steps: np.ndarray


def check_fd_step(fd_step) -> float:
    """``fd_step`` as a float, or ParameterError naming it (a finite number > 0)."""
    if isinstance(fd_step, bool) or not isinstance(fd_step, (int, float, np.floating)) or not math.isfinite(fd_step) \
            or fd_step <= 0:
        raise ParameterError(f"fd_step={fd_step!r} must be a finite number > 0 (relative to each parameter's unit)")
    return float(fd_step)


class AlipFiniteDifferenceRoute:
    """Route (c) with an :class:`~sequencer.alip.ipopt_.IpoptSolver` (each re-solve started from the base optimum)."""

    name = "finite_differences"

    def __init__(self, ipopt: IpoptSolver, fd_step: float = DEFAULT_FD_STEP) -> None:
        self.ipopt, self.nlp = ipopt, ipopt.nlp
        self.fd_step = check_fd_step(fd_step)

    def sensitivity(self, instance: AlipInstance, solution: AlipSolution,
                    active: AlipActiveSet | None = None) -> FiniteDifferenceSensitivity:
        """Central differences of re-solved NLPs around ``instance`` (``solution`` its optimum).

        Raises:
            ParameterError: a perturbed instance leaves the domain (t_curr < h, a command out of range).
            AlipSolverError: a re-solve failed.
        """
        nlp = self.nlp
        if active is None:
            active = detect_active_set(nlp, instance, solution)
        base = set(active.names)
        theta = instance.theta
        steps = self.fd_step * nlp.parameter_scale
        jacobian = np.empty((nlp.n_w, len(theta)))
        changes = []
        for j, name in enumerate(SENSITIVITY_PARAMETERS):
            sides = {}
            for sign in (1.0, -1.0):
                moved = theta.copy()
                moved[j] += sign * steps[j]
                try:
                    other = instance.with_theta(moved)
                    nlp.parameters(other)  # the command's range
                except ParameterError as err:
                    raise ParameterError(f"fd_step={self.fd_step:g} moves {name} to {moved[j]:.6g}, outside the "
                                         f"instance's domain: {err}") from err
                solved = self.ipopt.solve(other, warm=solution)
                sides[sign] = (solved.w, set(detect_active_set(nlp, other, solved).names))
            (w_plus, a_plus), (w_minus, a_minus) = sides[1.0], sides[-1.0]
            jacobian[:, j] = (w_plus - w_minus) / (2.0 * steps[j])
            if a_plus != base or a_minus != base:
                jacobian[:, j] = np.nan
                changes.append(ActiveSetChange(
                    parameter=name, step=float(steps[j]), plus_entered=tuple(sorted(a_plus - base)),
                    plus_left=tuple(sorted(base - a_plus)), minus_entered=tuple(sorted(a_minus - base)),
                    minus_left=tuple(sorted(base - a_minus)), forward=(w_plus - solution.w) / steps[j],
                    backward=(solution.w - w_minus) / steps[j]))
        result = AlipSensitivity(instance=instance, solution=solution, dw_dtheta=jacobian, active=active,
                                 method=self.name, names=tuple(nlp.names))
        return FiniteDifferenceSensitivity(result, tuple(changes), steps)
