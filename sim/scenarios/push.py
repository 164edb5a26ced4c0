"""``push``: a lateral push at the base while walking (paper, section IV.B, Figs. 5-6 bottom).

The paper applies 6.3 N along y at the base for 0.1 s (0.63 N·s) at t = 5 s while walking at
0.33 m/s. The force is applied at the base body's centre of mass, in the world frame, through
MuJoCo's ``xfrc_applied``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.scenarios.base import Scenario, _check_range, register


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
    base_body: str = "base_link"  # MuJoCo body that receives the force

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range("force", self.force, 0.0, 200.0, "N")
        _check_range("push_time", self.push_time, 0.0, 1e4, "s")
        _check_range("push_duration", self.push_duration, 1e-3, 10.0, "s")
        _check_range("direction", self.direction, -360.0, 360.0, "deg")

    @property
    def force_world(self) -> np.ndarray:
        """Push force, world frame [N], shape (3,)."""
        angle = np.deg2rad(self.direction)
        return self.force * np.array([np.cos(angle), np.sin(angle), 0.0])

    def initialize_episode(self, model, data, rng) -> None:
        import mujoco

        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, self.base_body)
        if body < 0:
            names = [model.body(i).name for i in range(model.nbody)]
            raise ValueError(f"base_body={self.base_body!r} is not a body of the model (bodies: {names})")
        object.__setattr__(self, "_body_id", body)

    def before_step(self, t: float, model, data) -> None:
        active = self.push_time <= t < self.push_time + self.push_duration - 1e-9
        data.xfrc_applied[self._body_id, :3] = self.force_world if active else 0.0

    def events(self) -> dict[str, float]:
        return {"push_start": self.push_time, "push_end": self.push_time + self.push_duration}
