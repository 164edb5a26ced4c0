"""Shared fixtures of the wbmpc tests: hand-written alternating gait schedules."""

from __future__ import annotations

import numpy as np

from sequencer.schedule import ContactSchedule


def alternating_schedule(t0: float, dt: float, n_nodes: int, step_duration: float = 0.3,
                         first_swing: str = "right", step_length: float = 0.1,
                         foot_y: tuple[float, float] = (0.1, -0.1), t_start: float = 0.0) -> ContactSchedule:
    """Single-support alternating gait: the ``first_swing`` foot swings on [t_start, t_start + T),
    then the other, and so on (no double support, as the sequencer's schedule). Touchdowns
    advance by ``step_length`` [m] in x per step."""
    feet = ("left", "right")
    times = t0 + dt * np.arange(n_nodes + 1)
    in_contact = np.ones((n_nodes + 1, 2), dtype=bool)
    phase = np.full((n_nodes + 1, 2), np.nan)
    duration = np.full((n_nodes + 1, 2), np.nan)
    touchdown = np.full((n_nodes + 1, 2, 2), np.nan)
    first = feet.index(first_swing)
    for k, t in enumerate(times):
        step = int(np.floor((t - t_start) / step_duration + 1e-9))
        if step < 0:
            continue
        swing = first if step % 2 == 0 else 1 - first
        in_contact[k, swing] = False
        phase[k, swing] = (t - t_start - step * step_duration) / step_duration
        duration[k, swing] = step_duration
        touchdown[k, swing] = ((step + 1) * step_length, foot_y[swing])
    return ContactSchedule(t0=t0, dt=dt, feet=feet, in_contact=in_contact, swing_phase=phase,
                           swing_duration=duration, touchdown_position=touchdown)


def standing_state(robot) -> np.ndarray:
    """Reference posture at rest, shape (nx,)."""
    return np.concatenate([np.asarray(robot.q_reference, dtype=float), np.zeros(robot.pinocchio_model.nv)])


def random_state(robot, rng: np.random.Generator, q_scale: float = 0.1, v_scale: float = 0.5) -> np.ndarray:
    """Random state near the reference posture (nx,)."""
    import pinocchio as pin

    model = robot.pinocchio_model
    q = pin.integrate(model, np.asarray(robot.q_reference, dtype=float), q_scale * rng.standard_normal(model.nv))
    return np.concatenate([q, v_scale * rng.standard_normal(model.nv)])


def crossing_schedule(n_nodes: int, dt: float = 0.02):
    """A walking schedule of 0.2 s steps, 0.5 m long, from t = 0 whose right swing passes over a 10 cm high, 10 cm
    deep box 0.25 m ahead (under the middle of the swing's straight path): (schedule, CrossingSchedule)."""
    from sequencer.obstacles import Obstacle
    from wbmpc.walking.reference import CrossingSchedule

    schedule = alternating_schedule(0.0, dt, n_nodes, step_duration=0.2, foot_y=(0.2, -0.2), step_length=0.5)
    box = Obstacle(np.array([0.25, 0.0]), 0.0, 0.1, 1.0, 0.1)
    swinging = ~schedule.in_contact
    index = np.where(swinging, 0, -1)
    liftoff = np.array([[-0.5, 0.2], [-0.25, -0.2]])  # each foot's lift-off, 0.5 m behind its touchdown
    liftoff_xy = np.where(swinging[..., None], np.broadcast_to(liftoff, schedule.touchdown_position.shape), np.nan)
    return schedule, CrossingSchedule((box,), index, liftoff_xy, np.where(swinging, 0.0, np.nan),
                                      schedule.feet)
