"""The closed loop with Crocoddyl's FDDP as the MPC solver (benchmark baseline only).

``wbmpc bench loop --baseline crocoddyl`` runs the same scenario twice: with the library's MPC
and with this one. Everything but the solve is shared: the sequencer, the OCP update from the
schedule and the warm start are the library's (a :class:`~wbmpc.WalkingMPC` inside), and the
solve runs Crocoddyl 3.2's ``SolverFDDP`` on the problem's twin (:mod:`bench.crocoddyl_mirror`,
single thread). The references are copied into the twin before each solve; that copy is Python
glue a C++ user would not have, so it is timed apart (``mirror_seconds``) and taken out of the
baseline's wall time. Both loops take the same controls to ~1e-8 N·m per update, so they walk
the same way and the comparison is the solver's cost in the closed loop.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from sim.controller import WalkingController
from wbmpc.mpc import MPCSolution


class CrocoddylWalkingMPC:
    """A :class:`~wbmpc.WalkingMPC`'s update with the solve done by Crocoddyl's ``SolverFDDP``.

    Args:
        mpc: the library's MPC whose OCP, warm start and options are used (its solver is not).

    Attributes:
        mirror_seconds: wall time spent copying references into the Crocoddyl twin [s].
    """

    def __init__(self, mpc: Any):
        import crocoddyl

        from bench.crocoddyl_mirror import CrocoddylMirror

        self.inner = mpc
        self.problem = mpc.problem
        self.mirror = CrocoddylMirror(mpc.problem)
        self.solver = crocoddyl.SolverFDDP(self.mirror.problem)
        self.solver.th_stop = mpc.solver.th_stop
        self.solver.reg_min = mpc.solver.reg_min
        self.solver.reg_max = mpc.solver.reg_max
        self.mirror_seconds = 0.0

    def prepare(self, deadline: float | None = None) -> int:
        """Crocoddyl has no preparation: nothing to do."""
        return 0

    def update(self, t: float, x_measured: np.ndarray, schedule, com_terminal_reference: np.ndarray) -> MPCSolution:
        """The library's update (OCP update, warm start) with Crocoddyl's solve; never raises."""
        mpc = self.inner
        tic = time.perf_counter()
        try:
            x = mpc.ocp.state.check_state("x_measured", x_measured)
            mpc.ocp.update(x, schedule, com_terminal_reference)
            xs, us, cold = mpc.warm_start(float(t), x)
            copy = time.perf_counter()
            self.mirror.update()
            self.mirror_seconds += time.perf_counter() - copy
            self.mirror.problem.x0 = x
            iterations = mpc.cold_start_iterations if cold else mpc.max_iterations
            converged = self.solver.solve(list(xs), list(us), iterations, False)
            solver = self.solver
            solution = MPCSolution(
                ok=True, status="converged" if converged else "max_iter",
                iterations=int(solver.iter) + 1 if converged else int(solver.iter),  # Crocoddyl's iter: index or maxiter
                cost=float(solver.cost), solve_time=time.perf_counter() - tic, t=float(t),
                xs=np.array(solver.xs), us=np.array(solver.us), K=-np.array(solver.K),  # library sign
            )
            if not (np.isfinite(solution.cost) and np.all(np.isfinite(solution.us))):
                raise FloatingPointError("the solution is not finite")
            mpc.last_good = solution
            return solution
        except Exception as err:  # same contract as WalkingMPC.update
            return mpc._failed(float(t), x_measured, f"failed: {type(err).__name__}: {err}", tic)


class CrocoddylWalkingController(WalkingController):
    """The walking controller with :class:`CrocoddylWalkingMPC` as its MPC."""

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        super().reset(robot, x0, t0)
        self.mpc = CrocoddylWalkingMPC(self.mpc)

    @property
    def mirror_seconds(self) -> float:
        mpc = getattr(self, "mpc", None)
        return getattr(mpc, "mirror_seconds", 0.0)
