"""Route (b): the parametric sensitivity of an OCP by central differences of re-solved problems.

For each parameter j the problem is re-solved at p ± h e_j (warm-started from the base solution and
converged tightly by the caller's ``solve``) and

    dx_k/dp_j ≈ (x_k(p + h e_j) ⊖ x_k(p − h e_j)) / 2h,   du_k/dp_j ≈ (u_k(p + h e_j) − u_k(p − h e_j)) / 2h,

and likewise for any other output ``solve`` returns. This measures the derivative of the true
solution map (whatever Hessian the solver uses): truncation error O(h²), plus the re-solves'
convergence error divided by h.
"""

from __future__ import annotations

import math
import time

import numpy as np

from sensitivity.ocp_riccati import OcpSensitivity
from wbmpc.errors import ParameterError


def check_fd_step(fd_step: float) -> float:
    """The finite-difference step as a float; ParameterError unless finite and > 0."""
    try:
        value = float(fd_step)
    except (TypeError, ValueError):
        raise ParameterError(f"fd_step={fd_step!r} must be a finite number > 0") from None
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"fd_step={fd_step!r} must be a finite number > 0")
    return value


def finite_difference_sensitivity(state, solve, parameters, fd_step: float) -> tuple[OcpSensitivity, dict]:
    """Central differences of re-solved problems.

    Args:
        state: the problem's state (its ``diff`` gives x1 ⊖ x0).
        solve: p (m,) -> dict with "xs" (N + 1, nx), "us" (N, nu) and any other arrays (outputs).
        parameters: the base p (m,).
        fd_step: h, in the parameters' unit, > 0.

    Returns:
        (OcpSensitivity, outputs) with outputs name -> derivative (output shape + (m,)).
    """
    h = check_fd_step(fd_step)
    p = np.asarray(parameters, dtype=float)
    tic = time.perf_counter()
    columns_x, columns_u, columns_out = [], [], {}
    for j in range(p.size):
        step = np.zeros(p.size)
        step[j] = h
        plus, minus = solve(p + step), solve(p - step)
        columns_x.append(np.array([state.diff(a, b) for a, b in zip(minus["xs"], plus["xs"])]) / (2.0 * h))
        columns_u.append((plus["us"] - minus["us"]) / (2.0 * h))
        for name, value in plus.items():
            if name not in ("xs", "us"):
                columns_out.setdefault(name, []).append((np.asarray(value) - np.asarray(minus[name])) / (2.0 * h))
    dxs = np.stack(columns_x, axis=-1)
    dus = np.stack(columns_u, axis=-1)
    outputs = {name: np.stack(columns, axis=-1) for name, columns in columns_out.items()}
    return (OcpSensitivity(dxs, dus, f"finite_differences (central, h={h:g})",
                           {"re-solves": time.perf_counter() - tic}), outputs)
