"""The NMPC of seed 001 eq. (11) on the corrected S2S map, one symbolic NLP shared by both solvers.

Indexing: step k = 0..K-1 has period T_k (step 0: from the start of the current stance, so its remaining
time is T_0 − t_curr), ankle torque τ_k (constant over the step) and ends with the pre-impact state
x_{k+1} and the touchdown ℓ_k (heading frame of step k). Decision vector w = (T (K), τ (2K), ℓ (2K),
x_1..x_K (4K)); multiple shooting, as eq. (11) is written::

    min  Σ_k |x_{k+1} − x^des_{k+1}|²_Qx + |ℓ_k − ℓ^des_k|²_Rℓ + R_T (T_k − T_des)² + |τ_k|²_Rτ
    s.t. x_1 = Φ(T_0 − t_curr) x_0 + Γ(T_0 − t_curr) τ_0
         x_{k+1} = Φ(T_k) H(r T_{k−1})ᵀ (x_k + B_d ℓ_{k−1}) + Γ(T_k) τ_k,   k = 1..K−1
         bounds on x_k (k = 1..K), ℓ_k, T_k (T_0 >= t_curr), τ_k

ℓ_{K−1} enters no state of the horizon: its optimum is ℓ^des clipped to its box (kept, as in eq. 11, so the
plan has K footholds). r is the yaw rate; with r = 0 the constraints are the paper's.

Desired values (eqs. 12-13 and the H-LIP orbits with T_SSP = T_des, T_DSP = 0): ℓ^des_x = v_x T_des,
ℓ^des_y = v_y T_des + γ ℓ_y^offset (γ = −1 from a left stance, +1 from a right one); x^des is the
period-2 orbit of the (τ = 0, non-turning) S2S map under those alternating steps: its sagittal part is the
H-LIP period-1 orbit (p⁻ = ℓ_x/2, v⁻ = ω coth(ωT/2) ℓ_x/2) and its lateral part the period-2 orbit; L = m z v
(L_x = −m z v_y), the paper's conversion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from sequencer.alip.model import phi_gamma_entries
from sequencer.alip.params import AlipParams
from sequencer.alip.s2s import B_D, heading_change_entries
from wbmpc.errors import ParameterError, SolverError

FEET = ("left", "right")
#: The instance's continuous data, in the order of :meth:`AlipNlp.parameter_jacobian`'s columns: the measured
#: state x0 (p_x [m], L_y [kg·m²/s], p_y [m], L_x [kg·m²/s]), t_curr [s] and the command (v_x, v_y [m/s], yaw_rate [rad/s]).
SENSITIVITY_PARAMETERS = ("p_x", "L_y", "p_y", "L_x", "t_curr", "v_x", "v_y", "yaw_rate")


class AlipSolverError(SolverError):
    """The ALIP NMPC failed (solver status not a success): carries the instance and the solver's status."""

    def __init__(self, message: str, instance: "AlipInstance", status: str, solver: str) -> None:
        super().__init__(message)
        self.instance, self.status, self.solver = instance, status, solver


def desired_steps(params: AlipParams, v_x: float, v_y: float, stance_foot: str) -> np.ndarray:
    """ℓ^des of eqs. (12)-(13) for the step taken from a ``stance_foot`` stance, shape (2,) [m]."""
    gamma = -1.0 if stance_foot == "left" else 1.0
    return np.array([v_x * params.t_des, v_y * params.t_des + gamma * params.width_offset])


def orbit_from_steps(params: AlipParams, step_left, step_right) -> dict[str, np.ndarray]:
    """Pre-impact states at the end of a left and of a right stance of the period-2 orbit (τ = 0, T = T_des)
    whose steps from a left / right stance are ``step_left`` / ``step_right`` [m], heading frame.

    Linear in the steps: each may be shape (2,) (a step; states shape (4,)) or (2, n) (n columns, e.g. the
    steps' derivatives, giving the states' derivatives, shape (4, n)).
    """
    model = params.model
    phi = np.array(phi_gamma_entries(params.t_des, model.omega, model.mz, model.mg)[0])
    l_left, l_right = B_D @ np.asarray(step_left, dtype=float), B_D @ np.asarray(step_right, dtype=float)
    # x_L = Φ (x_R + B ℓ_R), x_R = Φ (x_L + B ℓ_L)  ->  (I − Φ²) x_L = Φ² B ℓ_L + Φ B ℓ_R
    x_left = np.linalg.solve(np.eye(4) - phi @ phi, phi @ phi @ l_left + phi @ l_right)
    x_right = phi @ (x_left + l_left)
    return {"left": x_left, "right": x_right}


