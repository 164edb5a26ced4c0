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
