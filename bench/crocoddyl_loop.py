"""The closed loop with Crocoddyl's FDDP as the MPC solver (benchmark baseline only).

``wbmpc bench loop --baseline crocoddyl`` runs the same scenario twice: with the library's MPC
and with this one. Everything but the solve is shared: the controller's :class:`~wbmpc.walking.WalkingMPC`
keeps its OCP update, warm start and failure handling, and only its solver is replaced by
Crocoddyl 3.2's ``SolverFDDP`` on the problem's twin (:mod:`bench.crocoddyl_mirror`, single
thread). The references are copied into the twin before each solve; that copy is Python glue a
C++ user would not have, so it is timed apart (``mirror_seconds``) and taken out of the
baseline's wall time. Both loops take the same controls to ~1e-8 N·m per update, so they walk
the same way and the comparison is the solver's cost in the closed loop.

A preset whose walking OCP has no Crocoddyl twin (the H1's: its sole-weighted contact damping and
obstacle clearance terms) is compared on its twin-able variant instead, the preset with only the
options the mirror refuses replaced (:func:`crocoddyl_twinnable_variant`); both loops then run it.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from bench.crocoddyl_mirror import NoCrocoddylTwin
from wbmpc.walking.controller import WalkingController
from wbmpc.walking.preset import WalkingPreset, load_walking_preset

#: scenarios that place boxes the robot's perception can report as obstacles: there the walking OCP's obstacle
#: clearance terms act, so a variant without them would be another controller
SCENARIOS_WITH_OBSTACLES = ("obstacle", "terrain")


def crocoddyl_twinnable_variant(preset: WalkingPreset, scenario: str) -> dict[str, Any]:
    """The overrides that make ``preset`` its Crocoddyl-twin-able variant for ``scenario``: the nearest walking
    OCP that :class:`~bench.crocoddyl_mirror.CrocoddylMirror` mirrors, the preset with only the options the
    mirror refuses replaced (found by mirroring the H1 preset: these two are all it refuses):

    - ``ocp.contact_damping_moments`` "sole" or "corners" (moment rows damped apart, which Crocoddyl has no
      model of) -> "uniform": every contact row damped by the preset's own ``contact_damping`` μ [m/s² per N,
      rad/s² per N·m], which is Crocoddyl's ``JMinvJt_damping``; the dynamics backend is kept (the "kkt"
      backend solves the uniform damping too);
    - ``ocp.obstacle_clearance_weight`` > 0 -> 0 when ``scenario`` places no obstacles: its clearance barriers
      (``ResidualFramePointHeight``, no Crocoddyl model) are in the OCP but never active there.

    Args:
        preset: the robot's walking preset (with any overrides already applied).
        scenario: the name of the scenario the loop runs (``"walk"``, ...).

    Returns:
        ``{"ocp.<field>": value}``, the form of :func:`~wbmpc.walking.preset.load_walking_preset`'s overrides
        (and of ``--set``), holding only the fields whose value changes; empty when the preset is twin-able.

    Raises:
        NoCrocoddylTwin: ``scenario`` is one of :data:`SCENARIOS_WITH_OBSTACLES` and the preset has obstacle
            clearance terms: they act there, and no twin-able variant keeps them.
    """
    ocp = preset.ocp
    overrides: dict[str, Any] = {}
    if ocp.contact_damping_moments != "uniform":
        overrides["ocp.contact_damping_moments"] = "uniform"
    if ocp.obstacle_clearance_weight > 0:
        if scenario in SCENARIOS_WITH_OBSTACLES:
            raise NoCrocoddylTwin(f"no Crocoddyl twin for the obstacle clearance terms (ResidualFramePointHeight) of "
                                  f"obstacle_clearance_weight={ocp.obstacle_clearance_weight:g} in scenario={scenario!r}, "
                                  f"which places obstacles; a variant without them needs a scenario other than "
                                  f"{SCENARIOS_WITH_OBSTACLES}")
        overrides["ocp.obstacle_clearance_weight"] = 0.0
    return overrides


class CrocoddylSolver:
    """Crocoddyl's ``SolverFDDP`` on the twin of a wbmpc problem, with the part of
    :class:`~wbmpc.ocp.solvers.SolverFDDP`'s interface that :class:`~wbmpc.walking.WalkingMPC` uses.

    Args:
        problem: the wbmpc shooting problem (its twin is refreshed from it at every solve).
        like: the wbmpc solver whose options (th_stop, reg_min, reg_max) are copied.

    Attributes:
        mirror_seconds: wall time spent copying references into the Crocoddyl twin [s].
    """

    def __init__(self, problem: Any, like: Any):
        import crocoddyl

        from bench.crocoddyl_mirror import CrocoddylMirror

        self.mirror = CrocoddylMirror(problem)
        self.solver = crocoddyl.SolverFDDP(self.mirror.problem)
        self.solver.th_stop = like.th_stop
        self.solver.reg_min = like.reg_min
        self.solver.reg_max = self.reg_max = like.reg_max
        self.deadline_hit = False  # Crocoddyl has no deadline; the baseline runs without one
        self.log: list = []
        self.mirror_seconds = 0.0

    def solve(self, init_xs, init_us, maxiter: int = 100, is_feasible: bool = False, deadline=None) -> bool:
        """Refresh the twin (timed apart) and run Crocoddyl's solve; ``deadline`` is ignored."""
        tic = time.perf_counter()
        self.mirror.update()
        self.mirror_seconds += time.perf_counter() - tic
        converged = self.solver.solve(list(init_xs), list(init_us), maxiter, is_feasible)
        # Crocoddyl's iter: index of the converging iteration, or maxiter
        self.log = [None] * (self.solver.iter + 1 if converged else self.solver.iter)
        return converged

    @property
    def xs(self) -> np.ndarray:
        return np.array(self.solver.xs)

    @property
    def us(self) -> np.ndarray:
        return np.array(self.solver.us)

    @property
    def K(self) -> np.ndarray:
        """Feedback gains, library sign (the negative of Crocoddyl's)."""
        return -np.array(self.solver.K)

    @property
    def cost(self) -> float:
        return self.solver.cost

    @property
    def preg(self) -> float:
        return self.solver.preg


class CrocoddylWalkingController(WalkingController):
    """The walking controller with Crocoddyl's FDDP as its MPC solver (:class:`CrocoddylSolver`).
    Nothing is prepared between updates (``mpc_prepare`` off): Crocoddyl evaluates everything in
    its solve."""

    def __init__(self, preset: WalkingPreset | None = None) -> None:
        preset = preset or load_walking_preset("bolt")
        super().__init__(dataclasses.replace(preset, controller=dataclasses.replace(preset.controller,
                                                                                    mpc_prepare=False)),
                         mpc_solver=CrocoddylSolver)

    @property
    def mirror_seconds(self) -> float:
        """Wall time spent copying references into the Crocoddyl twin [s] (0 before reset)."""
        mpc = getattr(self, "mpc", None)
        return 0.0 if mpc is None else mpc.solver.mirror_seconds
