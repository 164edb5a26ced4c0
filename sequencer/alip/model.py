"""ALIP continuous dynamics (seed 001, section 2.3, eqs. 4-6) with Φ(T) and Γ(T) in closed form.

State x = (p_x, L_y, p_y, L_x) relative to the stance contact point, in the stance's heading frame:
p the CoM (x, y) relative to the contact [m], L the angular momentum about the contact [kg·m²/s];
input τ = (τ_y, τ_x), the ankle torques [N·m]. With ω = sqrt(g / z) and m z the "pendulum inertia"::

    ṗ_x =  L_y / (m z),   L̇_y =  m g p_x + τ_y,   ṗ_y = -L_x / (m z),   L̇_x = -m g p_y + τ_x

A² = ω² I, so e^{A T} = cosh(ωT) I + sinh(ωT) A / ω and ∫_0^T e^{A s} ds = sinh(ωT)/ω I + (cosh(ωT) − 1) A / ω²:

    Φ(T) = [[c, s/(m z ω), 0, 0], [m z ω s, c, 0, 0], [0, 0, c, -s/(m z ω)], [0, 0, -m z ω s, c]]
    Γ(T) = [[(c − 1)/(m g), 0], [s/ω, 0], [0, -(c − 1)/(m g)], [0, s/ω]]     (c = cosh ωT, s = sinh ωT)

valid for any real T (T < 0 flows backwards, eq. 17). A constant ankle torque is a constant shift of the
pivot (the CoP): τ_y = -m g c_x, τ_x = m g c_y, so the CoM moves as the LIP about contact + c.

The formulas are written once (:func:`phi_gamma_entries`) over a namespace providing ``sinh``/``cosh``:
:mod:`math` for numbers (the numpy matrices below) and :mod:`casadi` for the NLP's symbols
(:mod:`sequencer.alip.nlp`), so the NLP and the tests share one model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError

STATE_NAMES = ("p_x", "L_y", "p_y", "L_x")
TORQUE_NAMES = ("tau_y", "tau_x")


def phi_gamma_entries(T, omega: float, mz: float, mg: float, fn=math):
    """Entries of Φ(T) (4x4 nested list) and Γ(T) (4x2 nested list); ``fn`` provides sinh and cosh."""
    c, s = fn.cosh(omega * T), fn.sinh(omega * T)
    zero = 0.0 * c
    phi = [[c, s / (mz * omega), zero, zero],
           [mz * omega * s, c, zero, zero],
           [zero, zero, c, -s / (mz * omega)],
           [zero, zero, -mz * omega * s, c]]
    gamma = [[(c - 1.0) / mg, zero], [s / omega, zero], [zero, -(c - 1.0) / mg], [zero, s / omega]]
    return phi, gamma


@dataclass(frozen=True)
class AlipModel:
    """The 3D ALIP of eq. (4): mass m [kg], CoM height z [m] above the contact, gravity g [m/s²]."""

    mass: float
    com_height: float
    gravity: float = 9.81

    def __post_init__(self) -> None:
        for name in ("mass", "com_height", "gravity"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ParameterError(f"{name}={value!r} must be a finite number > 0")
            object.__setattr__(self, name, float(value))

    @property
    def omega(self) -> float:
        """ω = sqrt(g / z) [1/s]."""
        return math.sqrt(self.gravity / self.com_height)

    @property
    def mz(self) -> float:
        """m z [kg·m]: L = m z v for the CoM velocity v at constant height."""
        return self.mass * self.com_height

    @property
    def mg(self) -> float:
        """m g [N]."""
        return self.mass * self.gravity

    @property
    def A(self) -> np.ndarray:
        """A^ALIP of eq. (4), shape (4, 4)."""
        mz, mg = self.mz, self.mg
        return np.array([[0, 1 / mz, 0, 0], [mg, 0, 0, 0], [0, 0, 0, -1 / mz], [0, 0, -mg, 0]], dtype=float)

    @property
    def B(self) -> np.ndarray:
        """B^ALIP of eq. (4), shape (4, 2): τ_y drives L_y, τ_x drives L_x."""
        return np.array([[0, 0], [1, 0], [0, 0], [0, 1]], dtype=float)

    def phi(self, T: float) -> np.ndarray:
        """Φ(T) = e^{A T}, shape (4, 4)."""
        return np.array(phi_gamma_entries(float(T), self.omega, self.mz, self.mg)[0])

    def gamma(self, T: float) -> np.ndarray:
        """Γ(T) = ∫_0^T e^{A (T − s)} ds B, shape (4, 2)."""
        return np.array(phi_gamma_entries(float(T), self.omega, self.mz, self.mg)[1])

    def flow(self, x, tau, T: float) -> np.ndarray:
        """Eq. (6): x(t0 + T) = Φ(T) x(t0) + Γ(T) τ for a constant τ, shape (4,)."""
        phi, gamma = phi_gamma_entries(float(T), self.omega, self.mz, self.mg)
        return np.array(phi) @ np.asarray(x, dtype=float) + np.array(gamma) @ np.asarray(tau, dtype=float)

    def dynamics(self, x, tau) -> np.ndarray:
        """ẋ = A x + B τ (eq. 5), shape (4,)."""
        return self.A @ np.asarray(x, dtype=float) + self.B @ np.asarray(tau, dtype=float)

    def state_from_velocity(self, p_xy, v_xyz, p_z: float | None = None) -> np.ndarray:
        """ALIP state from the CoM position relative to the contact and its velocity (eqs. 14-15 without
        the centroidal I ω terms): L_y = m (p_z v_x − p_x v_z), L_x = m (p_y v_z − p_z v_y); p_z = com_height
        by default. Shape (4,)."""
        p_z = self.com_height if p_z is None else float(p_z)
        px, py = float(p_xy[0]), float(p_xy[1])
        vx, vy, vz = (float(v) for v in v_xyz)
        return np.array([px, self.mass * (p_z * vx - px * vz), py, self.mass * (py * vz - p_z * vy)])

    def impulse_state_change(self, impulse, p_xy=(0.0, 0.0), p_z: float | None = None) -> np.ndarray:
        """Jump of the ALIP state when an impulse Δp [N·s] (shape (2,) horizontal or (3,)) hits the CoM at
        (p_x, p_y, p_z) from the contact (heading frame; p_z = com_height by default), shape (4,).

        The CoM does not move during the impulse and its velocity jumps by Δp / m; L about the contact is
        linear in that velocity (:meth:`state_from_velocity`), so ΔL = r × Δp: ΔL_y = p_z Δp_x − p_x Δp_z,
        ΔL_x = p_y Δp_z − p_z Δp_y. A forward push (Δp_x > 0) raises L_y by z Δp_x, a push to the left
        (Δp_y > 0) lowers L_x by z Δp_y (L_x = −m z v_y).
        """
        impulse = np.asarray(impulse, dtype=float).reshape(-1)
        if impulse.shape not in ((2,), (3,)) or not np.all(np.isfinite(impulse)):
            raise ParameterError(f"impulse={impulse!r} must be 2 or 3 finite numbers [N·s]")
        jump = self.state_from_velocity(p_xy, np.append(impulse, 0.0)[:3] / self.mass, p_z)
        jump[[0, 2]] = 0.0
        return jump

    def cop_offset(self, tau) -> np.ndarray:
        """CoP offset from the contact (c_x, c_y) [m] equivalent to the ankle torque τ = (τ_y, τ_x)."""
        return np.array([-float(tau[0]) / self.mg, float(tau[1]) / self.mg])
