"""wbmpc: whole-body model-predictive walking control on Pinocchio.

The library is split in top-level packages, one concept each:

- ``sequencer``: DCM footstep sequencer (one QP per step, Algorithm 1 of Roux et al. 2024).
- ``sensitivity``: Fiacco sensitivity of the footstep QP to DCM disturbances.
- ``wbmpc``: the whole-body optimal control pipeline (state, actions, costs, FDDP, MPC).
- ``robots``: robot descriptions shared by Pinocchio and MuJoCo.
- ``sim``: MuJoCo closed loop, scenarios, metrics and plots.
"""

from wbmpc.errors import WbmpcError

__version__ = "0.1.0"

_LAZY = {
    "WalkingOCPConfig": "wbmpc.walking",
    "StateWeights": "wbmpc.walking",
    "WalkingOCP": "wbmpc.walking",
    "WalkingMPC": "wbmpc.mpc",
    "MPCSolution": "wbmpc.mpc",
    "ShootingProblem": "wbmpc.problem",
    "SolverFDDP": "wbmpc.solvers.fddp",
    "StateMultibody": "wbmpc.state",
}


def __getattr__(name: str):
    """Import the heavy (Pinocchio) parts on first use, so ``import wbmpc`` stays light."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'wbmpc' has no attribute {name!r}")


__all__ = ["WbmpcError", "__version__", *_LAZY]
