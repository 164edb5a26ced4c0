"""Derivatives of an action model by central finite differences (Crocoddyl's ActionModelNumDiff).

The reference the analytic derivatives are tested against. Differences are taken on the state
manifold: the state is displaced by ±h along each tangent direction (x ⊕ ±h eᵢ, the state's
``integrate``) and the next states are compared by the state difference at the unperturbed next
state, so Fx, Fu are expressed in the same tangent spaces as the analytic ones:

    Fx[:, i] = ((f(x ⊕ h eᵢ, u) ⊖ f(x, u)) − (f(x ⊕ −h eᵢ, u) ⊖ f(x, u))) / 2h

The step is h = disturbance · (1 + |zᵢ|), zᵢ the velocity or control component the direction
moves (1 for configuration directions, whose coordinates are O(1)); the default disturbance
eps^(1/3) ≈ 6e-6 balances the O(h²) truncation and O(eps/h) rounding errors of central
differences (both ~eps^(2/3) relative to the differenced values).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.integrator import ActionData

DISTURBANCE = float(np.finfo(float).eps ** (1.0 / 3.0))
"""Default relative step of the central differences, eps^(1/3)."""


def _check_disturbance(disturbance: float) -> float:
    if not (isinstance(disturbance, (int, float)) and np.isfinite(disturbance) and 0 < disturbance < 1e-1):
        raise ParameterError(f"disturbance={disturbance!r} must be a number in (0, 0.1)")
    return float(disturbance)


def tangent_steps(state, x: np.ndarray, disturbance: float = DISTURBANCE) -> np.ndarray:
    """Steps h (ndx,) of the tangent directions at x: disturbance on the configuration directions,
    disturbance · (1 + |v_i|) on the velocity ones."""
    nq, nv = state.nq, state.nv
    return disturbance * np.concatenate([np.ones(nv), 1.0 + np.abs(x[nq:nq + nv])])


def tangent_jacobian(state, f: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                     disturbance: float = DISTURBANCE) -> np.ndarray:
    """∂f/∂dx at x (m, ndx) by central differences along the tangent space, f: state -> (m,)."""
    disturbance = _check_disturbance(disturbance)
    steps = tangent_steps(state, x, disturbance)
    dx = np.zeros(state.ndx)
    columns = []
    for i, h in enumerate(steps):
        dx[i] = h
        plus = np.atleast_1d(f(state.integrate(x, dx)))
        dx[i] = -h
        minus = np.atleast_1d(f(state.integrate(x, dx)))
        dx[i] = 0.0
        columns.append((plus - minus) / (2.0 * h))
    return np.stack(columns, axis=1)


def vector_jacobian(f: Callable[[np.ndarray], np.ndarray], u: np.ndarray,
                    disturbance: float = DISTURBANCE) -> np.ndarray:
    """∂f/∂u at u (m, n) by central differences, steps disturbance · (1 + |u_i|)."""
    disturbance = _check_disturbance(disturbance)
    u = np.asarray(u, dtype=float)
    columns = []
    for i in range(u.size):
        h = disturbance * (1.0 + abs(u[i]))
        plus, minus = u.copy(), u.copy()
        plus[i] += h
        minus[i] -= h
        columns.append((np.atleast_1d(f(plus)) - np.atleast_1d(f(minus))) / (2.0 * h))
    return np.stack(columns, axis=1)


class ActionDataNumDiff(ActionData):
    """Buffers of :class:`ActionModelNumDiff`: the wrapped model's data (``model_data``, after
    :meth:`ActionModelNumDiff.calc` at the unperturbed point), xnext (nx,), cost, Fx (ndx, ndx),
    Fu (ndx, nu), Lx (ndx,), Lu (nu,), and, with ``hessians``, Lxx, Lxu, Luu."""

    def __init__(self, model: "ActionModelNumDiff"):
        super().__init__(model.state, model.nu)
        self.model_data = model.model.createData()


class ActionModelNumDiff:
    """An action model whose derivatives are central finite differences of another's calc().

    Args:
        model: the action model (``calc(data, x, u=None)`` filling ``xnext`` and ``cost``,
            ``createData()``, ``state``, ``nu``), e.g. an
            :class:`~wbmpc.ocp.integrator.IntegratedActionModelEuler`.
        disturbance: relative step, in (0, 0.1); default eps^(1/3) (see the module docstring).
        hessians: also fill Lxx, Lxu, Luu, the exact Hessians of the cost by central second
            differences (step disturbance^(3/4) ~ eps^(1/4); O(n²) calc() calls). They are not
            Gauss-Newton Hessians: compare them to analytic ones only where the residuals are
            linear. False (default): left at zero.

    Only calc() of the wrapped model is called; its data is evaluated anew for every step.
    """

    def __init__(self, model, disturbance: float = DISTURBANCE, hessians: bool = False):
        if not isinstance(hessians, bool):
            raise ParameterError(f"hessians={hessians!r} must be a boolean")
        self.model = model
        self.state = model.state
        self.nu = model.nu
        self.disturbance = _check_disturbance(disturbance)
        self.hessians = hessians

    def createData(self) -> ActionDataNumDiff:
        return ActionDataNumDiff(self)

    def _evaluate(self, x: np.ndarray, u: np.ndarray | None) -> tuple[np.ndarray, float]:
        data = self.model.createData()
        self.model.calc(data, x, u)
        return np.array(data.xnext, dtype=float), float(data.cost)

    def calc(self, data: ActionDataNumDiff, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.xnext and data.cost (the wrapped model's values)."""
        self.model.calc(data.model_data, x, u)
        data.xnext[:] = data.model_data.xnext
        data.cost = float(data.model_data.cost)

    def calcDiff(self, data: ActionDataNumDiff, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill data.Fx, Fu, Lx, Lu (and the Hessians with ``hessians``) at (x, u); u None: a
        terminal node (Fu, Lu, Lxu, Luu untouched)."""
        state = self.state
        x = np.asarray(x, dtype=float)
        self.calc(data, x, u)
        xnext0 = data.xnext.copy()

        def next_and_cost_of_x(xx):
            xnext, cost = self._evaluate(xx, u)
            return np.concatenate([state.diff(xnext0, xnext), [cost]])

        J = tangent_jacobian(state, next_and_cost_of_x, x, self.disturbance)
        data.Fx[:] = J[:-1]
        data.Lx[:] = J[-1]
        if u is not None:
            u = np.asarray(u, dtype=float)

            def next_and_cost_of_u(uu):
                xnext, cost = self._evaluate(x, uu)
                return np.concatenate([state.diff(xnext0, xnext), [cost]])

            J = vector_jacobian(next_and_cost_of_u, u, self.disturbance)
            data.Fu[:] = J[:-1]
            data.Lu[:] = J[-1]
        if self.hessians:
            self._hessians(data, x, u)

    def _hessians(self, data: ActionDataNumDiff, x: np.ndarray, u: np.ndarray | None) -> None:
        """Cost Hessian over z = (dx, du) by central second differences at (x, u)."""
        state = self.state
        ndx = state.ndx
        nu = 0 if u is None else self.nu
        h_rel = self.disturbance ** 0.75
        steps = np.concatenate([tangent_steps(state, x, h_rel),
                                h_rel * (1.0 + np.abs(u)) if u is not None else np.zeros(0)])
        n = ndx + nu

        def cost_at(z):
            uu = None if u is None else u + z[ndx:]
            return self._evaluate(state.integrate(x, z[:ndx]), uu)[1]

        H = np.zeros((n, n))
        z = np.zeros(n)
        for i in range(n):
            for j in range(i, n):
                values = []
                for si, sj in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)):
                    z[:] = 0.0
                    z[i] += si * steps[i]
                    z[j] += sj * steps[j]
                    values.append(cost_at(z))
                H[i, j] = H[j, i] = (values[0] - values[1] - values[2] + values[3]) / (4.0 * steps[i] * steps[j])
        data.Lxx[:] = H[:ndx, :ndx]
        if u is not None:
            data.Lxu[:] = H[:ndx, ndx:]
            data.Luu[:] = H[ndx:, ndx:]
