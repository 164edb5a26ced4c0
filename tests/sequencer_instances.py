"""Random footstep QP instances shared by the sequencer and sensitivity tests (seeded)."""

import dataclasses

import numpy as np

from sequencer import SequencerParams, StepProblem


def random_problems(count: int, seed: int, tight: bool = False) -> list[StepProblem]:
    """Random stance foot, foot position, DCM and elapsed time; ``tight`` makes bounds bind often."""
    rng = np.random.default_rng(seed)
    base = SequencerParams.table_i()
    problems = []
    for _ in range(count):
        params = base
        if tight:
            params = dataclasses.replace(
                base, l_min=-0.1, l_max=rng.uniform(0.1, 0.2), w_left_min=-0.3, w_left_max=-0.15,
                w_right_min=0.15, w_right_max=0.3, t_min=0.15, t_max=rng.uniform(0.35, 0.6),
                alpha2=10.0 ** rng.uniform(-1, 3),
            )
        stance = "left" if rng.random() < 0.5 else "right"
        p0 = rng.uniform(-0.5, 0.5, 2)
        dcm = p0 + rng.normal(0.0, 0.12 if tight else 0.06, 2)
        elapsed = rng.uniform(0.0, 0.3)
        problems.append(StepProblem.from_params(params, stance, p0, dcm, elapsed))
    return problems
