"""Compiled cost-sum pieces: the row-wise dead-zone quadratic (every activation of
:mod:`wbmpc.ocp.activations` is one), its value and Gauss-Newton derivatives over stacked residual
rows, and the dt scaling of integrated cost derivatives."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def dead_zone(r, w, lb, ub, scale):
    """The activation of one residual row, the only definition in the library: the value
    scale · ½ w e² with e = min(r − lb, 0) + max(r − ub, 0), its gradient coefficient c = scale w e
    and Gauss-Newton Hessian coefficient h = scale w outside the dead zone (lb < r < ub), 0 inside.
    Quadratics are the case lb = ub = 0 (then e = r)."""
    below = r - lb
    above = r - ub
    e = min(below, 0.0) + max(above, 0.0)
    sw = scale * w
    return 0.5 * sw * e * e, sw * e, sw if (below <= 0.0 or above >= 0.0) else 0.0


@njit(cache=True)
def dead_zone_rows(r, w, lb, ub, Ar, Arr):
    """Value Σ ½ wᵢ eᵢ² of the rows r (nr,), gradient Ar (nr,) and Hessian diagonal Arr (nr,)
    (:func:`dead_zone` row by row; the activations' calc and calcDiff)."""
    total = 0.0
    for i in range(r.size):
        value, c, h = dead_zone(r[i], w[i], lb[i], ub[i], 1.0)
        total += value
        Ar[i] = c
        Arr[i] = h
    return total


@njit(cache=True)
def cost_rows_value(r, row_term, term_scale, w, lb, ub, term_cost):
    """Σ over rows of term_scale[term] · ½ w e² (:func:`dead_zone`).

    Rows of inactive terms (term_scale 0) are skipped, whatever their stale residual holds.
    Fills term_cost (n_terms,) and returns the total.
    """
    term_cost[:] = 0.0
    for i in range(r.size):
        scale = term_scale[row_term[i]]
        if scale == 0.0:
            continue
        term_cost[row_term[i]] += dead_zone(r[i], w[i], lb[i], ub[i], scale)[0]
    total = 0.0
    for j in range(term_cost.size):
        total += term_cost[j]
    return total


@njit(cache=True)
def cost_rows_derivatives(r, R, row_term, term_scale, w, lb, ub, gradient, hessian):
    """Gauss-Newton gradient Rᵀ c (n,) and Hessian Rᵀ diag(h) R (n, n) of the stacked residual
    rows R (nrows, n), c and h the :func:`dead_zone` coefficients of each row."""
    nrows, n = R.shape
    coef_g = np.zeros(nrows)
    coef_h = np.zeros(nrows)
    for i in range(nrows):
        scale = term_scale[row_term[i]]
        if scale == 0.0:
            continue
        _, coef_g[i], coef_h[i] = dead_zone(r[i], w[i], lb[i], ub[i], scale)
    gradient[:] = 0.0
    hessian[:, :] = 0.0
    for i in range(nrows):
        cg = coef_g[i]
        ch = coef_h[i]
        if cg == 0.0 and ch == 0.0:
            continue
        Ri = R[i]
        for a in range(n):
            ra = Ri[a]
            if ra == 0.0:
                continue
            gradient[a] += ra * cg
            if ch != 0.0:
                v = ch * ra
                for b in range(a, n):
                    hessian[a, b] += v * Ri[b]
    for a in range(n):
        for b in range(a + 1, n):
            hessian[b, a] = hessian[a, b]


@njit(cache=True)
def scale_cost_derivatives(dt, gradient, hessian, ndx, Lx, Lu, Lxx, Lxu, Luu):
    """Integrated cost derivatives: dt × the continuous gradient (ndx + nu,) and Hessian blocks."""
    n = gradient.size
    for i in range(ndx):
        Lx[i] = dt * gradient[i]
        for j in range(ndx):
            Lxx[i, j] = dt * hessian[i, j]
        for j in range(ndx, n):
            Lxu[i, j - ndx] = dt * hessian[i, j]
    for i in range(ndx, n):
        Lu[i - ndx] = dt * gradient[i]
        for j in range(ndx, n):
            Luu[i - ndx, j - ndx] = dt * hessian[i, j]
