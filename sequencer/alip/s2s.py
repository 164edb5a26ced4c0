"""Step-to-step maps of the ALIP (seed 001, eqs. 7-9, two printing errors corrected; docs/sequencer.md).

Reset (eq. 7): at the impact ending step k the new stance foot lands at ℓ_k = (ℓ_x, ℓ_y) from the old one
(heading frame of step k); positions are re-expressed about the new contact, angular momentum about the
contact is conserved (equal-height contacts)::

    x⁺_{k+1} = x⁻_k + B_d ℓ_k,     B_d = [[-1, 0], [0, 0], [0, -1], [0, 0]]    (4x2: the paper prints a 4-vector)

S2S map (eq. 8 after eq. 7; the paper's printed eq. 9, Φ(T_k) x_k + Γ(T_k) τ_k + B_d ℓ_k, applies the step
after the flow of the same step, which is not that composition)::

    x⁻_{k+1} = Φ(T_{k+1}) (x⁻_k + B_d ℓ_k) + Γ(T_{k+1}) τ_{k+1}

Turning (an extension, identity without yaw rate): when the stance heading turns by Δψ at the impact the
post-impact state is re-expressed in the new heading frame, x⁺ ← H(Δψ)ᵀ (x⁻ + B_d ℓ), with H(Δψ) the
rotation about z acting on (p_x, p_y) and (L_x, L_y); the ALIP commutes with it.
"""

from __future__ import annotations

import math

import numpy as np

from sequencer.alip.model import AlipModel

B_D = np.array([[-1.0, 0.0], [0.0, 0.0], [0.0, -1.0], [0.0, 0.0]])


def heading_change_entries(dpsi, fn=math):
    """Entries of H(Δψ)ᵀ (4x4 nested list): a state in the old heading frame -> the frame turned by Δψ."""
    c, s = fn.cos(dpsi), fn.sin(dpsi)
    zero = 0.0 * c
    return [[c, zero, s, zero], [zero, c, zero, -s], [-s, zero, c, zero], [zero, s, zero, c]]


def reset(x_minus, step, dpsi: float = 0.0) -> np.ndarray:
    """Eq. (7) (with the heading change Δψ [rad]): post-impact state in the new stance's frame, shape (4,)."""
    x = np.asarray(x_minus, dtype=float) + B_D @ np.asarray(step, dtype=float)
    return x if dpsi == 0.0 else np.array(heading_change_entries(float(dpsi))) @ x


def s2s(model: AlipModel, x_minus, step, period: float, torque, dpsi: float = 0.0) -> np.ndarray:
    """Corrected eq. (9): the pre-impact state of the next step from this step's pre-impact state ``x_minus``,
    the step ``step`` = ℓ_k [m], the next step's ``period`` T_{k+1} [s] and ankle ``torque`` τ_{k+1} [N·m]."""
    return model.flow(reset(x_minus, step, dpsi), torque, period)
