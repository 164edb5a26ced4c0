"""Multibody state on the Lie group: x = [q (nq,), v (nv,)], tangent dx = [dq (nv,), dv (nv,)].

Pinocchio conventions throughout: for a floating base, q[0:3] is the base position in the world
frame [m], q[3:7] the base orientation quaternion (x, y, z, w), and v[0:6] the base spatial
velocity expressed in the base (LOCAL) frame [m/s, rad/s].

The state difference ``diff(x0, x1) = x1 ⊖ x0`` is the tangent vector that moves ``x0`` to ``x1``:
``pin.difference`` on the configuration and a plain difference on the velocity.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.lie import free_flyer_ddifference_second, free_flyer_state_difference
from wbmpc.ocp.kernels.residuals import state_difference_many


class StateMultibody:
    """State of a Pinocchio multibody model (configuration manifold × velocity vector space).

    Args:
        pinocchio_model: the robot model; it is shared, never modified.

    Attributes:
        nq, nv: configuration and velocity dimensions.
        nx: state dimension nq + nv.
        ndx: tangent-space dimension 2 nv.
    """

    def __init__(self, pinocchio_model: pin.Model):
        self.pinocchio = pinocchio_model
        self.nq = pinocchio_model.nq
        self.nv = pinocchio_model.nv
        self.nx = self.nq + self.nv
        self.ndx = 2 * self.nv
        # A free-flyer root followed by 1-dof joints has a compiled difference (same values as
        # pin.difference to ~1e-13; Pinocchio takes over near a half-turn relative rotation).
        self._compiled_difference = (
            pinocchio_model.njoints >= 2 and pinocchio_model.joints[1].nq == 7 and pinocchio_model.joints[1].nv == 6
            and self.nq == self.nv + 1)
        self._all_rows = self._rows_ok = None  # masks of diff_many

    def zero(self) -> np.ndarray:
        """Neutral configuration and zero velocity, shape (nx,)."""
        return np.concatenate([pin.neutral(self.pinocchio), np.zeros(self.nv)])

    def check_state(self, name: str, x: np.ndarray) -> np.ndarray:
        """Return ``x`` as a float array after checking its shape (nx,) and finiteness."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.nx,):
            raise ParameterError(f"{name} has shape {x.shape}, expected ({self.nx},) = [q (nq={self.nq}), v (nv={self.nv})]")
        if not np.all(np.isfinite(x)):
            raise ParameterError(f"{name} must be finite, got {x!r}")
        return x

    def diff(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Tangent vector x1 ⊖ x0, shape (ndx,)."""
        nq, nv = self.nq, self.nv
        if out is None:
            out = np.empty(self.ndx)
        if self._compiled_difference and free_flyer_state_difference(x0, x1, nq, out):
            return out
        out[:nv] = pin.difference(self.pinocchio, x0[:nq], x1[:nq])
        np.subtract(x1[nq:], x0[nq:], out=out[nv:])
        return out

    def diff_many(self, X0: np.ndarray, X1: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Row-wise X1[k] ⊖ X0[k] of (T, nx) arrays into out (T, ndx) (one compiled call, the loop
        the batched state residual runs)."""
        T = out.shape[0]
        if self._compiled_difference:
            if self._all_rows is None or self._all_rows.size != T:
                self._all_rows, self._rows_ok = np.ones(T, dtype=np.bool_), np.ones(T, dtype=np.bool_)
            if state_difference_many(X0, X1, self.nq, self._all_rows, out, self._rows_ok):
                return out
            rows = np.flatnonzero(~self._rows_ok)
        else:
            rows = range(T)
        for k in rows:
            self.diff(X0[k], X1[k], out=out[k])
        return out

    def integrate(self, x: np.ndarray, dx: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """State x ⊕ dx, shape (nx,)."""
        nq, nv = self.nq, self.nv
        if out is None:
            out = np.empty(self.nx)
        out[:nq] = pin.integrate(self.pinocchio, x[:nq], dx[:nv])
        np.add(x[nq:], dx[nv:], out=out[nq:])
        return out

    def Jdiff(self, x0: np.ndarray, x1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of x1 ⊖ x0 with respect to x0 and x1, each shape (ndx, ndx)."""
        nq, nv = self.nq, self.nv
        J0 = np.zeros((self.ndx, self.ndx))
        J1 = np.zeros((self.ndx, self.ndx))
        J0[:nv, :nv] = pin.dDifference(self.pinocchio, x0[:nq], x1[:nq], pin.ARG0)
        J1[:nv, :nv] = pin.dDifference(self.pinocchio, x0[:nq], x1[:nq], pin.ARG1)
        J0[nv:, nv:] = -np.eye(nv)
        J1[nv:, nv:] = np.eye(nv)
        return J0, J1

    def Jdiff_second_q(self, q0: np.ndarray, q1: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Configuration block of ∂(x1 ⊖ x0)/∂x1, shape (nv, nv) (the velocity block is identity);
        compiled for a free flyer (the kernel the batched problem uses), Pinocchio otherwise and
        near a half-turn relative rotation."""
        if out is None:
            out = np.empty((self.nv, self.nv))
        if self._compiled_difference and free_flyer_ddifference_second(q0, q1, out):
            return out
        out[:] = pin.dDifference(self.pinocchio, q0, q1, pin.ARG1)
        return out

    def Jintegrate(self, x: np.ndarray, dx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of x ⊕ dx with respect to x and dx, each shape (ndx, ndx)."""
        nq, nv = self.nq, self.nv
        J0 = np.zeros((self.ndx, self.ndx))
        J1 = np.zeros((self.ndx, self.ndx))
        J0[:nv, :nv] = pin.dIntegrate(self.pinocchio, x[:nq], dx[:nv], pin.ARG0)
        J1[:nv, :nv] = pin.dIntegrate(self.pinocchio, x[:nq], dx[:nv], pin.ARG1)
        J0[nv:, nv:] = np.eye(nv)
        J1[nv:, nv:] = np.eye(nv)
        return J0, J1
