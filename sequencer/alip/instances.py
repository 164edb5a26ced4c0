"""Random NMPC instances near the walking orbit (pushes on the angular momentum): tests and benchmarks."""

from __future__ import annotations

import numpy as np

from sequencer.alip.nlp import FEET, AlipInstance, desired_steps, orbit
from sequencer.alip.params import AlipParams
from sequencer.alip.s2s import B_D


def random_instances(params: AlipParams, n: int, seed: int = 0, push: float = 6.0) -> list[AlipInstance]:
    """``n`` instances: a command within 80 % of the range, a stance foot, t_curr in [0, 0.9 t_max], the orbit's
    state at t_curr plus a CoM offset of up to 3 cm and an angular-momentum push of up to ``push`` kg·m²/s."""
    rng = np.random.default_rng(seed)
    ranges = params.velocity_range()
    model = params.model
    out = []
    for i in range(n):
        foot = FEET[i % 2]
        v_x, v_y = (0.8 * rng.uniform(*ranges[name]) for name in ("v_x", "v_y"))
        yaw_rate = rng.uniform(-0.5, 0.5)
        previous = FEET[(i + 1) % 2]
        post = orbit(params, v_x, v_y)[previous] + B_D @ desired_steps(params, v_x, v_y, previous)
        t_curr = rng.uniform(0.0, 0.9 * params.t_max)
        x0 = model.flow(post, (0.0, 0.0), t_curr)
        x0 = x0 + np.array([rng.uniform(-0.03, 0.03), rng.uniform(-push, push), rng.uniform(-0.03, 0.03),
                            rng.uniform(-push, push)])
        out.append(AlipInstance(x0, t_curr, foot, v_x, v_y, yaw_rate))
    return out
