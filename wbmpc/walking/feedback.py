"""The 1 kHz feedback law: the latest MPC solution as a Riccati policy, with a simulated latency.

    tau = u_k + K_k (x_meas ⊖ x_k),     K = du*/dx  (library-wide gain convention)

k is node 1 of the latest solution (the paper's computation-delay model, ``delay_nodes=1``) or node
0, advanced by the time elapsed since that solution was computed, so a failed update keeps
following the last good plan. The law evaluates whatever :class:`~wbmpc.ocp.policy.RiccatiPolicy`
it holds; it does not know how the policy was produced.
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import NoSolutionError
from wbmpc.ocp.mpc import MPCSolution
from wbmpc.ocp.policy import RiccatiPolicy
from wbmpc.ocp.state import StateMultibody


class FeedbackLaw:
    """Holds the policy the 1 kHz loop follows and the ones still "being computed".

    Args:
        state: the robot's state manifold.
        node_dt: node spacing of the MPC's solutions [s].
        delay_nodes: 0 or 1, the node applied when a solution arrives (see the module docstring).
        interpolate: interpolate u and x between nodes k and k + 1 (otherwise zero-order hold).
        feedback: apply the Riccati gains (False: feed-forward u_k only).
        computation_delay: simulated solver latency [s]: a solution computed from the state at t
            is applied from t + computation_delay on (its node index still counts from t).
    """

    def __init__(self, state: StateMultibody, node_dt: float, delay_nodes: int, interpolate: bool,
                 feedback: bool, computation_delay: float) -> None:
        self.state = state
        self.node_dt, self.delay_nodes = float(node_dt), int(delay_nodes)
        self.interpolate, self.feedback = bool(interpolate), bool(feedback)
        self.computation_delay = float(computation_delay)
        self.policy: RiccatiPolicy | None = None
        self._pending: list[tuple[float, RiccatiPolicy]] = []  # (activation time [s], policy)

    def hand_over(self, t: float, solution: MPCSolution) -> None:
        """A new MPC solution computed from the state at ``t`` [s] (applied after the latency)."""
        policy = RiccatiPolicy(self.state, float(solution.t), self.node_dt, np.array(solution.xs),
                               np.array(solution.us), np.array(solution.K), delay_nodes=self.delay_nodes,
                               interpolate=self.interpolate)
        if self.computation_delay > 0.0 and self.policy is not None:
            self._pending.append((t + self.computation_delay, policy))
        else:
            self.policy = policy

    @property
    def age_reference(self) -> float | None:
        """Time of node 0 of the policy followed now [s] (None before the first)."""
        return None if self.policy is None else self.policy.t0

    def control(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torque command (nu,) [N·m] at time ``t`` for the measured state ``x`` (nx,).

        Raises:
            NoSolutionError: no solution yet (the first MPC update failed).
        """
        while self._pending and self._pending[0][0] <= t + 1e-9:
            self.policy = self._pending.pop(0)[1]
        if self.policy is None:
            raise NoSolutionError("FeedbackLaw.control(): no MPC solution yet (the first update failed)")
        return self.policy.control(t, x, feedback=self.feedback)
