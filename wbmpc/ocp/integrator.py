"""Explicit (semi-implicit) Euler integration of a differential action model.

    v⁺ = v + a dt,   q⁺ = q ⊕ (v dt + a dt²),   l = dt · l_continuous(x, u)

(Crocoddyl's IntegratedActionModelEuler). The step and its Jacobians are the compiled kernels of
:mod:`wbmpc.ocp.kernels.integration`, which the batched problem calls too (free-flyer robots use
the compiled Lie-group operations, others Pinocchio's). A node built with ``dt = 0`` is a terminal node: it
is evaluated with ``u=None``, its cost is the differential model's cost unscaled and x⁺ = x.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.costs import scale_cost_derivatives
from wbmpc.ocp.kernels.integration import euler_step_tangent, euler_transition_jacobians, free_flyer_euler_step
from wbmpc.ocp.kernels.lie import free_flyer_dintegrate


class IntegratedActionModelEuler:
    """Discrete node x⁺ = f(x, u) with cost l(x, u).

    Args:
        differential: continuous-time model (e.g. contact forward dynamics).
        dt: time step [s], ≥ 0 (0 for a terminal node).
    """

    def __init__(self, differential, dt: float):
        if not (np.isfinite(dt) and dt >= 0):
            raise ParameterError(f"dt={dt} s must be finite and >= 0")
        self.differential = differential
        self.state = differential.state
        self.nu = differential.nu
        self.dt = float(dt)

    def createData(self) -> "IntegratedActionDataEuler":
        return IntegratedActionDataEuler(self)

    def calc(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.xnext (nx,) and data.cost."""
        diff = self.differential
        dd = data.differential
        diff.calc(dd, x, u)
        if u is None:
            data.dx[:] = 0.0
            data.xnext[:] = x
            data.cost = dd.cost
            return
        state = self.state
        nq, nv = state.nq, state.nv
        dt = self.dt
        if state._compiled_difference:
            free_flyer_euler_step(x, dd.xout, dt, data.dx, data.xnext)
        else:
            euler_step_tangent(x[nq:], dd.xout, dt, data.dx, data.xnext[nq:])
            data.xnext[:nq] = pin.integrate(state.pinocchio, x[:nq], data.dx[:nv])
        data.cost = dt * dd.cost

    def calcDiff(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.Fx (ndx, ndx), Fu (ndx, nu), Lx, Lu, Lxx, Lxu, Luu. Needs calc first."""
        diff = self.differential
        dd = data.differential
        diff.calcDiff(dd, x, u)
        if u is None:
            data.Fx[:] = 0.0
            data.Fx[np.diag_indices(self.state.ndx)] = 1.0
            data.Lx[:] = dd.Lx
            data.Lxx[:] = dd.Lxx
            return
        dt = self.dt
        J_q, J_dq, n_base = self._integrate_jacobians(x, data.dx[: self.state.nv], data.J_q, data.J_dq)
        euler_transition_jacobians(dd.Fx, dd.Fu, J_q, J_dq, dt, n_base, data.Fx, data.Fu)
        costs = dd.costs
        scale_cost_derivatives(dt, costs.gradient, costs.hessian, *costs.hessian_entries,
                               data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu)

    def calcDiffDt(self, data, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Analytic derivatives of the node with respect to its spacing dt (a running node; needs
        calcDiff at (x, u)).

        With dq = v dt + a dt² and v⁺ = v + a dt: ∂x⁺/∂dt = [J_dq (v + 2 a dt); a] in the tangent
        space at x⁺ (J_dq = ∂(q ⊕ δ)/∂δ at δ = dq), and since l = dt · l_c(x, u),
        ∂Lx/∂dt = ∂l_c/∂x, ∂Lu/∂dt = ∂l_c/∂u.

        Returns:
            (dxnext_ddt (ndx,), dLx_ddt (ndx,), dLu_ddt (nu,)).
        """
        state = self.state
        nq, nv = state.nq, state.nv
        dd = data.differential
        a = dd.xout
        J_dq = self._integrate_jacobians(x, data.dx[: state.nv])[1]
        dxnext = np.empty(state.ndx)
        dxnext[:nv] = J_dq @ (x[nq:] + 2.0 * self.dt * a)
        dxnext[nv:] = a
        return dxnext, dd.Lx.copy(), dd.Lu.copy()

    def transitionJacobiansTransposeDt(self, data, x: np.ndarray, lam: np.ndarray,
                                       step: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
        """∂(Fxᵀ λ)/∂dt (ndx,) and ∂(Fuᵀ λ)/∂dt (nu,) for a fixed costate λ (ndx,) at x⁺ (needs
        calcDiff at (x, u)): the second-order term of the dynamics in (x, dt) a parametric
        sensitivity contracts with the costate.

        The acceleration derivatives do not depend on dt; Fx, Fu depend on it polynomially and
        through the Lie-group Jacobians of q ⊕ dq(dt), which have no closed-form derivative in
        Pinocchio. The transition Jacobians (the compiled kernel of calcDiff) are therefore
        differenced centrally in dt with ``step`` [s] (error O(step²), ~1e-10 relative).
        """
        state = self.state
        nq, ndx, nu = state.nq, state.ndx, self.nu
        dd = data.differential
        a = dd.xout
        v = x[nq:]
        out_x = np.zeros(ndx)
        out_u = np.zeros(nu)
        Fx = np.empty((ndx, ndx))
        Fu = np.empty((ndx, nu))
        for sign in (1.0, -1.0):
            dt = self.dt + sign * step
            J_q, J_dq, n_base = self._integrate_jacobians(x, v * dt + a * dt * dt)
            euler_transition_jacobians(dd.Fx, dd.Fu, J_q, J_dq, dt, n_base, Fx, Fu)
            out_x += sign * (Fx.T @ lam)
            out_u += sign * (Fu.T @ lam)
        return out_x / (2.0 * step), out_u / (2.0 * step)

    def _integrate_jacobians(self, x: np.ndarray, dq: np.ndarray, J_q: np.ndarray | None = None,
                             J_dq: np.ndarray | None = None):
        """(J_q, J_dq, n_base): Jacobians (nv, nv) of q ⊕ dq with respect to q and dq (the node's
        step data.dx[:nv] in calcDiff), identity outside the leading n_base block; the compiled
        free-flyer path writes them into J_q, J_dq when given (a node data's buffers)."""
        state = self.state
        nq, nv = state.nq, state.nv
        q = x[:nq]
        if state._compiled_difference:
            J_q = np.zeros((nv, nv)) if J_q is None else J_q
            J_dq = np.zeros((nv, nv)) if J_dq is None else J_dq
            free_flyer_dintegrate(q, dq, J_q, J_dq)
            return J_q, J_dq, 6
        model = state.pinocchio
        return pin.dIntegrate(model, q, dq, pin.ARG0), pin.dIntegrate(model, q, dq, pin.ARG1), nv


class ActionData:
    """What every action model's data holds (Crocoddyl's ActionDataAbstract): xnext (nx,), cost,
    the transition's Fx (ndx, ndx), Fu (ndx, nu) and the cost's Lx (ndx,), Lu (nu,), Lxx (ndx,
    ndx), Lxu (ndx, nu), Luu (nu, nu), allocated once."""

    def __init__(self, state, nu: int):
        ndx = state.ndx
        self.xnext = np.zeros(state.nx)
        self.cost = 0.0
        self.Fx = np.zeros((ndx, ndx))
        self.Fu = np.zeros((ndx, nu))
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))


class IntegratedActionDataEuler(ActionData):
    """Per-node buffers of :class:`IntegratedActionModelEuler`."""

    def __init__(self, model: IntegratedActionModelEuler):
        state = model.state
        super().__init__(state, model.nu)
        self.differential = model.differential.createData()
        self.dx = np.zeros(state.ndx)
        self.J_q = np.zeros((state.nv, state.nv))  # Jacobians of q ⊕ dq (compiled free-flyer path)
        self.J_dq = np.zeros((state.nv, state.nv))
