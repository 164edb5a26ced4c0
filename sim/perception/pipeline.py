"""Perception in the closed loop: the rangefinder array read at its rate, the terrain estimate, its log.

The runner (``sim.runner``) builds a :class:`PerceptionPipeline` when the walking preset enables
``[perception]``: :meth:`PerceptionPipeline.add_to_spec` before the model is compiled, then
:meth:`PerceptionPipeline.step` at every tick; between scans the last obstacles hold. Nothing here
reads the scene's ground truth: the scan comes from the sensors, the pose and the legs (the self
filter, :class:`LegSegments`) from the measurement.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from sequencer.obstacles import Obstacle
from sim.perception.rangefinder import RangefinderArray, add_rangefinders
from sim.perception.terrain import TerrainEstimator
from wbmpc.jsonable import to_jsonable
from wbmpc.walking.perception_config import PerceptionConfig

RNG_STREAM = 15  # the perception's generator: np.random.default_rng((seed, RNG_STREAM)), apart from the run's


class LegSegments:
    """The robot's legs as segments, world frame, from a configuration (the estimator's self filter).

    Each leg is the chain of joint origins from the base to its foot frame's joint, then to the sole
    frame, plus the sole from heel to toe (``robot.sole_size`` length along the sole's x; a point foot:
    the foot frame alone).

    Args:
        robot: the :class:`robots.description.RobotDescription`.
    """

    def __init__(self, robot) -> None:
        self.model = robot.pinocchio_model
        self.data = self.model.createData()
        self.chains, self.frames = [], []
        for frame_name in robot.foot_frames.values():
            frame_id = self.model.getFrameId(frame_name)
            joints, joint = [], self.model.frames[frame_id].parentJoint
            while joint > 0:
                joints.append(joint)
                joint = self.model.parents[joint]
            self.chains.append(joints[::-1])  # from the base's joint down to the foot's
            self.frames.append(frame_id)
        sole = getattr(robot, "sole_size", None)
        self.half_sole = 0.0 if sole is None else 0.5 * float(sole[0])

    def segments(self, q: np.ndarray) -> np.ndarray:
        """Segments (k, 2, 3) [m], world frame, at configuration ``q`` (Pinocchio convention)."""
        pin.forwardKinematics(self.model, self.data, q)
        out = []
        for joints, frame_id in zip(self.chains, self.frames):
            points = [self.data.oMi[j].translation.copy() for j in joints]
            foot = pin.updateFramePlacement(self.model, self.data, frame_id)
            points.append(foot.translation.copy())
            out.extend(zip(points[:-1], points[1:]))
            heel_to_toe = foot.rotation[:, 0] * self.half_sole
            out.append((foot.translation - heel_to_toe, foot.translation + heel_to_toe))
        return np.array(out)


class PerceptionPipeline:
    """The sensors and the estimator of one run.

    Args:
        model: the compiled ``mujoco.MjModel`` (its spec edited by :meth:`add_to_spec`).
        config: the walking preset's ``[perception]``.
        seed: the run's seed (noise and dropouts draw from their own stream of it).
        robot: the run's :class:`robots.description.RobotDescription`, for the self filter
            (``self_filter_radius``; None: no self filter).
    """

    def __init__(self, model, config: PerceptionConfig, seed: int, robot=None) -> None:
        self.config = config
        self.sensor = RangefinderArray(model, config, np.random.default_rng((int(seed), RNG_STREAM)))
        self.estimator = TerrainEstimator(config)
        self.legs = LegSegments(robot) if robot is not None and config.self_filter_radius > 0 else None
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
            x = np.asarray(x_measured, dtype=float)
            segments = None if self.legs is None else self.legs.segments(x[: self.legs.model.nq])
            self.obstacles = self.estimator.update(scan, x, segments)
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
            "detections": [to_jsonable(track.obstacle) | {"first_seen": track.first_seen,
                                                          "n_returns": track.n_returns}
                           for track in estimator.tracks],
        }

