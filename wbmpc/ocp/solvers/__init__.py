"""Optimal control solvers."""

from wbmpc.ocp.solvers.fddp import IterationLog, SolverFDDP

__all__ = ["IterationLog", "SolverFDDP"]
