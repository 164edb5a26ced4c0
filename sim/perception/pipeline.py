"""Perception in the closed loop: the rangefinder array read at its rate, the terrain estimate, its log.

The runner (``sim.runner``) builds a :class:`PerceptionPipeline` when the walking preset enables
``[perception]``: :meth:`PerceptionPipeline.add_to_spec` before the model is compiled, then
:meth:`PerceptionPipeline.step` at every tick; between scans the last obstacles hold. Nothing here
reads the scene's ground truth: the scan comes from the sensors and the pose from the measurement.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sequencer.obstacles import Obstacle
from sim.perception.rangefinder import RangefinderArray, add_rangefinders
from sim.perception.terrain import TerrainEstimator
from wbmpc.walking.perception_config import PerceptionConfig

RNG_STREAM = 15  # the perception's generator: np.random.default_rng((seed, RNG_STREAM)), apart from the run's


class PerceptionPipeline:
    """The sensors and the estimator of one run.

    Args:
        model: the compiled ``mujoco.MjModel`` (its spec edited by :meth:`add_to_spec`).
        config: the walking preset's ``[perception]``.
        seed: the run's seed (noise and dropouts draw from their own stream of it).
    """

    def __init__(self, model, config: PerceptionConfig, seed: int) -> None:
        self.config = config
        self.sensor = RangefinderArray(model, config, np.random.default_rng((int(seed), RNG_STREAM)))
        self.estimator = TerrainEstimator(config)
        self.obstacles: tuple[Obstacle, ...] = ()
        self.n_empty_scans = 0

    @staticmethod
    def add_to_spec(spec, config: PerceptionConfig, base_body: str) -> None:
        """Mount the rangefinders of ``config`` on ``base_body`` of ``spec`` (before compiling)."""
        add_rangefinders(spec, config, base_body)

    def step(self, tick: int, t: float, model, data, x_measured: np.ndarray) -> tuple[Obstacle, ...]:
        """Scan when due at simulation tick ``tick`` (time ``t`` [s]) and update the estimate from the
        measured state ``x_measured``; returns the obstacles reported so far (held between scans)."""
        if self.sensor.due(tick):
            scan = self.sensor.scan(t, model, data)
            if scan.n_returns == 0:
                self.n_empty_scans += 1
            self.obstacles = self.estimator.update(scan, x_measured)
        return self.obstacles

    def summary(self) -> dict[str, Any]:
        """What the run's log keeps (JSON-able): the rate, scan and return counts and, per reported
        obstacle, its first report time and its last estimate (world frame, m, rad)."""
        estimator = self.estimator
        return {
            "rate": self.sensor.rate,
            "n_rays": self.config.n_rays,
            "n_scans": self.sensor.n_scans,
            "n_empty_scans": self.n_empty_scans,
            "n_returns": estimator.n_returns,
            "n_dropped_near": estimator.n_dropped_near,
            "ground_level": estimator.ground,
            "detections": [obstacle_record(track.obstacle) | {"first_seen": track.first_seen,
                                                              "n_returns": track.n_returns}
                           for track in estimator.tracks],
        }


def obstacle_record(obstacle: Obstacle) -> dict[str, Any]:
    """An :class:`Obstacle` as plain data: center [x, y] [m], yaw [rad], depth, width, height [m]."""
    return {"center": [float(v) for v in obstacle.center], "yaw": float(obstacle.yaw), "depth": float(obstacle.depth),
            "width": float(obstacle.width), "height": float(obstacle.height)}
