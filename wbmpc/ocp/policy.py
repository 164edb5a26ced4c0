"""The feedback law of an MPC solution, evaluated between two updates (at 1 kHz in the closed loop).

    u(t, x) = u_k + K_k (x ⊖ x_k)

with the library's gain sign (K = ∂u*/∂x, the paper's eqs. 25-26; Crocoddyl's K is its negative)
and ⊖ the state difference (``pin.difference`` on q, plain difference on v). The solver's rollout
applies the same law (with its line-search terms) through the same compiled kernel,
:func:`wbmpc.ocp.kernels.feedback.feedback_control`.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.feedback import policy_control
from wbmpc.ocp.state import StateMultibody


class RiccatiPolicy:
    """Time-indexed affine policy u(t, x) = u_k + K_k (x ⊖ x_k) from an MPC solution.

    The node is k = floor((t − t0)/dt + 1e-9) + delay_nodes, clipped to [0, N − 1]. With
    ``interpolate``, u and the reference state are interpolated linearly between nodes k and k + 1
    (``pin.interpolate`` on q) by α = (t − t0)/dt − floor(...) clipped to [0, 1]; at k = N − 1 the
    node is held.

    Args:
        state: the state the solution lives in.
        t0: time of node 0 [s].
        dt: node spacing [s], > 0.
        xs: states (N + 1, nx) (or (N, nx)), Pinocchio convention.
        us: controls (N, nu) [N·m].
        K: gains (N, nu, ndx), library sign.
        delay_nodes: nodes added to the index (1: node 1 is "now" when the solution arrives), >= 0.
        interpolate: interpolate between nodes (otherwise zero-order hold).

    The arrays are copied. :meth:`control` allocates only its output; free-flyer robots take one
    compiled call (Pinocchio only near a half-turn relative rotation).
    """

    def __init__(self, state: StateMultibody, t0: float, dt: float, xs, us, K, delay_nodes: int = 0,
                 interpolate: bool = False):
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt={dt!r} s must be a finite number > 0")
        if not (isinstance(t0, (int, float)) and math.isfinite(t0)):
            raise ParameterError(f"t0={t0!r} s must be a finite number")
        if isinstance(delay_nodes, bool) or not isinstance(delay_nodes, (int, np.integer)) or delay_nodes < 0:
            raise ParameterError(f"delay_nodes={delay_nodes!r} must be an integer >= 0")
        if not isinstance(interpolate, (bool, np.bool_)):
            raise ParameterError(f"interpolate={interpolate!r} must be a boolean")
        us = np.array(us, dtype=float, order="C")
        if us.ndim != 2 or us.shape[0] < 1:
            raise ParameterError(f"us has shape {us.shape}, expected (N, nu) with N >= 1")
        N, nu = us.shape
        xs = np.array(xs, dtype=float, order="C")
        if xs.ndim != 2 or xs.shape[1] != state.nx or xs.shape[0] not in (N, N + 1):
            raise ParameterError(f"xs has shape {xs.shape}, expected ({N} or {N + 1}, nx={state.nx})")
        K = np.asarray(K, dtype=float)
        if K.shape != (N, nu, state.ndx):
            raise ParameterError(f"K has shape {K.shape}, expected ({N}, {nu}, {state.ndx})")
        self.state = state
        self.t0, self.dt = float(t0), float(dt)
        self.delay_nodes = int(delay_nodes)
        self.interpolate = bool(interpolate)
        self.xs, self.us = xs, us
        self.K = np.array(K, order="C")
        self.N, self.nu = N, nu
        self._K_crocoddyl = np.ascontiguousarray(-K)  # the kernel's sign: u − α k − K dx
        self._no_feedforward = np.zeros(nu)
        self._x_ref = np.zeros(state.nx)
        self._dx = np.zeros(state.ndx)
        self._compiled = state._compiled_difference

    def _node_and_fraction(self, t: float) -> tuple[int, float]:
        elapsed = (t - self.t0) / self.dt
        base = math.floor(elapsed + 1e-9)
        k = min(max(base + self.delay_nodes, 0), self.N - 1)
        if not self.interpolate or k + 1 >= self.N:
            return k, -1.0
        return k, min(max(elapsed - base, 0.0), 1.0)

    def node(self, t: float) -> int:
        """Index of the node applied at time t [s]."""
        return self._node_and_fraction(t)[0]

    def control(self, t: float, x: np.ndarray, feedback: bool = True) -> np.ndarray:
        """Control at time t [s] and measured state x (nx,), shape (nu,) [N·m]; ``feedback=False``
        returns the feedforward u_k (interpolated if so configured)."""
        k, alpha = self._node_and_fraction(t)
        out = np.empty(self.nu)
        nq = self.state.nq
        if self._compiled:
            code = policy_control(self.xs, self.us, self._K_crocoddyl, self._no_feedforward, k, alpha, x, feedback, nq,
                                  self._x_ref, self._dx, out)
            if code == 0:
                return out
        return self._control_pinocchio(k, alpha, x, feedback, out)

    def _control_pinocchio(self, k: int, alpha: float, x: np.ndarray, feedback: bool, out: np.ndarray) -> np.ndarray:
        """The same law with Pinocchio's Lie-group operations (other robots; near a half turn)."""
        nq, model = self.state.nq, self.state.pinocchio
        xs, us = self.xs, self.us
        if alpha >= 0.0:
            out[:] = (1.0 - alpha) * us[k] + alpha * us[k + 1]
            x_ref = self._x_ref
            x_ref[:nq] = pin.interpolate(model, xs[k, :nq], xs[k + 1, :nq], alpha)
            x_ref[nq:] = (1.0 - alpha) * xs[k, nq:] + alpha * xs[k + 1, nq:]
        else:
            out[:] = us[k]
            x_ref = xs[k]
        if feedback:
            self.state.diff(x_ref, np.asarray(x, dtype=float), out=self._dx)
            out += self.K[k] @ self._dx
        return out
