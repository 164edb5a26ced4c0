"""QP backends of the footstep sequencer, one per file (``exact`` lives in ``sequencer.step_qp``).

Every backend has a ``name`` and ``solve(problem: StepProblem) -> StepSolution``, keeps its
solver workspace between calls (set up once, then updated and warm-started), and raises
:class:`sequencer.step_qp.InfeasibleStep` / :class:`sequencer.step_qp.StepQPError` on failure.
"""

from __future__ import annotations

from wbmpc.errors import ParameterError

BACKEND_NAMES = ("exact", "osqp", "proxqp")


def make_backend(name: str):
    """Return a new backend instance by name: ``"exact"``, ``"osqp"`` or ``"proxqp"``."""
    if name == "exact":
        from sequencer.step_qp import ExactBackend

        return ExactBackend()
    if name == "osqp":
        from sequencer.backends.osqp_ import OsqpBackend

        return OsqpBackend()
    if name == "proxqp":
        from sequencer.backends.proxqp_ import ProxqpBackend

        return ProxqpBackend()
    raise ParameterError(f"backend={name!r} is not available (choose from {list(BACKEND_NAMES)})")
