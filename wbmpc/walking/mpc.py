"""The walking MPC: the walking OCP (:mod:`wbmpc.walking.ocp`) solved in receding horizon by the
core's :class:`~wbmpc.ocp.mpc.RecedingHorizonMPC`.

    mpc = WalkingMPC(robot, WalkingOCPConfig(), n_nodes=100, dt=0.01, max_iterations=1)
    sol = mpc.update(t, x_measured, schedule, com_terminal_reference)   # never raises
    tau = sol.u(1) + sol.K(1) @ state_difference(sol.x(1), x_hat)       # eq. (25), node 1

Each update writes the contact schedule and the terminal CoM reference into the OCP's node
models, then hands the problem to the receding-horizon core (warm start, solve, last good plan).
"""

from __future__ import annotations

from wbmpc.ocp.mpc import MPCSolution, MPCSolver, RecedingHorizonMPC
from wbmpc.ocp.solvers.fddp import SolverFDDP
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig, quasi_static_controls


class WalkingMPC:
    """Receding-horizon solves of the walking OCP.

    Args:
        robot: a ``robots.RobotDescription``.
        config: OCP weights and solver options (line search, regularisation, stop threshold).
        n_nodes: horizon length N (running nodes).
        dt: node spacing [s].
        solver: callable problem -> :class:`~wbmpc.ocp.mpc.MPCSolver`, the solver to run on
            the OCP's problem (e.g. Crocoddyl's FDDP behind an adapter, in the benchmarks);
            None = the library's ``SolverFDDP`` with the config's options.
        max_iterations, cold_start_iterations, horizon_end, time_budget, restart_after_failures: see
            :class:`~wbmpc.ocp.mpc.RecedingHorizonMPC`.
    """

    def __init__(self, robot, config: WalkingOCPConfig | None = None, n_nodes: int = 100, dt: float = 0.01,
                 max_iterations: int = 1, cold_start_iterations: int = 20, horizon_end: str = "repeat",
                 time_budget: float | None = None, solver=None, restart_after_failures: int | None = None):
        self.config = WalkingOCPConfig() if config is None else config
        self.ocp = WalkingOCP(robot, self.config, n_nodes, dt)
        self.problem = self.ocp.problem
        own = SolverFDDP(self.problem)
        own.set_max_line_search_trials(self.config.max_line_search_trials)
        own.reg_min, own.reg_max, own.th_stop = self.config.reg_min, self.config.reg_max, self.config.th_stop
        chosen: MPCSolver = own if solver is None else solver(self.problem, own)
        self.receding = RecedingHorizonMPC(
            self.problem, self.ocp.dt, initial_controls=lambda x: quasi_static_controls(self.ocp, x),
            solver=chosen, max_iterations=max_iterations, cold_start_iterations=cold_start_iterations,
            horizon_end=horizon_end, time_budget=time_budget, restart_after_failures=restart_after_failures,
            entering_controls=lambda x, node: quasi_static_controls(self.ocp, x, node),
        )
        self.solver = self.receding.solver
        self.n_nodes = self.ocp.n_nodes
        self.dt = self.ocp.dt

    @property
    def last_good(self) -> MPCSolution | None:
        """The last successful update's solution (None before the first)."""
        return self.receding.last_good

    @last_good.setter
    def last_good(self, solution: MPCSolution | None) -> None:
        """Seed the next warm start with a solution (e.g. one computed elsewhere)."""
        self.receding.last_good = solution

    def update(self, t: float, x_measured, schedule, com_terminal_reference,
               touchdown_depth: float = 0.0, crossings=None, max_iterations: int | None = None,
               com_path=None, swing_liftoff=None, swing_path_weight: float | None = None) -> MPCSolution:
        """Write the schedule and the terminal CoM reference (3,) [m, world] into the OCP, then
        re-solve from the measured state; never raises (failures come back with ok=False).
        ``touchdown_depth`` [m], ``crossings`` (swings over obstacles), ``com_path`` (the plan's CoM at the nodes),
        ``swing_liftoff`` (every swing's lift-off), ``swing_path_weight`` (this update's):
        see :meth:`~wbmpc.walking.ocp.WalkingOCP.update`;
        ``max_iterations``: this update's FDDP iterations
        (None: the MPC's own, see :meth:`~wbmpc.ocp.mpc.RecedingHorizonMPC.update`)."""
        return self.receding.update(
            t, x_measured,
            lambda x: self.ocp.update(x, schedule, com_terminal_reference, touchdown_depth, crossings, com_path,
                                      swing_liftoff, swing_path_weight),
            max_iterations=max_iterations,
        )

    def prepare(self, deadline: float | None = None) -> int:
        """See :meth:`wbmpc.ocp.mpc.RecedingHorizonMPC.prepare`."""
        return self.receding.prepare(deadline)

    def warm_start(self, t: float, x_measured):
        """See :meth:`wbmpc.ocp.mpc.RecedingHorizonMPC.warm_start`."""
        return self.receding.warm_start(t, x_measured)
