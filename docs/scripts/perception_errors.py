"""The perception's error figures of docs/perception.md: the H1's rangefinders against the true scene.

Random layouts (seeded): one box across the path, near edge 1.8-2.8 m ahead, depth 0.1-0.3 m, width
0.8-1.5 m, height 0.1-0.4 m, centre 0-0.1 m off the path; with ``--yaw-max`` the box is turned about its
centre by up to that angle either way, with ``--heading-max`` the robot's heading is off the path (world
x) by up to that angle either way (both drawn from a generator of their own, so the boxes are the same
with and without them). The standing H1 slides along x at 0.5 m/s (no controller: the figures are the
perception's own), scanning at 67 Hz, until the box's near edge is 1 m ahead; then the reported
obstacle is compared with the box: yaw, depth, height, and the near and far edges where the line
through the box's centre along its own depth axis enters and leaves the reported footprint.

    PYTHONPATH=. python docs/scripts/perception_errors.py [n_layouts] [FIELD=VALUE of [perception] ...]
        [--axis heading|near_edge] [--yaw-max RAD] [--heading-max RAD] [--noise M [M ...]]
"""

from __future__ import annotations

import argparse
import ast
import dataclasses

import mujoco
import numpy as np

from robots import load_robot
from robots.conventions import pinocchio_to_mujoco_state
from robots.mujoco_model import add_box_geom, build_mujoco_spec
from sequencer.obstacles import Obstacle
from sim.perception import PerceptionPipeline
from wbmpc.walking.perception_config import OBSTACLE_AXES
from wbmpc.walking.preset import load_walking_preset

SCAN_DT, SPEED = 0.015, 0.5  # [s], [m/s]
LAYOUT_SEED, ANGLE_SEED = 15, (15, 1)  # the boxes' generator, the angles' (box yaw, robot heading)


def errors(h1, config, rng, angles, seed, yaw_max, heading_max):
    """(yaw [rad], depth, height, near edge, far edge [m], first report distance [m], width seen / true)."""
    near, depth, width, height, offset = (rng.uniform(1.8, 2.8), rng.uniform(0.1, 0.3), rng.uniform(0.8, 1.5),
                                          rng.uniform(0.1, 0.4), rng.uniform(-0.1, 0.1))
    yaw, heading = angles.uniform(-yaw_max, yaw_max), angles.uniform(-heading_max, heading_max)
    truth = Obstacle(center=[near + 0.5 * depth, offset], yaw=yaw, depth=depth, width=width, height=height)
    spec = build_mujoco_spec(h1, link_collisions=True)
    PerceptionPipeline.add_to_spec(spec, config, h1.base_body)
    add_box_geom(spec, "obstacle", np.array([*truth.center, 0.5 * height]), 0.5 * np.array([depth, width, height]),
                 yaw=yaw)
    model = spec.compile()
    data = mujoco.MjData(model)
    pipeline = PerceptionPipeline(model, config, seed, h1)
    q = np.array(h1.q_reference)
    q[3:7] = [0.0, 0.0, np.sin(0.5 * heading), np.cos(0.5 * heading)]  # Pinocchio's (x, y, z, w)
    first = None
    for k, x in enumerate(np.arange(0.0, near - 1.0 + 1e-9, SPEED * SCAN_DT)):
        q[0] = x
        data.qpos[:], _ = pinocchio_to_mujoco_state(h1, q, np.zeros(h1.nv))
        if pipeline.step(0, k * SCAN_DT, model, data, np.concatenate([q, np.zeros(h1.nv)])) and first is None:
            first = near - x
    (obstacle,) = pipeline.estimator.obstacles
    entry, exit_ = obstacle.interval_along(truth.center - truth.axes[0], yaw)  # from 1 m before the centre
    return (obstacle.yaw - yaw, obstacle.depth - depth, obstacle.height - height, entry - (1.0 - 0.5 * depth),
            exit_ - (1.0 + 0.5 * depth), first, obstacle.width / width)


def main(n: int = 20, noises=(0.0, 0.005, 0.01, 0.02), yaw_max: float = 0.0, heading_max: float = 0.0,
         **overrides) -> None:
    h1 = load_robot("h1")
    base = dataclasses.replace(load_walking_preset("h1").perception, **overrides)
    for noise in noises:
        config = dataclasses.replace(base, noise_std=noise)
        rng, angles = np.random.default_rng(LAYOUT_SEED), np.random.default_rng(ANGLE_SEED)
        rows = np.array([errors(h1, config, rng, angles, seed, yaw_max, heading_max) for seed in range(n)])
        yaw, depth, h, near, far, first, width = rows.T
        print(f"{config.obstacle_axis}, noise {1e3 * noise:4.1f} mm, {n} layouts: |yaw error| max "
              f"{1e3 * np.abs(yaw).max():6.1f} mrad; depth error [{1e3 * depth.min():6.1f}, {1e3 * depth.max():6.1f}] mm; "
              f"|height error| max {1e3 * np.abs(h).max():5.1f} mean {1e3 * np.abs(h).mean():5.1f} mm; "
              f"near edge error [{1e3 * near.min():6.1f}, {1e3 * near.max():5.1f}] mm; "
              f"far edge error [{1e3 * far.min():6.1f}, {1e3 * far.max():5.1f}] mm; first report {first.min():.2f}-"
              f"{first.max():.2f} m ahead; width seen / true {width.min():.2f}-{width.max():.2f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("n_layouts", nargs="?", type=int, default=20)
    parser.add_argument("overrides", nargs="*", metavar="FIELD=VALUE", help="fields of [perception] (Python literals)")
    parser.add_argument("--axis", choices=OBSTACLE_AXES, help="perception.obstacle_axis (default: the preset's)")
    parser.add_argument("--yaw-max", type=float, default=0.0, help="the box's yaw, uniform in +-this [rad]")
    parser.add_argument("--heading-max", type=float, default=0.0, help="the robot's heading, uniform in +-this [rad]")
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.005, 0.01, 0.02], help="range noise [m]")
    arguments = parser.parse_args()
    fields = {k: ast.literal_eval(v) for k, v in (arg.split("=", 1) for arg in arguments.overrides)}
    if arguments.axis is not None:
        fields["obstacle_axis"] = arguments.axis
    main(arguments.n_layouts, arguments.noise, arguments.yaw_max, arguments.heading_max, **fields)
