"""The perception's error figures of docs/perception.md: the H1's rangefinders against the true scene.

Random layouts (seeded): one box across the path, near edge 1.8-2.8 m ahead, depth 0.1-0.3 m, width
0.8-1.5 m, height 0.1-0.4 m, centre 0-0.1 m off the path. The standing H1 slides toward it at
0.5 m/s (no controller: the figures are the perception's own), scanning at 67 Hz, until the box's
near edge is 1 m ahead; then the reported obstacle is compared with the box.

    PYTHONPATH=. python docs/scripts/perception_errors.py [n_layouts] [FIELD=VALUE of [perception] ...]
"""

from __future__ import annotations

import dataclasses
import sys

import mujoco
import numpy as np

from robots import load_robot
from robots.conventions import pinocchio_to_mujoco_state
from robots.mujoco_model import add_box_geom, build_mujoco_spec
from sim.perception import PerceptionPipeline
from wbmpc.walking.preset import load_walking_preset

SCAN_DT, SPEED = 0.015, 0.5  # [s], [m/s]


def errors(h1, config, rng, seed):
    near, depth, width, height, offset = (rng.uniform(1.8, 2.8), rng.uniform(0.1, 0.3), rng.uniform(0.8, 1.5),
                                          rng.uniform(0.1, 0.4), rng.uniform(-0.1, 0.1))
    spec = build_mujoco_spec(h1, link_collisions=True)
    PerceptionPipeline.add_to_spec(spec, config, h1.base_body)
    add_box_geom(spec, "obstacle", np.array([near + 0.5 * depth, offset, 0.5 * height]),
                 0.5 * np.array([depth, width, height]))
    model = spec.compile()
    data = mujoco.MjData(model)
    pipeline = PerceptionPipeline(model, config, seed, h1)
    q = np.array(h1.q_reference)
    first = None
    for k, x in enumerate(np.arange(0.0, near - 1.0 + 1e-9, SPEED * SCAN_DT)):
        q[0] = x
        data.qpos[:], _ = pinocchio_to_mujoco_state(h1, q, np.zeros(h1.nv))
        if pipeline.step(0, k * SCAN_DT, model, data, np.concatenate([q, np.zeros(h1.nv)])) and first is None:
            first = near - x
    (obstacle,) = pipeline.estimator.obstacles
    low, high = obstacle.center[0] - 0.5 * obstacle.depth, obstacle.center[0] + 0.5 * obstacle.depth
    return obstacle.height - height, low - near, high - (near + depth), first, obstacle.width / width


def main(n: int = 20, **overrides) -> None:
    h1 = load_robot("h1")
    base = dataclasses.replace(load_walking_preset("h1").perception, **overrides)
    for noise in (0.0, 0.005, 0.01, 0.02):
        config = dataclasses.replace(base, noise_std=noise)
        rng = np.random.default_rng(15)
        rows = np.array([errors(h1, config, rng, seed) for seed in range(n)])
        h, near, far, first, width = rows.T
        print(f"noise {1e3 * noise:4.1f} mm, {n} layouts: |height error| max {1e3 * np.abs(h).max():5.1f} mean "
              f"{1e3 * np.abs(h).mean():5.1f} mm; near edge error [{1e3 * near.min():6.1f}, {1e3 * near.max():5.1f}] mm; "
              f"far edge error [{1e3 * far.min():6.1f}, {1e3 * far.max():5.1f}] mm; first report {first.min():.2f}-"
              f"{first.max():.2f} m ahead; width seen / true {width.min():.2f}-{width.max():.2f}")


if __name__ == "__main__":
    import ast

    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20,
         **{k: ast.literal_eval(v) for k, v in (arg.split("=", 1) for arg in sys.argv[2:])})
