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

__all__ = ["WbmpcError", "__version__"]
