"""Parameters of the ALIP step-to-step NMPC (seed 001, eq. 11), frozen and validated; presets in
``sequencer/presets/alip/<robot>.toml`` (the reasons for each value are comments there and in docs/sequencer.md).

Units: m, s, kg, N·m, kg·m²/s. Frames: each step's heading frame (x along the stance's heading, y left).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

from sequencer.alip.model import AlipModel
from wbmpc.config import dataclass_from_table, named_preset, read_toml
from wbmpc.errors import ParameterError

PRESET_DIR = Path(__file__).resolve().parent.parent / "presets" / "alip"
_VECTORS = {"q_x": 4, "r_length": 2, "r_torque": 2}


@dataclass(frozen=True)
class AlipParams:
    """Model, horizon, weights and bounds of the ALIP NMPC.

    Attributes:
        mass: m [kg]; com_height: z [m] (CoM above the contact, held constant); gravity: g [m/s²].
        steps: K, steps in the NMPC horizon (>= 2: the lateral orbit has period 2).
        t_min, t_des, t_max: step period bounds and desired value [s], 0 < t_min <= t_des <= t_max
            (t_min = t_max: fixed timing).
        width_offset: ℓ_y^offset, nominal lateral step magnitude [m] (eq. 13).
        length_min, length_max: bounds of ℓ_x [m] (heading frame of the step).
        width_min, width_max: bounds of the lateral step magnitude away from the stance foot [m]:
            left stance -ℓ_y in [width_min, width_max], right stance ℓ_y in it.
        torque_y_max, torque_x_max: |τ_y|, |τ_x| bounds [N·m].
        position_max: |p_x|, |p_y| bound of the pre-impact states x_1..x_K [m].
        momentum_max: |L_y|, |L_x| bound of the pre-impact states [kg·m²/s].
        q_x: diagonal of Q_x, weights of (p_x, L_y, p_y, L_x) errors [1/m², 1/(kg·m²/s)²].
        r_length: diagonal of R_ℓ [1/m²]; r_period: R_T [1/s²]; r_torque: diagonal of R_τ [1/(N·m)²].
        horizon: the plan handed to the controller is extended by nominal steps (ℓ_des, T_des, τ = 0)
            until a touchdown at or after t + horizon [s].
        double_support: time both feet stay on the ground after a touchdown [s] (0: the ALIP's instantaneous
            transfer; the contact schedule only).
        tolerance: optimality / feasibility tolerance of the SQP fast path (scaled NLP) [-].
        ipopt_tolerance: IPOPT's tolerance [-]; tighter, as an interior point stays ~tol inside active bounds.
        max_iterations: iteration limit of both solvers.
        name: label.
    """

    mass: float = 33.34
    com_height: float = 0.64
    gravity: float = 9.81
    steps: int = 4
    t_min: float = 0.25
    t_des: float = 0.4
    t_max: float = 0.5
    width_offset: float = 0.22
    length_min: float = -0.3
    length_max: float = 0.3
    width_min: float = 0.12
    width_max: float = 0.40
    torque_y_max: float = 15.0
    torque_x_max: float = 5.0
    position_max: float = 0.25
    momentum_max: float = 32.0
    q_x: tuple = (2500.0, 0.9, 2500.0, 0.9)
    r_length: tuple = (100.0, 100.0)
    r_period: float = 100.0
    r_torque: tuple = (0.01, 0.11)
    horizon: float = 2.0
    double_support: float = 0.0
    tolerance: float = 1e-9
    ipopt_tolerance: float = 1e-12
    max_iterations: int = 100
    name: str = "custom"

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            name, value = field.name, getattr(self, field.name)
            if name == "name":
                continue
            if name in _VECTORS:
                try:
                    items = tuple(float(v) for v in value)
                except (TypeError, ValueError):
                    raise ParameterError(f"{name}={value!r} must be {_VECTORS[name]} numbers") from None
                if len(items) != _VECTORS[name] or not all(math.isfinite(v) and v >= 0 for v in items):
                    raise ParameterError(f"{name}={value!r} must be {_VECTORS[name]} finite numbers >= 0")
                object.__setattr__(self, name, items)
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"{name}={value!r} must be a finite real number")
            if name in ("steps", "max_iterations"):
                if int(value) != value or value < (2 if name == "steps" else 1):
                    raise ParameterError(f"{name}={value!r} must be an integer >= {2 if name == 'steps' else 1}")
                object.__setattr__(self, name, int(value))
            else:
                object.__setattr__(self, name, float(value))
        for name in ("mass", "com_height", "gravity", "t_min", "width_offset", "torque_y_max", "torque_x_max",
                     "position_max", "momentum_max", "horizon", "tolerance", "ipopt_tolerance", "r_period"):
            if getattr(self, name) <= 0:
                raise ParameterError(f"{name}={getattr(self, name)} must be > 0")
        if self.t_min > self.t_max:
            raise ParameterError(f"t_min={self.t_min} s must be <= t_max={self.t_max} s")
        if not self.t_min <= self.t_des <= self.t_max:
            raise ParameterError(f"t_des={self.t_des} s must lie within [t_min, t_max] = [{self.t_min}, {self.t_max}] s")
        if self.length_min > self.length_max:
            raise ParameterError(f"length_min={self.length_min} m must be <= length_max={self.length_max} m")
        if not 0 <= self.width_min <= self.width_max:
            raise ParameterError(f"width_min={self.width_min} m must be in [0, width_max={self.width_max} m]")
        if not self.width_min <= self.width_offset <= self.width_max:
            raise ParameterError(f"width_offset={self.width_offset} m must lie within [width_min, width_max] = "
                                 f"[{self.width_min}, {self.width_max}] m")
        if not 0.0 <= self.double_support < self.t_min:
            raise ParameterError(f"double_support={self.double_support} s must be in [0, t_min={self.t_min} s)")
        if not 0.0 <= self.length_max * 0.5 <= self.position_max or not -self.position_max <= self.length_min * 0.5:
            raise ParameterError(f"position_max={self.position_max} m must hold the period-1 orbit of the longest "
                                 f"steps (|length_min|/2, length_max/2 = {-self.length_min / 2}, {self.length_max / 2} m)")

    # ------------------------------------------------------------------ derived
    @property
    def model(self) -> AlipModel:
        """The ALIP of these parameters."""
        return AlipModel(self.mass, self.com_height, self.gravity)

    @property
    def omega(self) -> float:
        """ω = sqrt(g / z) [1/s]."""
        return math.sqrt(self.gravity / self.com_height)

    def velocity_range(self) -> dict[str, tuple[float, float]]:
        """Commands whose desired steps (eqs. 12-13) lie within the step boxes [m/s], heading frame."""
        t, w, w_lo, w_hi = self.t_des, self.width_offset, self.width_min, self.width_max
        # left stance: v_y t - w in [-w_hi, -w_lo]; right stance: v_y t + w in [w_lo, w_hi]
        return {"v_x": (self.length_min / t, self.length_max / t),
                "v_y": (max(w - w_hi, w_lo - w) / t, min(w - w_lo, w_hi - w) / t)}

    def check_velocity(self, v_x: float, v_y: float) -> None:
        """ParameterError naming the component, its value and the range, unless (v_x, v_y) is in velocity_range()."""
        ranges = self.velocity_range()
        for name, value in (("v_x", v_x), ("v_y", v_y)):
            low, high = ranges[name]
            if not low - 1e-12 <= value <= high + 1e-12:
                raise ParameterError(
                    f"{name}={value} m/s puts the desired step (eqs. 12-13, t_des={self.t_des} s) outside the step "
                    f"bounds: {name} must lie within [{low:.4g}, {high:.4g}] m/s"
                )

    def fixed_timing(self, period: float) -> "AlipParams":
        """The same parameters with the step period fixed to ``period`` [s] (t_min = t_des = t_max)."""
        return dataclasses.replace(self, t_min=period, t_des=period, t_max=period)

    # ------------------------------------------------------------------ I/O
    @classmethod
    def from_toml(cls, path: str | Path) -> "AlipParams":
        """Load from a TOML file with one key per field (missing keys keep defaults; unknown keys raise)."""
        return cls.from_dict(read_toml(path, "parameter file"), source=str(path))

    @classmethod
    def from_dict(cls, data: dict, source: str = "dict") -> "AlipParams":
        return dataclass_from_table(cls, data, "ALIP parameter", source)

    @classmethod
    def preset(cls, name: str) -> "AlipParams":
        """``sequencer/presets/alip/<name>.toml`` (e.g. ``"g1"``)."""
        return named_preset(cls, PRESET_DIR, name, "ALIP preset")

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)
