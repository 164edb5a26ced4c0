"""The rangefinder perception of a walking preset (optional section ``[perception]``).

A robot's walking preset may carry a ``[perception]`` section: the layout of a rangefinder array on
the robot's base (the floating-base body, Pinocchio's first joint), its rate, range and faults, and
the numbers of the terrain estimate that turns its returns into obstacles. The simulation
(``sim.perception``) builds the MuJoCo sensors from it and fills
:attr:`wbmpc.walking.measurement.Measurement.obstacles`; this module only holds and checks the
numbers (the walking layer imports no simulation).

Rays: one per (pitch, yaw) pair of ``pitch_deg`` x ``yaw_deg``, all from ``mount_position``. In the
base frame (x forward, y left, z up) a ray of pitch p (down from the horizontal) and yaw y (to the
left of x) has the unit direction (cos p cos y, cos p sin y, -sin p).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbmpc.errors import ParameterError

OBSTACLE_AXES = ("heading", "near_edge")  # the values of PerceptionConfig.obstacle_axis


def _number(name: str, value, low: float, high: float, unit: str, low_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"perception.{name}={value!r} must be a number [{unit}]")
    value = float(value)
    below = value <= low if low_open else value < low
    if not math.isfinite(value) or below or value > high:
        interval = f"{'(' if low_open else '['}{low}, {high}]"
        raise ParameterError(f"perception.{name}={value} {unit} must be in {interval} {unit}".replace("  ", " "))
    return value


def _angles(name: str, value, low: float, high: float) -> tuple[float, ...]:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = (value,)
    try:
        angles = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise ParameterError(f"perception.{name}={value!r} must be a list of angles [deg]") from None
    if not angles or not all(math.isfinite(a) and low <= a <= high for a in angles):
        raise ParameterError(f"perception.{name}={value!r} must be a non-empty list of angles in [{low}, {high}] deg")
    if len(set(angles)) != len(angles):
        raise ParameterError(f"perception.{name}={value!r} holds duplicates")
    return angles


def _intervals(name: str, value) -> tuple[tuple[float, float], ...]:
    try:
        intervals = tuple((float(a), float(b)) for a, b in value)
    except (TypeError, ValueError):
        raise ParameterError(f"perception.{name}={value!r} must be a list of [start, end] times [s]") from None
    for start, end in intervals:
        if not (math.isfinite(start) and math.isfinite(end) and 0.0 <= start < end):
            raise ParameterError(f"perception.{name}: [{start}, {end}] must be finite times with 0 <= start < end [s]")
    return intervals


@dataclass(frozen=True)
class PerceptionConfig:
    """Rangefinder array and terrain estimate of a walking preset (section ``[perception]``).

    Sensor (``sim.perception.rangefinder``):
        enabled: read the sensors and report obstacles (False: as without the section).
        mount_position: origin of every ray in the base frame [m], shape (3,).
        pitch_deg: ray pitches below the horizontal [deg], each in [0, 90].
        yaw_deg: ray yaws to the left of the base x axis [deg], each in [-90, 90].
        rate: scan rate [Hz]; the scan is taken every ``round(1 / (rate * dt))`` simulation ticks
            and holds between scans.
        max_range: a return farther than this is no return [m].
        noise_std: standard deviation of the Gaussian noise on each range [m] (seeded by the run seed).
        dropout_probability: probability that a ray returns nothing in a scan [-] (seeded).
        blackouts: time intervals [[start, end], ...] [s] during which every ray returns nothing
            (an injected sensor fault).

    Terrain estimate (``sim.perception.terrain``):
        min_ground_distance: returns closer than this to the measured base, horizontally, are
            dropped [m]: they may be the robot's own legs (a knee raised to step over a box is hit
            0.41 m ahead of the H1's pelvis), which would read as obstacles.
        self_filter_radius: returns closer than this to the robot's legs are dropped [m]: the
            segments joining the joints of each leg, from the base to the sole, and the sole from
            heel to toe, placed by the *measured* configuration (0: no such filter).
        cell_size: side of the height map's square cells, world frame [m].
        obstacle_min_height: a cell whose mean return height is this much above the ground level is
            an obstacle cell [m].
        min_cell_returns: returns a cell needs before it can be an obstacle cell [-] (its mean height
            averages the range noise: with noise a cell of one return above the threshold is
            likelier noise than an obstacle).
        cluster_gap: obstacle cells closer than this (centre to centre) belong to one obstacle [m].
        min_returns: returns an obstacle needs, summed over its cells, to be reported [-].
        ground_radius: the ground level is the median height of the non-obstacle cells within this
            horizontal distance of the base [m].
        obstacle_axis: how a reported obstacle's depth axis (``Obstacle.yaw``, world frame) is chosen:
            ``"heading"``, the robot's measured base heading when the obstacle was first reported (the
            box's own orientation is not estimated); ``"near_edge"``, the normal of the box's near edge
            (the face toward the robot) fitted to the obstacle cells' returns, refitted at every
            re-estimate, the heading when the fit is not trusted (``sim.perception.terrain``,
            :func:`~sim.perception.terrain.near_edge_yaw`).
    """

    enabled: bool = True
    mount_position: tuple[float, float, float] = (0.15, 0.0, 0.0)
    pitch_deg: tuple[float, ...] = tuple(20.0 + 2.5 * k for k in range(17))  # 20, 22.5, ..., 60
    yaw_deg: tuple[float, ...] = (-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 15.0)
    rate: float = 67.0
    max_range: float = 4.0
    noise_std: float = 0.0
    dropout_probability: float = 0.0
    blackouts: tuple[tuple[float, float], ...] = ()
    min_ground_distance: float = 0.6
    self_filter_radius: float = 0.12
    cell_size: float = 0.02
    obstacle_min_height: float = 0.04
    min_cell_returns: int = 2
    cluster_gap: float = 0.3
    min_returns: int = 12
    ground_radius: float = 3.0
    obstacle_axis: str = "heading"

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ParameterError(f"perception.enabled={self.enabled!r} must be true or false")
        try:
            mount = tuple(float(v) for v in self.mount_position)
        except (TypeError, ValueError):
            mount = ()
        if len(mount) != 3 or not all(map(math.isfinite, mount)):
            raise ParameterError(f"perception.mount_position={self.mount_position!r} must be 3 finite numbers [m]")
        object.__setattr__(self, "mount_position", mount)
        object.__setattr__(self, "pitch_deg", _angles("pitch_deg", self.pitch_deg, 0.0, 90.0))
        object.__setattr__(self, "yaw_deg", _angles("yaw_deg", self.yaw_deg, -90.0, 90.0))
        object.__setattr__(self, "rate", _number("rate", self.rate, 0.0, 1000.0, "Hz", low_open=True))
        object.__setattr__(self, "max_range", _number("max_range", self.max_range, 0.0, 100.0, "m", low_open=True))
        object.__setattr__(self, "noise_std", _number("noise_std", self.noise_std, 0.0, 1.0, "m"))
        object.__setattr__(self, "dropout_probability",
                           _number("dropout_probability", self.dropout_probability, 0.0, 1.0, "-"))
        object.__setattr__(self, "blackouts", _intervals("blackouts", self.blackouts))
        object.__setattr__(self, "min_ground_distance",
                           _number("min_ground_distance", self.min_ground_distance, 0.0, 10.0, "m"))
        object.__setattr__(self, "self_filter_radius",
                           _number("self_filter_radius", self.self_filter_radius, 0.0, 1.0, "m"))
        object.__setattr__(self, "cell_size", _number("cell_size", self.cell_size, 0.001, 1.0, "m"))
        object.__setattr__(self, "obstacle_min_height",
                           _number("obstacle_min_height", self.obstacle_min_height, 0.0, 1.0, "m", low_open=True))
        object.__setattr__(self, "cluster_gap", _number("cluster_gap", self.cluster_gap, 0.0, 5.0, "m", low_open=True))
        for name in ("min_returns", "min_cell_returns"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ParameterError(f"perception.{name}={value!r} must be an integer >= 1")
        object.__setattr__(self, "ground_radius",
                           _number("ground_radius", self.ground_radius, 0.0, 100.0, "m", low_open=True))
        if self.obstacle_axis not in OBSTACLE_AXES:
            raise ParameterError(f"perception.obstacle_axis={self.obstacle_axis!r} must be one of {OBSTACLE_AXES}")
        if self.min_ground_distance >= self.max_range:
            raise ParameterError(f"perception.min_ground_distance={self.min_ground_distance} m must be below "
                                 f"max_range={self.max_range} m")

    @property
    def n_rays(self) -> int:
        """Number of rays (len(pitch_deg) x len(yaw_deg))."""
        return len(self.pitch_deg) * len(self.yaw_deg)

    def ray_angles_deg(self) -> tuple[tuple[float, float], ...]:
        """(pitch, yaw) [deg] of every ray, pitch-major (the sensors' order)."""
        return tuple((p, y) for p in self.pitch_deg for y in self.yaw_deg)

    def in_blackout(self, t: float) -> bool:
        """True when ``t`` [s] lies in one of :attr:`blackouts` (start included, end excluded)."""
        return any(start <= t < end for start, end in self.blackouts)
