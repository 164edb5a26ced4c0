"""``slip``: a low-friction patch under one foot's path (paper, section IV.C, Fig. 7).

The patch is a thin box (top 1 mm above the floor) added with ``robots.mujoco_model.add_box_geom``,
which gives it contact priority so MuJoCo uses the patch's friction for foot contacts on it.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.scenarios.base import Scenario, _check_range, register
from wbmpc.errors import ParameterError


@register("slip")
@dataclass(frozen=True)
class Slip(Scenario):
    """Walk at ``speed`` across a low-friction patch under the ``side`` foot.

    The default patch spans y in [-0.03, 0.12] m (left): the left foot's track of the ``walk`` gait
    (which settles about 5 cm to the right of the start, footholds near y = 0 and y = -0.1 m), and
    not the right foot's.
    """

    default_duration = 12.0

    speed: float = 0.33  # [m/s]
    friction: float = 0.15  # sliding friction coefficient on the patch (0.14 and below: Bolt falls, seed 0)
    side: str = "left"  # "left" (y > 0) or "right" (y < 0) foot's track
    x_start: float = 1.0  # [m], world x where the patch begins
    length: float = 0.4  # [m], patch length along x
    patch_width: float = 0.15  # [m], along y
    track_offset: float = 0.045  # [m], |y| of the patch centre: covers y in [-0.03, 0.12] m for "left"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.side not in ("left", "right"):
            raise ParameterError(f"side={self.side!r} must be 'left' or 'right'")
        _check_range("friction", self.friction, 0.0, 10.0, "")
        _check_range("length", self.length, 1e-3, 100.0, "m")
        _check_range("patch_width", self.patch_width, 1e-3, 10.0, "m")

    def modify_spec(self, spec, rng) -> None:
        import numpy as np

        from robots.mujoco_model import add_box_geom

        y = self.track_offset if self.side == "left" else -self.track_offset
        add_box_geom(
            spec, "slip_patch", np.array([self.x_start + 0.5 * self.length, y, 0.0]),
            np.array([0.5 * self.length, 0.5 * self.patch_width, 0.001]),
            friction=self.friction, rgba=(0.4, 0.7, 1.0, 1.0),
        )

    def events(self) -> dict[str, float]:
        return {"patch_x_start": self.x_start, "patch_x_end": self.x_start + self.length}