def orbit(params: AlipParams, v_x: float, v_y: float) -> dict[str, np.ndarray]:
    """Desired pre-impact ALIP state at the end of a left and of a right stance (H-LIP orbits), shape (4,) each."""
    return orbit_from_steps(params, *(desired_steps(params, v_x, v_y, foot) for foot in FEET))


@dataclass(frozen=True)
class AlipInstance:
    """One NMPC problem: measured state, time in stance, stance foot and command (validated).

    Attributes:
        x0: measured ALIP state (p_x, L_y, p_y, L_x), current stance's heading frame, shape (4,).
        t_curr: time already spent in the current stance [s], >= 0 (clamped to t_max by the planner).
        stance_foot: "left" or "right".
        v_x, v_y: command [m/s], heading frame; yaw_rate: [rad/s].
    """

    x0: np.ndarray
    t_curr: float
    stance_foot: str
    v_x: float = 0.0
    v_y: float = 0.0
    yaw_rate: float = 0.0

    def __post_init__(self) -> None:
        x0 = np.array(self.x0, dtype=float).reshape(-1)
        if x0.shape != (4,) or not np.all(np.isfinite(x0)):
            raise ParameterError(f"x0={self.x0!r} must be 4 finite numbers (p_x, L_y, p_y, L_x)")
        x0.setflags(write=False)
        object.__setattr__(self, "x0", x0)
        for name in ("t_curr", "v_x", "v_y", "yaw_rate"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
                    or not math.isfinite(value):
                raise ParameterError(f"{name}={value!r} must be a finite real number")
            object.__setattr__(self, name, float(value))
        if self.t_curr < 0:
            raise ParameterError(f"t_curr={self.t_curr} s must be >= 0")
        if self.stance_foot not in FEET:
            raise ParameterError(f"stance_foot={self.stance_foot!r} must be one of {FEET}")

    @property
    def theta(self) -> np.ndarray:
        """The continuous data (x0, t_curr, v_x, v_y, yaw_rate) in the order of :data:`SENSITIVITY_PARAMETERS`, shape (8,)."""
        return np.concatenate([self.x0, [self.t_curr, self.v_x, self.v_y, self.yaw_rate]])

    def with_theta(self, theta) -> "AlipInstance":
        """The same stance foot with the continuous data ``theta`` (shape (8,), see :attr:`theta`), validated."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.shape != (len(SENSITIVITY_PARAMETERS),):
            raise ParameterError(f"theta must have {len(SENSITIVITY_PARAMETERS)} entries {SENSITIVITY_PARAMETERS}, "
                                 f"got shape {theta.shape}")
        return AlipInstance(theta[:4], float(theta[4]), self.stance_foot, *(float(v) for v in theta[5:]))


@dataclass(frozen=True)
class AlipSolution:
    """Optimum of eq. (11). Arrays per step k = 0..K-1 (heading frame of step k).

    Attributes:
        periods: T_k [s], shape (K,) (T_0 counts from the start of the current stance).
        torques: τ_k = (τ_y, τ_x) [N·m], shape (K, 2).
        steps: ℓ_k [m], shape (K, 2).
        states: pre-impact states x_1..x_K, shape (K, 4).
        cost: optimal cost; iterations: solver iterations; solver: name; active: names of active bounds.
        w, lam_w, lam_g: primal and dual solution (warm starts).
    """

    periods: np.ndarray
    torques: np.ndarray
    steps: np.ndarray
    states: np.ndarray
    cost: float
    iterations: int
    solver: str
    active: tuple[str, ...]
    w: np.ndarray
    lam_w: np.ndarray
    lam_g: np.ndarray


class AlipNlp:
    """The symbolic NLP of eq. (11) for one parameter set, and its numeric data per instance.

    ``nlp`` (x, p, f, g) is what both solvers are built on; :meth:`parameters` and :meth:`bounds` give an
    instance's p and (lbw, ubw), :meth:`parameter_jacobian` their derivatives in the instance's data (the
    sensitivity routes of ``sensitivity/alip_*.py``); :meth:`initial_guess` a consistent cold start;
    :meth:`solution` unpacks. ``scale`` (n_w,) maps the scaled decision vector to physical units,
    ``parameter_scale`` (8,) gives each of :data:`SENSITIVITY_PARAMETERS` its natural unit.
    """

    def __init__(self, params: AlipParams) -> None:
        if not isinstance(params, AlipParams):
            raise ParameterError(f"params must be an AlipParams, got {type(params).__name__}")
        self.params = params
        K = params.steps
        self.K = K
        model = params.model
        omega, mz, mg = model.omega, model.mz, model.mg
        # decision variables are scaled to metres, seconds and m/s: L / (m z) and τ / (m g) (the CoP offset)
        self.scale = np.concatenate([np.ones(K), np.tile([mg, mg], K), np.ones(2 * K), np.tile([1.0, mz, 1.0, mz], K)])
        # the natural unit of each of SENSITIVITY_PARAMETERS (the same scaling: L in m z · 1 m/s)
        self.parameter_scale = np.array([1.0, mz, 1.0, mz, 1.0, 1.0, 1.0, 1.0])
        w_scaled = ca.SX.sym("w", 9 * K)
        w = w_scaled * ca.DM(self.scale)
        T = w[0:K]
        tau = ca.reshape(w[K:3 * K], 2, K)
        ell = ca.reshape(w[3 * K:5 * K], 2, K)
        x = ca.reshape(w[5 * K:9 * K], 4, K)
        p = ca.SX.sym("p", 4 + 1 + 1 + 2 * K + 4 * K)
        x0, t_curr, rate = p[0:4], p[4], p[5]
        ell_des = ca.reshape(p[6:6 + 2 * K], 2, K)
        x_des = ca.reshape(p[6 + 2 * K:], 4, K)
        bd = ca.DM(B_D)

        def flow(state, torque, duration):
            phi, gamma = phi_gamma_entries(duration, omega, mz, mg, ca)
            return ca.mtimes(ca.blockcat(phi), state) + ca.mtimes(ca.blockcat(gamma), torque)

        g = [x[:, 0] - flow(x0, tau[:, 0], T[0] - t_curr)]
        for k in range(1, K):
            post = ca.mtimes(ca.blockcat(heading_change_entries(rate * T[k - 1], ca)), x[:, k - 1] + ca.mtimes(bd, ell[:, k - 1]))
            g.append(x[:, k] - flow(post, tau[:, k], T[k]))
        qx, rl, rt = ca.DM(params.q_x), ca.DM(params.r_length), ca.DM(params.r_torque)
        f = 0
        for k in range(K):
            dx, dl = x[:, k] - x_des[:, k], ell[:, k] - ell_des[:, k]
            f += ca.dot(qx, dx * dx) + ca.dot(rl, dl * dl) + params.r_period * (T[k] - params.t_des) ** 2 \
                + ca.dot(rt, tau[:, k] * tau[:, k])
        self.nlp = {"x": w_scaled, "p": p, "f": f, "g": ca.vertcat(*g)}
        self.n_w, self.n_g = 9 * K, 4 * K
        self.names = ([f"T_{k}" for k in range(K)] + [f"{n}_{k}" for k in range(K) for n in ("tau_y", "tau_x")]
                      + [f"{n}_{k}" for k in range(K) for n in ("l_x", "l_y")]
                      + [f"{n}_{k + 1}" for k in range(K) for n in ("p_x", "L_y", "p_y", "L_x")])
        self._orbits: dict = {}

    # ------------------------------------------------------------------ instance data
    def stance_sequence(self, stance_foot: str) -> list[str]:
        """Stance foot of steps 0..K-1."""
        other = {"left": "right", "right": "left"}
        feet = [stance_foot]
        for _ in range(self.K - 1):
            feet.append(other[feet[-1]])
        return feet

    def desired(self, instance: AlipInstance) -> tuple[np.ndarray, np.ndarray]:
        """(ℓ^des shape (K, 2), x^des shape (K, 4)) of the instance."""
        key = (instance.v_x, instance.v_y)
        if key not in self._orbits:
            self.params.check_velocity(*key)
            self._orbits = {key: orbit(self.params, *key)}
        orbits = self._orbits[key]
        feet = self.stance_sequence(instance.stance_foot)
        ell = np.array([desired_steps(self.params, instance.v_x, instance.v_y, foot) for foot in feet])
        return ell, np.array([orbits[foot] for foot in feet])

    def parameters(self, instance: AlipInstance) -> np.ndarray:
        """The NLP's p for the instance (t_curr clamped to t_max)."""
        ell, x_des = self.desired(instance)
        t_curr = min(instance.t_curr, self.params.t_max)
        return np.concatenate([instance.x0, [t_curr, instance.yaw_rate], ell.ravel(), x_des.ravel()])

    def bounds(self, instance: AlipInstance) -> tuple[np.ndarray, np.ndarray]:
        """(lbw, ubw) of the instance: boxes of eq. (11), T_0 >= t_curr, widths by stance foot."""
        params, K = self.params, self.K
        lb, ub = np.empty(self.n_w), np.empty(self.n_w)
        lb[:K], ub[:K] = params.t_min, params.t_max
        lb[0] = max(params.t_min, min(instance.t_curr, params.t_max))
        lb[K:3 * K] = np.tile([-params.torque_y_max, -params.torque_x_max], K)
        ub[K:3 * K] = -lb[K:3 * K]
        for k, foot in enumerate(self.stance_sequence(instance.stance_foot)):
            i = 3 * K + 2 * k
            lb[i], ub[i] = params.length_min, params.length_max
            if foot == "left":
                lb[i + 1], ub[i + 1] = -params.width_max, -params.width_min
            else:
                lb[i + 1], ub[i + 1] = params.width_min, params.width_max
        box = np.tile([params.position_max, params.momentum_max], 2 * K)
        lb[5 * K:], ub[5 * K:] = -box, box
        return lb, ub

    def parameter_jacobian(self, instance: AlipInstance) -> tuple[np.ndarray, np.ndarray]:
        """Derivatives of :meth:`parameters` and :meth:`bounds` with respect to the instance's continuous data
        θ = :data:`SENSITIVITY_PARAMETERS` (x0 (4), t_curr [s], v_x, v_y [m/s], yaw_rate [rad/s]).

        p is affine in θ: x0 and the yaw rate enter as they are, t_curr too below t_max (its clamp; at or
        above t_max the derivative is 0), (v_x, v_y) through ℓ^des (∂ℓ^des/∂v = T_des I) and x^des
        (:func:`orbit_from_steps` of those columns, the orbit being linear in the steps). Of the bounds only
        T_0's lower one, max(t_min, min(t_curr, t_max)), moves: with slope 1 for t_min < t_curr < t_max (at the
        kinks t_curr = t_min, t_max the right derivative, 1 and 0).

        Returns:
            (dp/dθ shape (n_p, 8), d lbw/dθ shape (n_w, 8)), physical units; ubw does not depend on θ.
        """
        self.parameters(instance)  # validates the command
        K, params = self.K, self.params
        dp = np.zeros((6 + 6 * K, len(SENSITIVITY_PARAMETERS)))
        dp[0:4, 0:4] = np.eye(4)
        dp[4, 4] = 1.0 if instance.t_curr < params.t_max else 0.0
        dp[5, 7] = 1.0
        dstep = params.t_des * np.eye(2)  # ∂ℓ^des/∂(v_x, v_y), either stance
        dorbit = orbit_from_steps(params, dstep, dstep)
        for k, foot in enumerate(self.stance_sequence(instance.stance_foot)):
            dp[6 + 2 * k:8 + 2 * k, 5:7] = dstep
            dp[6 + 2 * K + 4 * k:10 + 2 * K + 4 * k, 5:7] = dorbit[foot]
        dlb = np.zeros((self.n_w, len(SENSITIVITY_PARAMETERS)))
        dlb[0, 4] = 1.0 if params.t_min <= instance.t_curr < params.t_max else 0.0
        return dp, dlb

    def scaled_bounds(self, instance: AlipInstance) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`bounds` in the NLP's scaled variables."""
        lb, ub = self.bounds(instance)
        return lb / self.scale, ub / self.scale

    def initial_guess(self, instance: AlipInstance) -> np.ndarray:
        """Cold start: T = T_des (within the bounds), τ = 0, ℓ = ℓ^des and x = x^des (the orbit), clipped."""
        K = self.K
        ell, x_des = self.desired(instance)
        lb, ub = self.bounds(instance)
        T = np.full(K, self.params.t_des)
        return np.clip(np.concatenate([T, np.zeros(2 * K), ell.ravel(), x_des.ravel()]), lb, ub)

    def solution(self, w_scaled, lam_w, lam_g, cost: float, iterations: int, solver: str, instance: AlipInstance,
                 active_tol: float = 1e-7) -> AlipSolution:
        """Unpack the NLP's (scaled) primal-dual solution; ``w`` of the result is in physical units."""
        K = self.K
        w = np.asarray(w_scaled, dtype=float).ravel() * self.scale
        lb, ub = self.bounds(instance)
        scale = np.maximum(1.0, np.abs(ub - lb))
        active = tuple(name + (":lower" if w[i] - lb[i] < ub[i] - w[i] else ":upper")
                       for i, name in enumerate(self.names)
                       if min(w[i] - lb[i], ub[i] - w[i]) <= active_tol * scale[i])
        return AlipSolution(
            periods=w[:K].copy(), torques=w[K:3 * K].reshape(K, 2).copy(), steps=w[3 * K:5 * K].reshape(K, 2).copy(),
            states=w[5 * K:].reshape(K, 4).copy(), cost=float(cost), iterations=int(iterations), solver=solver,
            active=active, w=w.copy(), lam_w=np.asarray(lam_w, dtype=float).ravel().copy(),
            lam_g=np.asarray(lam_g, dtype=float).ravel().copy(),
        )
