"""``obstacle``: walk straight at ``speed`` toward a box lying across the path (issue 15).

The box (a world geom named ``obstacle_box``, :data:`sim.falls.OBSTACLE_GEOM_PREFIX`) stands on the
floor across the robot's path: its near edge ``distance`` ahead of the robot's starting base
position, ``distance`` drawn uniformly in [``distance_min``, ``distance_max``], its depth (along
the path) in [``depth_min``, ``depth_max``] and its friction in [``friction_min``,
``friction_max``], all from the run's seed; its ``height`` and ``width`` (across the path, centred
on it) are parameters. The robot learns of the box only through its rangefinders (the walking
preset's ``[perception]``); :meth:`Obstacle.true_obstacles` is the ground truth the metrics
compare with (``sim.obstacle_metrics``).

Shanks: the robot's lower legs carry no collision geometry (``robots.mujoco_model``: only the
feet touch the floor). So that a shank hitting the box is felt (and counted as a touch), the
scenario adds a capsule along each lower leg that collides with the box only (contype/conaffinity
bit 2: not with the floor nor the robot). ``perceivable=False`` makes the box invisible to the
rangefinders (alpha 0: MuJoCo's rays skip it): a missed detection, the fault a test injects.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sequencer.obstacles import Obstacle as ObstacleBox
from sim.falls import OBSTACLE_GEOM_PREFIX
from sim.scenarios.base import Scenario, _check_range, register

BOX_GEOM_NAME = f"{OBSTACLE_GEOM_PREFIX}_box"
SHANK_GEOM_PREFIX = "shank_guard_"
SHANK_RADIUS = 0.035  # [m], the capsule along each lower leg
SHANK_LENGTH_MIN = 0.1  # [m]: the lower leg is the first ancestor of the foot body at least this far from it
OBSTACLE_ONLY_BIT = 2  # contype/conaffinity bit the shank capsules share with the box only
HEIGHT_RANGE = (0.02, 0.6)  # [m], box heights accepted
DISTANCE_RANGE = (0.5, 20.0)  # [m], near-edge distances accepted


@register("obstacle")
@dataclass(frozen=True)
class Obstacle(Scenario):
    """Walk at ``speed`` toward a box of ``height`` [m] across the path, at a seeded distance ahead."""

    default_duration = 14.0

    speed: float = 0.4  # [m/s]
    height: float = 0.1  # [m], box height
    distance_min: float = 2.0  # [m], near edge ahead of the starting base position: drawn in [min, max]
    distance_max: float = 3.0  # [m]
    depth_min: float = 0.1  # [m], box extent along the path: drawn in [min, max]
    depth_max: float = 0.3  # [m]
    width: float = 1.2  # [m], box extent across the path (centred on it)
    friction_min: float = 0.5  # box sliding friction: drawn in [min, max]
    friction_max: float = 1.0
    perceivable: bool = True  # False: the rangefinders do not see the box (a missed detection)

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range("height", self.height, *HEIGHT_RANGE, "m")
        _check_range("distance_min", self.distance_min, *DISTANCE_RANGE, "m")
        _check_range("distance_max", self.distance_max, self.distance_min, DISTANCE_RANGE[1], "m")
        _check_range("depth_min", self.depth_min, 0.02, 2.0, "m")
        _check_range("depth_max", self.depth_max, self.depth_min, 2.0, "m")
        _check_range("width", self.width, 0.1, 20.0, "m")
        _check_range("friction_min", self.friction_min, 0.01, 5.0, "")
        _check_range("friction_max", self.friction_max, self.friction_min, 5.0, "")
        if not isinstance(self.perceivable, bool):
            from wbmpc.errors import ParameterError

            raise ParameterError(f"perceivable={self.perceivable!r} must be true or false")

    def setup(self, robot, command_range) -> None:
        object.__setattr__(self, "_robot", robot)

    def sample_box(self, rng: np.random.Generator) -> dict[str, float]:
        """The box of this seed: near-edge distance ahead of the start, depth [m], friction [-]."""
        return {"distance": float(rng.uniform(self.distance_min, self.distance_max)),
                "depth": float(rng.uniform(self.depth_min, self.depth_max)),
                "friction": float(rng.uniform(self.friction_min, self.friction_max))}

    def modify_spec(self, spec, rng: np.random.Generator) -> None:
        from robots.mujoco_model import add_box_geom

        box = self.sample_box(rng)
        robot = getattr(self, "_robot", None)
        start = np.zeros(2) if robot is None else np.asarray(robot.q_reference[:2], dtype=float)
        center = np.array([start[0] + box["distance"] + 0.5 * box["depth"], start[1]])
        truth = ObstacleBox(center=center, yaw=0.0, depth=box["depth"], width=self.width, height=self.height)
        object.__setattr__(self, "_truth", truth)
        object.__setattr__(self, "_box", box)
        geom = add_box_geom(spec, BOX_GEOM_NAME, np.array([*center, 0.5 * self.height]),
                            0.5 * np.array([box["depth"], self.width, self.height]), friction=box["friction"],
                            rgba=(0.8, 0.45, 0.2, 1.0 if self.perceivable else 0.0))
        geom.contype = geom.conaffinity = int(geom.contype) | OBSTACLE_ONLY_BIT
        if robot is not None:
            _add_shank_guards(spec, robot)

    def true_obstacles(self) -> tuple[ObstacleBox, ...]:
        """The scene's box, world frame (after :meth:`modify_spec`; the metrics' ground truth, never the controller's)."""
        truth = getattr(self, "_truth", None)
        return () if truth is None else (truth,)


def _add_shank_guards(spec, robot) -> None:
    """A capsule from each lower leg's origin (the knee) to its foot body's, colliding with the box only.

    The lower leg is the foot body's first ancestor at least :data:`SHANK_LENGTH_MIN` from it: the H1's and
    Bolt's foot hangs from the shank itself; the G1's from a 1.8 cm ankle link (pitch, then roll), whose capsule
    would leave the shin, 0.3 m, without a guard."""
    import mujoco

    for side, geoms in robot.mujoco_foot_geoms.items():
        foot = spec.body(geoms[0][0])
        shank, end = foot.parent, np.array(foot.pos, dtype=float)  # the foot's origin in the shank's frame [m]
        while shank is not None and shank.name != "world" and np.linalg.norm(end) < SHANK_LENGTH_MIN:
            rotated = np.zeros(3)
            mujoco.mju_rotVecQuat(rotated, end, np.array(shank.quat, dtype=float))
            shank, end = shank.parent, np.array(shank.pos, dtype=float) + rotated
        if shank is None or shank.name == "world":
            continue
        shank.add_geom(
            name=f"{SHANK_GEOM_PREFIX}{side}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            fromto=[0.0, 0.0, 0.0, *[float(v) for v in end]], size=[SHANK_RADIUS, 0.0, 0.0],
            contype=OBSTACLE_ONLY_BIT, conaffinity=OBSTACLE_ONLY_BIT, group=3,
            rgba=[0.6, 0.6, 0.6, 0.0],  # alpha 0: the rays skip it (they see the leg's own mesh)
            mass=0.0, density=0.0,
        )
