"""The generic optimal-control core: state, actuation, contacts, contact dynamics, residuals,
activations, costs, the shooting problem and its evaluators (node by node or batched), FDDP and
the receding-horizon MPC.

It follows Crocoddyl's model/data contract and imports nothing of the planners, robots, walking
application or simulation (an import-linter contract in pyproject.toml holds this).
"""

from wbmpc.ocp.mpc import MPCSolution, MPCSolver, RecedingHorizonMPC
from wbmpc.ocp.problem import ShootingProblem
from wbmpc.ocp.solvers.fddp import SolverFDDP
from wbmpc.ocp.state import StateMultibody

__all__ = ["MPCSolution", "MPCSolver", "RecedingHorizonMPC", "ShootingProblem", "SolverFDDP", "StateMultibody"]
