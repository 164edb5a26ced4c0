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

    The patch is centred on ``track_y``; by default on the ``side`` foot's track of the robot's
    default ``walk`` gait where it was measured (``MEASURED_TRACKS``): Bolt's (seed 0) settles
    about 13 cm to the right of its start during the first steps, left footholds near
    y = -0.085 m, right ones near y = -0.168 m; the default width, 7 cm, covers its left track and
    not the right one (4 cm apart). For a robot without measured tracks (G1) the default is the
    foot's y in the reference posture (its feet 24 cm apart: a 7 cm patch lies under one only).
    Before :meth:`setup` (no robot yet) the defaults are the paper's robot's, Bolt's.
    """

    default_duration = 12.0

    speed: float = 0.33  # [m/s]
    friction: float = 0.15  # sliding friction coefficient on the patch (seed 0: 0.12 walks, 0.10 falls)
    side: str = "left"  # "left" (y > 0) or "right" (y < 0) foot's track
    x_start: float = 1.0  # [m], world x where the patch begins
    length: float = 0.4  # [m], patch length along x
    patch_width: float = 0.07  # [m], along y
    track_y: float | None = None  # [m], world y of the patch centre; None: DEFAULT_TRACKS[side]

    MEASURED_TRACKS = {"bolt": {"left": -0.085, "right": -0.168}}  # [m], footholds' y of each robot's walk gait
    DEFAULT_TRACKS = MEASURED_TRACKS["bolt"]  # before setup: the paper's robot

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.side not in ("left", "right"):
            raise ParameterError(f"side={self.side!r} must be 'left' or 'right'")
        _check_range("friction", self.friction, 0.0, 10.0, "")
        _check_range("length", self.length, 1e-3, 100.0, "m")
        _check_range("patch_width", self.patch_width, 1e-3, 10.0, "m")
        if self.track_y is not None:
            _check_range("track_y", self.track_y, -100.0, 100.0, "m")
        self._set_tracks(self.DEFAULT_TRACKS)

    def _set_tracks(self, tracks) -> None:
        object.__setattr__(self, "tracks", dict(tracks))  # {side: y [m]} of the run's robot, not a parameter

    def setup(self, robot, command_range) -> None:
        reference = {side: float(p[1]) for side, p in robot.foot_positions_reference().items()}
        self._set_tracks(self.MEASURED_TRACKS.get(robot.name, reference))

    def modify_spec(self, spec, rng) -> None:
        import numpy as np

        from robots.mujoco_model import add_box_geom

        y = self.tracks[self.side] if self.track_y is None else self.track_y
        add_box_geom(
            spec, "slip_patch", np.array([self.x_start + 0.5 * self.length, y, 0.0]),
            np.array([0.5 * self.length, 0.5 * self.patch_width, 0.001]),
            friction=self.friction, rgba=(0.4, 0.7, 1.0, 1.0),
        )

    def events(self) -> dict[str, float]:
        return {"patch_x_start": self.x_start, "patch_x_end": self.x_start + self.length}
