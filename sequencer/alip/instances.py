"""NMPC instances on and near the walking orbit: the undisturbed state of a command, and random pushes
(tests, benchmarks, the sensitivity study)."""

from __future__ import annotations

import numpy as np

from sequencer.alip.nlp import FEET, AlipInstance, desired_steps, orbit
from sequencer.alip.params import AlipParams
from sequencer.alip.s2s import B_D

OTHER_FOOT = {"left": "right", "right": "left"}


def orbit_state(params: AlipParams, v_x: float, v_y: float, stance_foot: str, t_curr: float) -> np.ndarray:
    """The orbit's ALIP state t_curr [s] into a ``stance_foot`` stance of the command (v_x, v_y) [m/s]: the
    pre-impact orbit state of the previous stance, reset by its desired step (eq. 7), flowed with τ = 0.
    Stance heading frame, shape (4,)."""
    previous = OTHER_FOOT[stance_foot]
    post = orbit(params, v_x, v_y)[previous] + B_D @ desired_steps(params, v_x, v_y, previous)
    return params.model.flow(post, (0.0, 0.0), t_curr)


def orbit_instance(params: AlipParams, v_x: float, v_y: float, stance_foot: str, t_curr: float,
                   yaw_rate: float = 0.0) -> AlipInstance:
    """The undisturbed instance of a command at t_curr [s] into a ``stance_foot`` stance (:func:`orbit_state`)."""
    return AlipInstance(orbit_state(params, v_x, v_y, stance_foot, t_curr), t_curr, stance_foot, v_x, v_y, yaw_rate)


def random_instances(params: AlipParams, n: int, seed: int = 0, push: float = 6.0) -> list[AlipInstance]:
    """``n`` instances: a command within 80 % of the range, a stance foot, t_curr in [0, 0.9 t_max], the orbit's
    state at t_curr plus a CoM offset of up to 3 cm and an angular-momentum push of up to ``push`` kg·m²/s."""
    rng = np.random.default_rng(seed)
    ranges = params.velocity_range()
    out = []
    for i in range(n):
        foot = FEET[i % 2]
        v_x, v_y = (0.8 * rng.uniform(*ranges[name]) for name in ("v_x", "v_y"))
        yaw_rate = rng.uniform(-0.5, 0.5)
        t_curr = rng.uniform(0.0, 0.9 * params.t_max)
        x0 = orbit_state(params, v_x, v_y, foot, t_curr)
        x0 = x0 + np.array([rng.uniform(-0.03, 0.03), rng.uniform(-push, push), rng.uniform(-0.03, 0.03),
                            rng.uniform(-push, push)])
        out.append(AlipInstance(x0, t_curr, foot, v_x, v_y, yaw_rate))
    return out
