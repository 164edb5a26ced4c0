"""Nominal step and nominal DCM offsets of a periodic LIPM gait (Khadiv et al. 2020, Appendix A).

Conventions: world frame, x forward, y to the LEFT. ``stance_foot`` is the foot on the ground
while the step is planned; the OTHER foot lands at the end of the step, and the DCM offset
``b_T = zeta_T - p_T`` is measured from that landing foot.

Periodic-gait derivation (also checked numerically in ``tests/test_sequencer_nominal.py``): with
step duration T, E = exp(omega T), step widths w_left = -l_p + v_y T (left stance, the right foot
lands on the right) and w_right = +l_p + v_y T, the LIPM DCM obeys
``b_next = b E - w`` at each touchdown. The 2-periodic solution gives, for the step planned from a
LEFT stance (right foot lands)::

    b_y = + l_p / (1 + E) - v_y T / (1 - E)

and the mirror ``- l_p / (1 + E) - v_y T / (1 - E)`` from a RIGHT stance. At touchdown of the
right foot, the DCM is still to the LEFT of the right foot (b_y > 0): it is travelling from the
left foot towards the right one. (Flipping the sign of the l_p term, as one widely copied public
implementation does, makes the nominal gait non-periodic.) Sagittally: ``b_x = L / (E - 1)``.

Swing drift (an extension, off by default): on a robot whose legs carry a large share of its mass
the DCM gains, over each stance, ``kappa * L`` more than the LIPM predicts (the swing leg's
angular momentum; Bolt: kappa ~ 0.2, docs/closed_loop.md). The sagittal step relation becomes
``(1 - kappa) L + b_next = b E`` and the periodic offset ``b_x = (1 - kappa) L / (E - 1)``.

Heading frame: with a turning command every step is planned in the frame of its stance rotated
by the planned heading (see :mod:`sequencer.dcm_planner`); the nominal values here are in that
frame (x along the heading), so they do not depend on the heading. :class:`NominalGait` gathers
them for one velocity command and one set of LIPM corrections.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbmpc.errors import ParameterError

FEET = ("left", "right")


def other_foot(foot: str) -> str:
    """Return ``"right"`` for ``"left"`` and vice versa (raise ParameterError otherwise)."""
    if foot == "left":
        return "right"
    if foot == "right":
        return "left"
    raise ParameterError(f"foot={foot!r} must be 'left' or 'right'")


def stance_sign(stance_foot: str) -> float:
    """+1 for a left stance, -1 for a right stance (the sign of the l_p term in b_y,nom)."""
    if stance_foot == "left":
        return 1.0
    if stance_foot == "right":
        return -1.0
    raise ParameterError(f"stance_foot={stance_foot!r} must be 'left' or 'right'")


def nominal_step_width(pelvis_width: float, v_y: float, t_nom: float, stance_foot: str) -> float:
    """Nominal lateral step ``p_T,y - p_0,y`` [m]: ``-l_p + v_y T`` (left stance), ``+l_p + v_y T`` (right)."""
    return -stance_sign(stance_foot) * pelvis_width + v_y * t_nom


def nominal_dcm_offset(
    omega: float, step_length: float, pelvis_width: float, v_y: float, t_nom: float, stance_foot: str,
    swing_drift: float = 0.0, stance_drift: float = 0.0,
) -> tuple[float, float]:
    """Nominal DCM offset at touchdown ``(b_x, b_y)`` [m], relative to the landing foot.

    The sagittal offset is that of the periodic gait (1 − κ) L + d + b_x = b_x E, E = exp(ω T_nom):
    b_x = ((1 − κ) L − d) / (E − 1), with the LIPM's drift over a stance modelled as κ L + d.

    Args:
        omega: LIPM natural frequency sqrt(g / z_c) [1/s], > 0.
        step_length: nominal step length L_nom = v_x T_nom [m].
        pelvis_width: nominal lateral distance between the feet l_p [m].
        v_y: commanded lateral velocity [m/s] (y to the left).
        t_nom: nominal step duration [s], > 0.
        stance_foot: ``"left"`` or ``"right"``, the foot in stance during the planned step.
        swing_drift: kappa in [0, 1), forward DCM gain per unit of step length beyond the LIPM
            (0: the pure LIPM, the paper's sequencer).
        stance_drift: d [m], forward DCM gain beyond the LIPM over a stance, whatever the step
            length (0: the pure LIPM).
    """
    if not (omega > 0 and t_nom > 0):
        raise ParameterError(f"omega={omega} 1/s and t_nom={t_nom} s must both be > 0")
    if not (0.0 <= swing_drift < 1.0):
        raise ParameterError(f"swing_drift={swing_drift} must be in [0, 1)")
    growth = math.exp(omega * t_nom)
    b_x = ((1.0 - swing_drift) * step_length - stance_drift) / (growth - 1.0)
    b_y = stance_sign(stance_foot) * pelvis_width / (1.0 + growth) - v_y * t_nom / (1.0 - growth)
    return b_x, b_y


def aimed_dcm_offset(
    omega: float, step_length: float, pelvis_width: float, v_y: float, t_nom: float, stance_foot: str,
    swing_drift: float = 0.0, dcm_offset_bias: float = 0.0, stance_drift: float = 0.0,
) -> tuple[float, float]:
    """The DCM offset the step QP aims at [m]: :func:`nominal_dcm_offset` minus ``dcm_offset_bias`` in x.

    ``dcm_offset_bias`` [m] is how far ahead of the planned offset the DCM is, on average, when
    the foot lands; aiming that much short makes the next stance start from the nominal offset.
    """
    b_x, b_y = nominal_dcm_offset(omega, step_length, pelvis_width, v_y, t_nom, stance_foot, swing_drift,
                                  stance_drift)
    return b_x - dcm_offset_bias, b_y


@dataclass(frozen=True, slots=True)
class NominalGait:
    """Nominal step and aimed DCM offset of each stance for one command and one set of LIPM corrections.

    Every value is in the heading frame of the stance (x along the heading, y to the left).

    Attributes:
        v_x, v_y: velocity command [m/s] the gait was computed for.
        swing_drift: κ [-]; dcm_offset_bias, stance_drift: [m] (the LIPM corrections it was
            computed with).
        step_length: l_nom = v_x t_nom [m].
        per_stance: stance foot -> (w_nom [m], (b_x, b_y) [m]): the nominal lateral step
            p_T,y - p_0,y and the aimed DCM offset at the touchdown ending that stance.
    """

    v_x: float
    v_y: float
    swing_drift: float
    dcm_offset_bias: float
    stance_drift: float
    step_length: float
    per_stance: dict

    def step_width(self, stance_foot: str) -> float:
        """Nominal lateral step p_T,y - p_0,y from ``stance_foot`` [m]."""
        return self._stance(stance_foot)[0]

    def dcm_offset(self, stance_foot: str) -> tuple[float, float]:
        """Aimed DCM offset (b_x, b_y) at the touchdown ending a ``stance_foot`` stance [m]."""
        return self._stance(stance_foot)[1]

    def _stance(self, stance_foot: str):
        if stance_foot not in self.per_stance:
            stance_sign(stance_foot)  # raises the one-line error naming the foot
        return self.per_stance[stance_foot]


def nominal_gait(
    omega: float, t_nom: float, pelvis_width: float, v_x: float, v_y: float,
    swing_drift: float = 0.0, dcm_offset_bias: float = 0.0, stance_drift: float = 0.0,
    feet: tuple[str, ...] = FEET,
) -> NominalGait:
    """The :class:`NominalGait` of command (v_x, v_y) [m/s] with LIPM corrections (κ [-], bias [m],
    stance drift [m]).

    Computed with the same operations as ``SequencerParams.l_nom``, ``w_nom`` and ``b_nom``, so a
    gait built from a parameter set's own values equals them bit for bit.
    """
    step_length = v_x * t_nom
    per_stance = {
        foot: (
            nominal_step_width(pelvis_width, v_y, t_nom, foot),
            aimed_dcm_offset(omega, step_length, pelvis_width, v_y, t_nom, foot, swing_drift, dcm_offset_bias,
                             stance_drift),
        )
        for foot in feet
    }
    return NominalGait(v_x, v_y, swing_drift, dcm_offset_bias, stance_drift, step_length, per_stance)
