"""The rangefinder array as MuJoCo sensors: sites and ``rangefinder`` sensors on the robot's base.

:func:`add_rangefinders` edits the robot's ``MjSpec`` before it is compiled (one site and one
rangefinder sensor per ray, named ``rangefinder_<k>``); :class:`RangefinderArray` then reads them
at the configured rate and applies the configured faults (Gaussian range noise, per-ray dropouts,
blackouts), all seeded.

MuJoCo computes every sensor at every ``mj_step`` unless sensors are disabled: the array sets
``mjDSBL_SENSOR`` once bound, and a scan enables them for one ``mj_kinematics`` + ``mj_sensorPos``
on the current state (the model has no other sensor; the runner reads the state from ``qpos``).

What a ray sees: MuJoCo's rangefinder hits any geom with a visible colour (visual meshes included,
collision geoms of every group) except those of the body carrying the site, so the robot's own
legs, arms and torso can be hit. The array leaves those returns in the scan, as a real sensor
would; the terrain estimate drops the returns near the robot (``min_ground_distance``).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.perception.layout import quaternion_z_to, ray_directions_base
from sim.perception.scan import Scan
from wbmpc.errors import ParameterError
from wbmpc.walking.perception_config import PerceptionConfig

SENSOR_PREFIX = "rangefinder_"
_SENSOR_FLAG = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
_DATA_DISTANCE = 1 << int(mujoco.mjtRayDataField.mjRAYDATA_DIST)  # the sensor outputs the distance only


def sensor_name(index: int) -> str:
    """Name of the site and of the rangefinder sensor of ray ``index``."""
    return f"{SENSOR_PREFIX}{index}"


def add_rangefinders(spec: mujoco.MjSpec, config: PerceptionConfig, body_name: str) -> None:
    """Add one site and one rangefinder sensor per ray of ``config`` to body ``body_name`` of ``spec``.

    Raises:
        ParameterError: ``spec`` has no body ``body_name``.
    """
    body = spec.body(body_name)
    if body is None:
        raise ParameterError(f"perception: the MuJoCo model has no body {body_name!r} to mount the rangefinders on")
    for k, direction in enumerate(ray_directions_base(config.ray_angles_deg())):
        body.add_site(name=sensor_name(k), pos=list(config.mount_position), quat=list(quaternion_z_to(direction)),
                      size=[0.005, 0.0, 0.0], group=4)
        spec.add_sensor(name=sensor_name(k), type=mujoco.mjtSensor.mjSENS_RANGEFINDER,
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=sensor_name(k), intprm=[_DATA_DISTANCE, 0, 0])


class RangefinderArray:
    """Reads the rangefinders of a compiled model at the configured rate, with the configured faults.

    Args:
        model: the compiled ``mujoco.MjModel`` (built with :func:`add_rangefinders`).
        config: the array's configuration.
        rng: the generator of the noise and dropouts (seeded from the run's seed).

    Attributes:
        period_ticks: simulation ticks between scans, ``round(1 / (rate * timestep))`` (>= 1).
        rate: the rate actually obtained, 1 / (period_ticks * timestep) [Hz] (67 Hz at 1 kHz: 66.7).
    """

    def __init__(self, model: mujoco.MjModel, config: PerceptionConfig, rng: np.random.Generator) -> None:
        self.config, self.rng = config, rng
        self.directions_base = ray_directions_base(config.ray_angles_deg())
        self.origin_base = np.asarray(config.mount_position, dtype=float)
        addresses = []
        for k in range(config.n_rays):
            sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, sensor_name(k))
            if sensor < 0:
                raise ParameterError(f"perception: the MuJoCo model has no sensor {sensor_name(k)!r} "
                                     "(build it with sim.perception.add_rangefinders)")
            addresses.append(int(model.sensor_adr[sensor]))
        self.addresses = np.asarray(addresses)
        dt = float(model.opt.timestep)
        self.period_ticks = max(1, int(round(1.0 / (config.rate * dt))))
        self.rate = 1.0 / (self.period_ticks * dt)
        model.opt.disableflags |= _SENSOR_FLAG  # computed only when scanned (see the module docstring)
        self.last: Scan | None = None
        self.n_scans = 0

    def due(self, tick: int) -> bool:
        """True when a scan is taken at simulation tick ``tick`` (ticks 0, period_ticks, ...)."""
        return tick % self.period_ticks == 0

    def scan(self, t: float, model: mujoco.MjModel, data: mujoco.MjData) -> Scan:
        """Measure every ray on the current state of ``data`` (time ``t`` [s]); the faults applied."""
        model.opt.disableflags &= ~_SENSOR_FLAG
        try:
            mujoco.mj_kinematics(model, data)
            mujoco.mj_sensorPos(model, data)
        finally:
            model.opt.disableflags |= _SENSOR_FLAG
        ranges = np.array(data.sensordata[self.addresses], dtype=float)
        ranges[(ranges < 0.0) | (ranges > self.config.max_range)] = np.nan  # -1: no surface hit
        config = self.config
        if config.noise_std > 0.0:
            ranges += self.rng.normal(0.0, config.noise_std, ranges.shape)
        if config.dropout_probability > 0.0:
            ranges[self.rng.random(ranges.shape) < config.dropout_probability] = np.nan
        if config.in_blackout(t):
            ranges[:] = np.nan
        scan = Scan(t=float(t), ranges=ranges, origin_base=self.origin_base, directions_base=self.directions_base)
        self.last = scan
        self.n_scans += 1
        return scan
