"""The record of one closed-loop run: arrays at 1 kHz and at the replan rate, outcome, metrics.

A :class:`RunLog` is plain data (numpy arrays, dicts of scalars, strings), so it pickles cheaply for
worker processes, and :meth:`RunLog.save` writes it as ``log.npz`` (compressed arrays) plus
``metrics.json`` (outcome, parameters, metrics). :func:`load_run` reads a saved run back.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# Signals recorded at every simulation tick (name -> per-tick shape suffix, filled by the runner).
TICK_SIGNALS_DOC = {
    "t": "simulation time [s], (n,)",
    "qpos": "MuJoCo generalized positions, (n, nq), quaternion (w, x, y, z)",
    "qvel": "MuJoCo generalized velocities, (n, nv), base linear velocity in world frame",
    "x": "true state in Pinocchio convention, (n, nq + nv)",
    "tau_command": "controller output before clipping [N·m], (n, nu)",
    "tau": "applied (clipped) torque [N·m], (n, nu)",
    "com": "centre of mass, world frame [m], (n, 3)",
    "com_velocity": "centre-of-mass velocity, world frame [m/s], (n, 3)",
    "dcm": "divergent component of motion c_xy + c_dot_xy / omega, world frame [m], (n, 2)",
    "feet": "foot frame positions, world frame [m], (n, n_feet, 3)",
    "foot_contact": "foot touching the ground, (n, n_feet) bool",
    "base_velocity_world": "base linear velocity, world frame [m/s], (n, 3)",
    "velocity_command": "walking velocity command (v_x, v_y) [m/s], (n, 2)",
}


@dataclass
class RunLog:
    """Everything recorded during one run.

    Attributes:
        scenario: scenario name.
        robot: robot name.
        seed: random seed of the run.
        params: scenario, controller and runner parameters actually used (JSON-able).
        status: "completed", "fell", "failed" (the controller had nothing to follow: its first solve failed,
            or its planner failed until the kept plan ran out; ``error`` says which), "error" or "interrupted".
        fall_time: time of the fall [s] (None if no fall).
        fall_reason: why the run counts as a fall (None if no fall).
        error: "ExceptionType: message" if the run ended with an exception.
        ticks: 1 kHz signals (see ``TICK_SIGNALS_DOC``), truncated to the ticks simulated.
        replans: replan-rate signals; ``t`` plus the controller's record keys (e.g. ``mpc_ok``,
            ``mpc_solve_time``, ``stance_foot``, ``next_x``), each shape (n_replans,).
        timing: wall-clock seconds spent in simulation, replanning, feedback and in total;
            ``setup`` (models, buffers and the controller's reset with its cold first solve) and
            ``loop`` (the ticks: total − setup).
        metrics: summary figures (see ``sim.metrics``), filled at the end of the run.
    """

    scenario: str
    robot: str
    seed: int
    params: dict[str, Any]
    status: str = "running"
    fall_time: float | None = None
    fall_reason: str | None = None
    error: str | None = None
    ticks: dict[str, np.ndarray] = field(default_factory=dict)
    replans: dict[str, np.ndarray] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)

    @property
    def fell(self) -> bool:
        return self.status == "fell"

    @property
    def duration(self) -> float:
        """Simulated time covered by the log [s]."""
        t = self.ticks.get("t")
        return 0.0 if t is None or len(t) == 0 else float(t[-1] - t[0])

    def summary(self) -> dict[str, Any]:
        """Outcome, parameters, timing and metrics as one JSON-able dict (what ``metrics.json`` holds)."""
        return {
            "scenario": self.scenario,
            "robot": self.robot,
            "seed": self.seed,
            "status": self.status,
            "fell": self.fell,
            "fall_time": self.fall_time,
            "fall_reason": self.fall_reason,
            "error": self.error,
            "params": self.params,
            "timing": self.timing,
            "metrics": self.metrics,
        }

    def save(self, out_dir: str | os.PathLike) -> tuple[str, str]:
        """Write ``log.npz`` (compressed) and ``metrics.json`` into ``out_dir``; returns both paths."""
        from wbmpc.jsonable import to_jsonable

        os.makedirs(out_dir, exist_ok=True)
        arrays = {f"ticks/{k}": v for k, v in self.ticks.items()}
        arrays.update({f"replans/{k}": v for k, v in self.replans.items()})
        npz_path = os.path.join(out_dir, "log.npz")
        json_path = os.path.join(out_dir, "metrics.json")
        tmp_npz = npz_path + ".tmp.npz"
        np.savez_compressed(tmp_npz, **arrays)
        os.replace(tmp_npz, npz_path)
        tmp_json = json_path + ".tmp"
        with open(tmp_json, "w") as stream:
            json.dump(to_jsonable(self.summary()), stream, indent=2)
            stream.write("\n")
        os.replace(tmp_json, json_path)
        return npz_path, json_path


def load_run(out_dir: str | os.PathLike) -> RunLog:
    """Read a run written by :meth:`RunLog.save`."""
    with open(os.path.join(out_dir, "metrics.json")) as stream:
        summary = json.load(stream)
    log = RunLog(
        scenario=summary["scenario"],
        robot=summary["robot"],
        seed=summary["seed"],
        params=summary["params"],
        status=summary["status"],
        fall_time=summary["fall_time"],
        fall_reason=summary["fall_reason"],
        error=summary["error"],
        timing=summary["timing"],
        metrics=summary["metrics"],
    )
    with np.load(os.path.join(out_dir, "log.npz")) as arrays:
        for key in arrays.files:
            group, name = key.split("/", 1)
            getattr(log, group)[name] = arrays[key]
    return log
