"""wbmpc: whole-body model-predictive walking control on Pinocchio.

The library is split in layers (held by import-linter contracts in pyproject.toml, see
docs/architecture.md), from the bottom up:

- ``wbmpc.errors``, ``wbmpc.config``, ``wbmpc.jsonable``: shared leaves (errors, TOML presets,
  JSON conversion);
- ``robots``: robot descriptions shared by Pinocchio and MuJoCo, state conventions;
- ``wbmpc.ocp``: the generic optimal-control core (state, actuation, contacts, contact dynamics,
  residuals, activations, costs, shooting problem and its evaluators, FDDP, receding-horizon MPC);
  ``sequencer``: footstep planners (DCM step QP, Algorithm 1) and the contact-schedule types;
- ``sensitivity``: sensitivities of the planners' solutions;
- ``wbmpc.walking``: the walking application (OCP builder from a contact schedule, the
  controller composed of planner + MPC + feedback + estimators, per-robot presets);
- ``sim``: MuJoCo closed loop, scenarios, metrics, plots, campaigns;
- ``bench``: benchmarks; ``wbmpc.cli``: the ``wbmpc`` command line, above all.

Importing ``wbmpc`` itself loads only the error types (the planners use them).
"""

from wbmpc.errors import ParameterError, SolverError, WbmpcError

__version__ = "0.1.0"

__all__ = ["ParameterError", "SolverError", "WbmpcError", "__version__"]
