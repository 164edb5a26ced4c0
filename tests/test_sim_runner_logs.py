"""The runner's tick logs grow by chunks (no allocation for the whole duration) and its on_tick observer."""

from __future__ import annotations

import numpy as np
import pytest

import sim.runner
from sim import run_scenario


def test_an_open_ended_duration_allocates_only_what_it_runs():
    # 1e12 s once asked for 7 PiB up front; the PD controller falls within about a second
    log = run_scenario("walk", controller="pd", duration=1e12, progress=False)
    assert log.status == "fell" and 0.1 < log.fall_time < 5.0
    n = len(log.ticks["t"])
    assert all(len(v) == n for v in log.ticks.values())
    assert log.ticks["t"][-1] == pytest.approx(log.fall_time)


def test_chunk_boundaries_do_not_change_the_log(monkeypatch):
    kwargs = dict(controller="pd", duration=0.5, stop_on_fall=False, progress=False)
    whole = run_scenario("walk", **kwargs)
    monkeypatch.setattr(sim.runner, "LOG_CHUNK_TICKS", 64)  # 500 ticks: 7 full chunks and a part
    chunked = run_scenario("walk", **kwargs)
    assert set(chunked.ticks) == set(whole.ticks)
    for key, values in whole.ticks.items():
        assert chunked.ticks[key].shape == values.shape and chunked.ticks[key].dtype == values.dtype
        np.testing.assert_array_equal(chunked.ticks[key], values, err_msg=key)


def test_on_tick_sees_every_step_and_leaves_the_run_unchanged():
    import mujoco

    seen = []

    def observer(model, data):
        assert isinstance(model, mujoco.MjModel) and isinstance(data, mujoco.MjData)
        seen.append(data.time)

    kwargs = dict(controller="pd", duration=0.2, progress=False)
    log = run_scenario("walk", on_tick=observer, **kwargs)
    assert len(seen) == len(log.ticks["t"]) == 200
    assert np.allclose(np.diff(seen), 1e-3)
    np.testing.assert_array_equal(run_scenario("walk", **kwargs).ticks["qpos"], log.ticks["qpos"])
