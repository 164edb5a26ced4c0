"""``push``: a lateral push at the base while walking (paper, section IV.B, Figs. 5-6 bottom), and
``yaw_push``: a moment about the vertical on the torso (ALIP paper, seed 001, section 4.2, Fig. 5).

The paper applies 6.3 N along y at the base for 0.1 s (0.63 N·s) at t = 5 s while walking at
0.33 m/s. The force is applied at the base body's centre of mass, in the world frame, through
MuJoCo's ``xfrc_applied``. The base body is the robot description's
(:attr:`robots.description.RobotDescription.base_body`: Bolt's ``base_link``, the G1's ``pelvis``)
unless ``base_body`` names another. The force may reach ``MAX_FORCE``, which covers the G1's push
maps (F_x -600..600 N, F_y 0..400 N: up to 721 N) as well as Bolt's (a few newtons).

A push may also carry a ``moment`` [N·m] about the world z axis (signed, counter-clockwise seen from
above positive), applied to the same body over the same interval through ``xfrc_applied[:, 3:]``: a
pure moment (MuJoCo applies it about the body's centre of mass, no force). ``yaw_push`` is a push with
the ALIP paper's yaw-disturbance defaults: no force, a moment on the ``torso_link`` (the G1's and the
H1's torso; another body by ``base_body``) for 0.05 s while walking at 0.3 m/s. The paper's moments
are 30-150 N·m; ``MAX_MOMENT`` bounds them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.scenarios.base import Scenario, _check_range, register

MAX_FORCE = 1000.0  # [N], largest push magnitude accepted
MAX_MOMENT = 500.0  # [N·m], largest |moment| accepted (the paper's largest: 150 N·m)


@register("push")
@dataclass(frozen=True)
class Push(Scenario):
    """Walk at ``speed`` and push the base with ``force`` [N] along ``direction`` for ``push_duration``."""

    default_duration = 12.0

    speed: float = 0.33  # [m/s]
    force: float = 6.3  # [N], magnitude of the push
    direction: float = 90.0  # [deg], in the ground plane from +x (90 = +y, the paper's push)
    push_time: float = 5.0  # [s], start of the push
    push_duration: float = 0.1  # [s]
    base_body: str | None = None  # MuJoCo body that receives the force; None: the robot's base (RobotDescription.base_body)
    moment: float = 0.0  # [N·m], about the world z axis, counter-clockwise (seen from above) positive

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range("force", self.force, 0.0, MAX_FORCE, "N")
        _check_range("push_time", self.push_time, 0.0, 1e4, "s")
        _check_range("push_duration", self.push_duration, 1e-3, 10.0, "s")
        _check_range("direction", self.direction, -360.0, 360.0, "deg")
        _check_range("moment", self.moment, -MAX_MOMENT, MAX_MOMENT, "N·m")

    @property
    def force_world(self) -> np.ndarray:
        """Push force, world frame [N], shape (3,)."""
        angle = np.deg2rad(self.direction)
        return self.force * np.array([np.cos(angle), np.sin(angle), 0.0])

    @property
    def moment_world(self) -> np.ndarray:
        """Push moment, world frame [N·m], shape (3,): about z only."""
        return np.array([0.0, 0.0, self.moment])

    def setup(self, robot, command_range) -> None:
        object.__setattr__(self, "_body_name", robot.base_body if self.base_body is None else self.base_body)

    def initialize_episode(self, model, data, rng) -> None:
        import mujoco

        name = getattr(self, "_body_name", self.base_body)
        body = -1 if name is None else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        if body < 0:
            names = [model.body(i).name for i in range(model.nbody)]
            raise ValueError(f"base_body={name!r} is not a body of the model (bodies: {names})")
        object.__setattr__(self, "_body_id", body)

    def before_step(self, t: float, model, data) -> None:
        active = self.push_time <= t < self.push_time + self.push_duration - 1e-9
        data.xfrc_applied[self._body_id, :3] = self.force_world if active else 0.0
        data.xfrc_applied[self._body_id, 3:] = self.moment_world if active else 0.0

    def events(self) -> dict[str, float]:
        return {"push_start": self.push_time, "push_end": self.push_time + self.push_duration}


@register("yaw_push")
@dataclass(frozen=True)
class YawPush(Push):
    """Walk at ``speed`` and turn the torso with ``moment`` [N·m] about the world z axis for
    ``push_duration`` (ALIP paper, section 4.2: 30-150 N·m for 0.05 s at 0.3 m/s). The metrics of
    :func:`sim.metrics.yaw_disturbance_metrics` measure the pelvis's yaw after the recovery."""

    default_duration = 8.0

    speed: float = 0.3  # [m/s]
    force: float = 0.0  # [N]: a pure moment
    push_time: float = 4.0  # [s], two seconds of steady walking after the 2 s ramp
    push_duration: float = 0.05  # [s]
    base_body: str | None = "torso_link"  # None: the robot's base (RobotDescription.base_body)
    moment: float = 90.0  # [N·m], the middle of the paper's 30-150 N·m
