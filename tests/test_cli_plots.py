"""Figures: the ground-plane panel keeps a long walk readable; the walk figure and Fig. 2 are written."""

from __future__ import annotations

import numpy as np
import pytest

from sim.plots import plane_limits


def test_a_long_walk_gets_its_own_lateral_scale():
    x = np.linspace(0.0, 20.0, 2000)  # 20 m forward, ±0.06 m lateral sway
    y = 0.06 * np.sin(x * 10)
    xlim, ylim, equal = plane_limits(x, y, aspect=3 / 8)
    assert not equal
    assert xlim[0] < 0.0 and xlim[1] > 20.0 and xlim[1] - xlim[0] < 22.5
    assert ylim[0] < -0.06 and ylim[1] > 0.06 and ylim[1] - ylim[0] < 0.15  # not ±3 m


def test_comparable_extents_keep_equal_scales_and_contain_the_data():
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-0.3, 0.5, 100), rng.uniform(-0.2, 0.2, 100)
    xlim, ylim, equal = plane_limits(x, y, aspect=3 / 8)
    assert equal
    assert (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]) == pytest.approx(3 / 8)  # the panel's shape, 1 m = 1 m
    assert xlim[0] <= x.min() and xlim[1] >= x.max() and ylim[0] <= y.min() and ylim[1] >= y.max()
    assert plane_limits(np.array([np.nan]), np.array([np.nan]), 1.0) == ((-1.0, 1.0), (-1.0, 1.0), True)


def test_walk_figure_of_a_short_run(tmp_path):
    from matplotlib.image import imread

    from sim import run_scenario
    from sim.plots import save_figures

    log = run_scenario("walk", controller="pd", duration=0.3, progress=False)
    path = save_figures(log, tmp_path / "figures" / "walk.png")
    image = imread(path)
    assert image.shape[0] > 1000 and image.shape[1] > 1000


def _standing_log(robot_name: str, yaw: float, n: int = 200):
    """A synthetic log of ``robot_name`` standing still at its reference posture, turned by ``yaw`` [rad]
    about z, both feet on the ground, the base moving at 0.2 m/s along its own heading."""
    import pinocchio as pin

    from robots import load_robot
    from sim.log import RunLog

    robot = load_robot(robot_name)
    model, data = robot.pinocchio_model, robot.pinocchio_model.createData()
    q = np.array(robot.q_reference, dtype=float)
    q[3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(0.0, 0.0, yaw)).coeffs()
    pin.framesForwardKinematics(model, data, q)
    feet = np.array([data.oMf[model.getFrameId(f)].translation for f in robot.foot_frames.values()])
    heading = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    ticks = {
        "t": np.arange(n) * 1e-3,
        "x": np.tile(np.concatenate([q, np.zeros(model.nv)]), (n, 1)),
        "feet": np.tile(feet, (n, 1, 1)),
        "foot_contact": np.ones((n, len(feet)), dtype=bool),
        "base_velocity_world": np.tile(0.2 * heading, (n, 1)),
    }
    return RunLog(scenario="walk", robot=robot_name, seed=0, params={}, ticks=ticks)


def test_footsteps_carry_the_sole_yaw_and_velocities_rotate_into_the_heading_frame():
    from sim.metrics import velocity_in_heading_frame
    from sim.plots import footsteps, turns

    log = _standing_log("g1", yaw=0.7)
    steps = footsteps(log)
    assert [j for j, _, _ in steps] == [0, 1]  # one footstep per foot: the whole log is one contact
    for j, centre, yaw in steps:
        assert yaw == pytest.approx(0.7, abs=1e-9)  # the soles turned with the base
        assert np.allclose(centre, log.ticks["feet"][100, j, :2])
    assert np.allclose(velocity_in_heading_frame(log.ticks), [0.2, 0.0])  # forward along its heading
    assert not turns(log)  # a constant yaw, however large, is not a turn
    log.ticks["foot_contact"][:, 0] = False
    log.ticks["foot_contact"][10:30, 1] = False  # a 10 ms contact then a long one: only the long one counts
    log.ticks["foot_contact"][:5, 1] = True
    assert [j for j, _, _ in footsteps(log)] == [1]
