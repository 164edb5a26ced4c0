"""Optimal control solvers."""

from wbmpc.solvers.fddp import IterationLog, SolverFDDP

__all__ = ["IterationLog", "SolverFDDP"]
