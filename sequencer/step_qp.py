"""One-step footstep QP (Roux et al. 2024, eqs. 2-5) and its exact small-QP solution.

Decision variable (shape (5,)): ``x = (p_T,x, p_T,y, Gamma, b_T,x, b_T,y)`` with ``p_T`` the world
(x, y) of the next foothold [m], ``Gamma = exp(omega T)`` [-] where T is the touchdown time
measured from the start of the current stance [s], and ``b_T = zeta_T - p_T`` the DCM offset at
touchdown [m].

Cost (eq. 3a, exactly as written, so its Hessian is ``2 diag(a1, a1, a2, a3, a3)``)::

    f = a1 |p_T - p0 - (l_nom, w_nom)|^2 + a2 (Gamma - Gamma_nom)^2 + a3 |b_T - b_nom|^2

Inequalities ``g_i(x) >= 0`` in the paper's order (eqs. 4a-4f): step length lower/upper, step
width lower/upper, Gamma lower/upper. Equalities (eq. 5): ``p_T + b_T - p0 - a Gamma = 0`` with
``a = (zeta_hat - p0) exp(-omega t)`` and t the time elapsed since the current stance began.

Lagrange multipliers follow eq. (9): ``grad f - sum_i u_i grad g_i + sum_j w_j grad h_j = 0``
with ``u >= 0``.

Deviation from the paper, documented in docs/sequencer.md: the lower time bound is
``max(T_min, t)`` (a touchdown cannot be planned in the past); if ``t > T_max`` the step is
infeasible and :class:`InfeasibleStep` is raised.

The exact solver eliminates ``b_T`` through the equality, leaving a strictly convex QP in
``(p_T - p0, Gamma)`` with box bounds. For a fixed Gamma the two step coordinates decouple and are
clipped projections; the reduced cost in Gamma is convex piecewise quadratic, with a continuous
piecewise-linear nondecreasing derivative whose root is found exactly among at most 4
breakpoints. No iteration, no tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wbmpc.errors import ParameterError, SolverError

CONSTRAINT_NAMES = (
    "step_length_min",
    "step_length_max",
    "step_width_min",
    "step_width_max",
    "time_min",
    "time_max",
)
VARIABLE_NAMES = ("p_T_x", "p_T_y", "Gamma", "b_T_x", "b_T_y")


class StepQPError(SolverError):
    """The footstep QP could not be solved; carries the problem and the solver status.

    Attributes:
        problem: the :class:`StepProblem` that failed.
        status: the solver's status string (e.g. ``"primal infeasible"``).
        backend: name of the backend that failed.
    """

    def __init__(self, message: str, problem: "StepProblem", status: str, backend: str):
        super().__init__(f"{message} [backend={backend}, status={status}]\n{problem.describe()}")
        self.problem = problem
        self.status = status
        self.backend = backend


class InfeasibleStep(StepQPError):
    """The footstep QP has no feasible point (e.g. the elapsed time t exceeds T_max)."""


@dataclass(frozen=True)
class StepProblem:
    """Data of one footstep QP (eqs. 2-5).

    Attributes:
        stance_foot: ``"left"`` or ``"right"``, the foot on the ground (the other one lands).
        p0: world (x, y) of the stance foot [m], shape (2,).
        dcm_measured: world (x, y) of the measured DCM zeta_hat at the elapsed time [m], shape (2,).
        elapsed: time since the stance began, t [s], >= 0.
        omega: LIPM natural frequency [1/s].
        alpha: (alpha1, alpha2, alpha3) [-], shape (3,).
        step_nominal: (l_nom, w_nom) [m], shape (2,).
        t_nom: nominal step duration [s] (Gamma_nom = exp(omega t_nom)).
        b_nominal: nominal DCM offset at touchdown (b_x,nom, b_y,nom) [m], shape (2,).
        length_bounds: (l_min, l_max) [m]; width_bounds: (w_min, w_max) [m] for this stance.
        time_bounds: (T_min, T_max) [s] of the step duration.
    """

    stance_foot: str
    p0: np.ndarray
    dcm_measured: np.ndarray
    elapsed: float
    omega: float
    alpha: np.ndarray
    step_nominal: np.ndarray
    t_nom: float
    b_nominal: np.ndarray
    length_bounds: tuple[float, float]
    width_bounds: tuple[float, float]
    time_bounds: tuple[float, float]

    def __post_init__(self) -> None:
        for name in ("p0", "dcm_measured", "step_nominal", "b_nominal", "alpha"):
            value = np.asarray(getattr(self, name), dtype=float)
            size = 3 if name == "alpha" else 2
            if value.shape != (size,):
                raise ParameterError(f"{name} has shape {value.shape}, expected ({size},)")
            if not np.all(np.isfinite(value)):
                raise ParameterError(f"{name}={value.tolist()} must be finite (no NaN or inf)")
            object.__setattr__(self, name, value)
        if not (math.isfinite(self.elapsed) and self.elapsed >= 0):
            raise ParameterError(f"elapsed={self.elapsed} s (time since the stance began) must be finite and >= 0")

    @classmethod
    def from_params(
        cls, params, stance_foot: str, p0, dcm_measured, elapsed: float, gait=None
    ) -> "StepProblem":
        """Build the QP of eqs. (2)-(5) for ``params`` (a SequencerParams) and one stance, with the
        nominal step and offset of ``gait`` (a ``sequencer.nominal.NominalGait``; None: the
        parameters' own command and corrections)."""
        gait = params.nominal_gait() if gait is None else gait
        return cls(
            stance_foot=stance_foot,
            p0=np.asarray(p0, dtype=float),
            dcm_measured=np.asarray(dcm_measured, dtype=float),
            elapsed=float(elapsed),
            omega=params.omega,
            alpha=np.array([params.alpha1, params.alpha2, params.alpha3]),
            step_nominal=np.array([gait.step_length, gait.step_width(stance_foot)]),
            t_nom=params.t_nom,
            b_nominal=np.array(gait.dcm_offset(stance_foot)),
            length_bounds=(params.l_min, params.l_max),
            width_bounds=params.width_bounds(stance_foot),
            time_bounds=(params.t_min, params.t_max),
        )

    def with_dcm_disturbance(self, theta) -> "StepProblem":
        """The same problem with zeta_hat + theta (eq. 6), theta shape (2,) [m]."""
        from dataclasses import replace

        return replace(self, dcm_measured=self.dcm_measured + np.asarray(theta, dtype=float))

    # ------------------------------------------------------------------ derived data
    @property
    def decay(self) -> float:
        """exp(-omega t) [-]: the factor multiplying Gamma in eq. (5)."""
        return math.exp(-self.omega * self.elapsed)

    @property
    def dcm_growth(self) -> np.ndarray:
        """a = (zeta_hat - p0) exp(-omega t) [m], shape (2,): zeta_T = p0 + a Gamma."""
        return (self.dcm_measured - self.p0) * self.decay

    @property
    def gamma_nominal(self) -> float:
        """Gamma(T_nom) = exp(omega T_nom) [-]."""
        return math.exp(self.omega * self.t_nom)

    @property
    def gamma_bounds(self) -> tuple[float, float]:
        """(exp(omega max(T_min, t)), exp(omega T_max)) [-]; raises InfeasibleStep if t > T_max."""
        t_min, t_max = self.time_bounds
        if self.elapsed > t_max:
            raise InfeasibleStep(
                f"elapsed time t={self.elapsed:.4g} s exceeds T_max={t_max} s: no touchdown time is feasible",
                self,
                "primal infeasible",
                "none (bound check before any solver)",
            )
        return math.exp(self.omega * max(t_min, self.elapsed)), math.exp(self.omega * t_max)

    def variable_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds on (p_T,x, p_T,y, Gamma), world frame, shapes (3,)."""
        g_lo, g_hi = self.gamma_bounds
        lower = np.array([self.p0[0] + self.length_bounds[0], self.p0[1] + self.width_bounds[0], g_lo])
        upper = np.array([self.p0[0] + self.length_bounds[1], self.p0[1] + self.width_bounds[1], g_hi])
        return lower, upper

    def qp_matrices(self) -> dict[str, np.ndarray]:
        """Dense QP data ``min 1/2 x'Px + q'x  s.t. A x = b, lower <= C x <= upper``.

        Returns a dict with P (5, 5), q (5,), A (2, 5), b (2,), C (3, 5), lower (3,), upper (3,);
        the objective differs from f of eq. (3a) by a constant (see :meth:`objective`).
        """
        a1, a2, a3 = self.alpha
        P = 2.0 * np.diag([a1, a1, a2, a3, a3])
        target_p = self.p0 + self.step_nominal
        q = -2.0 * np.array(
            [a1 * target_p[0], a1 * target_p[1], a2 * self.gamma_nominal, a3 * self.b_nominal[0], a3 * self.b_nominal[1]]
        )
        growth = self.dcm_growth
        A = np.array([[1.0, 0.0, -growth[0], 1.0, 0.0], [0.0, 1.0, -growth[1], 0.0, 1.0]])
        C = np.zeros((3, 5))
        C[0, 0] = C[1, 1] = C[2, 2] = 1.0
        lower, upper = self.variable_bounds()
        return {"P": P, "q": q, "A": A, "b": self.p0.copy(), "C": C, "lower": lower, "upper": upper}

    def objective(self, x: np.ndarray) -> float:
        """f(x) of eq. (3a) [-]."""
        a1, a2, a3 = self.alpha
        step_error = x[:2] - self.p0 - self.step_nominal
        return float(
            a1 * step_error @ step_error
            + a2 * (x[2] - self.gamma_nominal) ** 2
            + a3 * np.sum((x[3:] - self.b_nominal) ** 2)
        )

    def inequalities(self, x: np.ndarray) -> np.ndarray:
        """g(x) of eqs. (4a)-(4f), shape (6,), >= 0 when feasible."""
        g_lo, g_hi = self.gamma_bounds
        d = x[:2] - self.p0
        return np.array(
            [
                d[0] - self.length_bounds[0],
                self.length_bounds[1] - d[0],
                d[1] - self.width_bounds[0],
                self.width_bounds[1] - d[1],
                x[2] - g_lo,
                g_hi - x[2],
            ]
        )

    def equalities(self, x: np.ndarray) -> np.ndarray:
        """h(x) of eq. (5), shape (2,), zero when feasible [m]."""
        return x[:2] + x[3:] - self.p0 - self.dcm_growth * x[2]

    def inequality_jacobian(self) -> np.ndarray:
        """G = (grad g_1 ... grad g_6), shape (5, 6) (constant)."""
        G = np.zeros((5, 6))
        for k in range(3):
            G[k, 2 * k] = 1.0
            G[k, 2 * k + 1] = -1.0
        return G

    def equality_jacobian(self) -> np.ndarray:
        """H = (grad h_1, grad h_2), shape (5, 2)."""
        growth = self.dcm_growth
        return np.array([[1.0, 0.0], [0.0, 1.0], [-growth[0], -growth[1]], [1.0, 0.0], [0.0, 1.0]])

    def describe(self) -> str:
        """Multi-line human-readable dump of the problem data (used in error messages)."""
        return (
            f"StepProblem(stance_foot={self.stance_foot!r}, p0={self.p0.tolist()} m, "
            f"dcm_measured={self.dcm_measured.tolist()} m, elapsed t={self.elapsed:.6g} s, "
            f"omega={self.omega:.6g} 1/s, alpha={self.alpha.tolist()}, step_nominal={self.step_nominal.tolist()} m, "
            f"t_nom={self.t_nom} s, b_nominal={self.b_nominal.tolist()} m, length_bounds={self.length_bounds} m, "
            f"width_bounds={self.width_bounds} m, time_bounds={self.time_bounds} s)"
        )


@dataclass(frozen=True)
class StepSolution:
    """Primal-dual solution of one footstep QP.

    Attributes:
        x: (p_T,x, p_T,y, Gamma, b_T,x, b_T,y), shape (5,) [m, m, -, m, m].
        u: inequality multipliers of eqs. (4a)-(4f), shape (6,), >= 0 (eq. 9 convention).
        w: equality multipliers of eq. (5), shape (2,).
        active: which of the 6 inequalities are active (at their bound), shape (6,) bool.
        duration: touchdown time T = ln(Gamma) / omega since the stance began [s].
        objective: f(x) of eq. (3a) [-].
        backend: name of the solver that produced it; status: its status string.
    """

    x: np.ndarray
    u: np.ndarray
    w: np.ndarray
    active: np.ndarray
    duration: float
    objective: float
    backend: str
    status: str = "solved"
    iterations: int = 0
    extra: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def step_position(self) -> np.ndarray:
        """World (x, y) of the next foothold p_T [m], shape (2,)."""
        return self.x[:2]

    @property
    def gamma(self) -> float:
        """Gamma = exp(omega T) [-]."""
        return float(self.x[2])

    @property
    def dcm_offset(self) -> np.ndarray:
        """b_T = zeta_T - p_T [m], shape (2,)."""
        return self.x[3:]

    @property
    def active_names(self) -> list[str]:
        """Names of the active inequalities (see CONSTRAINT_NAMES)."""
        return [name for name, on in zip(CONSTRAINT_NAMES, self.active) if on]


def multipliers_from_primal(problem: StepProblem, x: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Multipliers (u (6,), w (2,)) of eq. (9) recovered from an exact primal solution.

    Stationarity in b_T gives w = -2 a3 (b_T - b_nom); stationarity in p_T and Gamma gives the
    net bound multiplier of each variable, assigned to the active side (0 if neither is active).
    """
    a1, a2, a3 = problem.alpha
    w = -2.0 * a3 * (x[3:] - problem.b_nominal)
    residual = np.empty(3)
    residual[:2] = 2.0 * a1 * (x[:2] - problem.p0 - problem.step_nominal) + w
    residual[2] = 2.0 * a2 * (x[2] - problem.gamma_nominal) - w @ problem.dcm_growth
    u = np.zeros(6)
    for k in range(3):
        if active[2 * k]:
            u[2 * k] = max(residual[k], 0.0)
        elif active[2 * k + 1]:
            u[2 * k + 1] = max(-residual[k], 0.0)
    return u, w


def solve_exact_scalars(
    p0x: float, p0y: float, ax: float, ay: float,
    a1: float, a2: float, a3: float,
    nx: float, ny: float, gamma_nom: float, bnx: float, bny: float,
    lx_lo: float, lx_hi: float, ly_lo: float, ly_hi: float, g_lo: float, g_hi: float,
) -> tuple[float, float, float, float, float, int]:
    """Exact solution of the eliminated 3-variable QP, on plain floats (the Algorithm 1 fast path).

    Args are the problem data in step-relative form: stance foot (p0x, p0y) [m], DCM growth
    a = (zeta_hat - p0) exp(-omega t) [m], weights, nominal step (nx, ny) [m], Gamma_nom [-],
    nominal offsets (bnx, bny) [m], bounds on p_T - p0 [m] and on Gamma [-].

    Returns:
        (p_T,x, p_T,y, Gamma, b_T,x, b_T,y, active_bits): world footstep [m], Gamma [-], DCM offset
        [m] and a bit mask of active inequalities (bit i <-> g_{i+1}).
    """
    denom = a1 + a3
    cx = (a1 * nx - a3 * bnx) / denom
    cy = (a1 * ny - a3 * bny) / denom
    sx = a3 * ax / denom
    sy = a3 * ay / denom

    def slope(gamma: float) -> float:
        dx = cx + sx * gamma
        dx = lx_lo if dx < lx_lo else (lx_hi if dx > lx_hi else dx)
        dy = cy + sy * gamma
        dy = ly_lo if dy < ly_lo else (ly_hi if dy > ly_hi else dy)
        return 2.0 * (a2 * (gamma - gamma_nom) + a3 * (ax * (ax * gamma - dx - bnx) + ay * (ay * gamma - dy - bny)))

    active = 0
    slope_lo = slope(g_lo)
    if slope_lo >= 0.0:
        gamma = g_lo
        active |= 16
    else:
        slope_hi = slope(g_hi)
        if slope_hi <= 0.0:
            gamma = g_hi
            active |= 32
        else:
            points = [g_lo, g_hi]
            if sx != 0.0:
                for bound in (lx_lo, lx_hi):
                    gb = (bound - cx) / sx
                    if g_lo < gb < g_hi:
                        points.append(gb)
            if sy != 0.0:
                for bound in (ly_lo, ly_hi):
                    gb = (bound - cy) / sy
                    if g_lo < gb < g_hi:
                        points.append(gb)
            points.sort()
            left, s_left = g_lo, slope_lo
            gamma = g_hi
            for right in points[1:]:
                s_right = slope_hi if right == g_hi else slope(right)
                if s_right >= 0.0:
                    # phi' is linear on [left, right]: the root is exact up to rounding
                    gamma = right if s_right == 0.0 else left - s_left * (right - left) / (s_right - s_left)
                    break
                left, s_left = right, s_right
    dx = cx + sx * gamma
    if dx <= lx_lo:
        dx = lx_lo
        active |= 1
    elif dx >= lx_hi:
        dx = lx_hi
        active |= 2
    dy = cy + sy * gamma
    if dy <= ly_lo:
        dy = ly_lo
        active |= 4
    elif dy >= ly_hi:
        dy = ly_hi
        active |= 8
    return p0x + dx, p0y + dy, gamma, ax * gamma - dx, ay * gamma - dy, active


class ExactBackend:
    """Exact active-set solution of the footstep QP (no iterations, no tolerance; the fastest path)."""

    name = "exact"

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve ``problem`` exactly; raises InfeasibleStep if t > T_max."""
        g_lo, g_hi = problem.gamma_bounds
        growth = problem.dcm_growth
        a1, a2, a3 = problem.alpha
        px, py, gamma, bx, by, bits = solve_exact_scalars(
            problem.p0[0], problem.p0[1], growth[0], growth[1], a1, a2, a3,
            problem.step_nominal[0], problem.step_nominal[1], problem.gamma_nominal,
            problem.b_nominal[0], problem.b_nominal[1],
            problem.length_bounds[0], problem.length_bounds[1],
            problem.width_bounds[0], problem.width_bounds[1], g_lo, g_hi,
        )
        x = np.array([px, py, gamma, bx, by])
        active = np.array([(bits >> i) & 1 == 1 for i in range(6)])
        u, w = multipliers_from_primal(problem, x, active)
        return StepSolution(
            x=x, u=u, w=w, active=active, duration=math.log(gamma) / problem.omega,
            objective=problem.objective(x), backend=self.name,
        )


def solution_from_solver(
    problem: StepProblem, x: np.ndarray, y_eq: np.ndarray, z_box: np.ndarray, backend: str, status: str,
    iterations: int, active_tol: float = 1e-7,
) -> StepSolution:
    """Convert a solver's (x, y, z) with the convention ``Px + q + A'y + C'z = 0`` to a StepSolution.

    z_box > 0 means the upper bound is pushing, z_box < 0 the lower one. A bound is reported
    active when x is within ``active_tol`` of it (in the variable's own units).
    """
    lower, upper = problem.variable_bounds()
    u = np.zeros(6)
    active = np.zeros(6, dtype=bool)
    for k in range(3):
        active[2 * k] = x[k] - lower[k] <= active_tol
        active[2 * k + 1] = upper[k] - x[k] <= active_tol
        u[2 * k] = max(-z_box[k], 0.0)
        u[2 * k + 1] = max(z_box[k], 0.0)
    gamma = float(x[2])
    return StepSolution(
        x=np.asarray(x, dtype=float).copy(), u=u, w=np.asarray(y_eq, dtype=float).copy(), active=active,
        duration=math.log(gamma) / problem.omega if gamma > 0 else float("nan"),
        objective=problem.objective(x), backend=backend, status=status, iterations=int(iterations),
    )
