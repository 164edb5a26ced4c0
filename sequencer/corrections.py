"""Online corrections of the sequencer's LIPM: the live swing drift and touchdown offset bias.

The DCM step QP plans with the linear inverted pendulum. Two sagittal corrections, identified
while walking by the controller's estimator, make its nominal DCM offset fit a robot that does
not walk exactly like the LIPM (see :mod:`sequencer.nominal` and docs/sequencer.md):

- ``swing_drift`` κ [-]: forward DCM gain per unit of step length over a stance beyond the LIPM;
  the nominal offset becomes ``b_x = (1 - κ) l_nom / (E - 1)``;
- ``dcm_offset_bias`` [m]: how far ahead of the planned offset b_T,x the DCM is, on average, when
  the foot lands; the offset aimed at is ``b_x - dcm_offset_bias``.

:class:`LipmCorrections` is the one mutable object of the planner's inputs: the estimator owns it
and assigns its fields, the planner reads the live values at every plan (no planner rebuild).
``SequencerParams.swing_drift`` / ``dcm_offset_bias`` are the preset's initial values
(:meth:`LipmCorrections.from_params`).
"""

from __future__ import annotations

import math
import numbers

from wbmpc.errors import ParameterError

SWING_DRIFT_MAX = 0.9
"""Largest swing drift κ [-] a plan accepts (κ -> 1 would cancel the nominal offset)."""

DCM_OFFSET_BIAS_MAX = 0.05
"""Largest |dcm_offset_bias| [m] a plan accepts."""

STANCE_DRIFT_MAX = 0.1
"""Largest |stance_drift| [m] a plan accepts."""


def check_swing_drift(value) -> float:
    """``value`` as a float; ParameterError unless it is a real number in [0, SWING_DRIFT_MAX]."""
    value = _real("swing_drift", value)
    if not 0.0 <= value <= SWING_DRIFT_MAX:
        raise ParameterError(f"swing_drift={value} must be in [0, {SWING_DRIFT_MAX}]")
    return value


def check_stance_drift(value) -> float:
    """``value`` as a float [m]; ParameterError unless |value| <= STANCE_DRIFT_MAX."""
    value = _real("stance_drift", value)
    if not abs(value) <= STANCE_DRIFT_MAX:
        raise ParameterError(f"stance_drift={value} m must be in [-{STANCE_DRIFT_MAX}, {STANCE_DRIFT_MAX}] m")
    return value


def check_dcm_offset_bias(value) -> float:
    """``value`` as a float [m]; ParameterError unless |value| <= DCM_OFFSET_BIAS_MAX."""
    value = _real("dcm_offset_bias", value)
    if not abs(value) <= DCM_OFFSET_BIAS_MAX:
        raise ParameterError(
            f"dcm_offset_bias={value} m must be in [-{DCM_OFFSET_BIAS_MAX}, {DCM_OFFSET_BIAS_MAX}] m"
        )
    return value


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name}={value!r} must be a real number")
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"{name}={value!r} must be finite (no NaN or inf)")
    return value


class LipmCorrections:
    """Live LIPM corrections read by the planner at every plan (validated on assignment).

    Attributes:
        swing_drift: κ in [0, 0.9] [-], 0 = the paper's LIPM.
        dcm_offset_bias: sagittal touchdown offset bias [m], |.| <= 0.05, 0 = none.
        stance_drift: d [m], |.| <= 0.1, forward DCM gain beyond the LIPM over a stance whatever
            the step length (0 = the paper's LIPM); what the walking controller identifies.

    Example::

        corrections = LipmCorrections.from_params(params)   # the preset's initial values
        planner = DcmFootstepPlanner(params, corrections=corrections)
        corrections.swing_drift = 0.2                       # the next plan uses it
    """

    __slots__ = ("_swing_drift", "_dcm_offset_bias", "_stance_drift")

    def __init__(self, swing_drift: float = 0.0, dcm_offset_bias: float = 0.0, stance_drift: float = 0.0) -> None:
        self.swing_drift = swing_drift
        self.dcm_offset_bias = dcm_offset_bias
        self.stance_drift = stance_drift

    @classmethod
    def from_params(cls, params) -> "LipmCorrections":
        """Corrections starting from a SequencerParams' ``swing_drift``, ``dcm_offset_bias`` and
        ``stance_drift``."""
        return cls(params.swing_drift, params.dcm_offset_bias, params.stance_drift)

    @property
    def stance_drift(self) -> float:
        """d [m], forward DCM gain beyond the LIPM over a stance, whatever the step length."""
        return self._stance_drift

    @stance_drift.setter
    def stance_drift(self, value: float) -> None:
        self._stance_drift = check_stance_drift(value)

    @property
    def swing_drift(self) -> float:
        """κ [-], forward DCM gain per unit of step length beyond the LIPM."""
        return self._swing_drift

    @swing_drift.setter
    def swing_drift(self, value: float) -> None:
        self._swing_drift = check_swing_drift(value)

    @property
    def dcm_offset_bias(self) -> float:
        """Measured minus planned sagittal DCM offset at touchdown, aimed off [m]."""
        return self._dcm_offset_bias

    @dcm_offset_bias.setter
    def dcm_offset_bias(self, value: float) -> None:
        self._dcm_offset_bias = check_dcm_offset_bias(value)

    def as_tuple(self) -> tuple[float, float, float]:
        """(swing_drift [-], dcm_offset_bias [m], stance_drift [m])."""
        return (self._swing_drift, self._dcm_offset_bias, self._stance_drift)

    def __repr__(self) -> str:
        return (f"LipmCorrections(swing_drift={self._swing_drift!r}, dcm_offset_bias={self._dcm_offset_bias!r}, "
                f"stance_drift={self._stance_drift!r})")

    def __eq__(self, other) -> bool:
        if not isinstance(other, LipmCorrections):
            return NotImplemented
        return self.as_tuple() == other.as_tuple()

    __hash__ = None  # mutable
