"""Compiled cost-sum pieces: the row-wise dead-zone quadratic (every activation of
:mod:`wbmpc.ocp.activations` is one), its value and Gauss-Newton derivatives over stacked residual
rows, and the dt scaling of integrated cost derivatives."""

from __future__ import annotations

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
def cost_rows_derivatives(r, values, row_start, cols, row_term, term_scale, w, lb, ub, gradient, hessian,
                          symmetric=True):
    """Gauss-Newton gradient Rᵀ c (n,) and Hessian Rᵀ diag(h) R (n, n) of the stacked residual
    rows, c and h the :func:`dead_zone` coefficients of each row.

    R is given by its row-major structural nonzeros: row i holds values[row_start[i]:row_start[i + 1]]
    at the increasing columns cols[row_start[i]:row_start[i + 1]] (a dense R (nrows, n) is the
    pattern of every column: ``R.reshape(-1)``, row_start = n·i). Rows of inactive terms
    (term_scale 0) are skipped. ``symmetric=False`` fills only the upper triangle (what
    :func:`scale_cost_derivatives` reads).
    """
    n = gradient.size
    gradient[:] = 0.0
    hessian[:, :] = 0.0
    for i in range(r.size):
        scale = term_scale[row_term[i]]
        if scale == 0.0:
            continue
        _, cg, ch = dead_zone(r[i], w[i], lb[i], ub[i], scale)
        if cg == 0.0 and ch == 0.0:
            continue
        end = row_start[i + 1]
        for p in range(row_start[i], end):
            ra = values[p]
            if ra == 0.0:
                continue
            a = cols[p]
            gradient[a] += ra * cg
            if ch != 0.0:
                v = ch * ra
                for q in range(p, end):
                    hessian[a, cols[q]] += v * values[q]
    if symmetric:
        for a in range(n):
            for b in range(a + 1, n):
                hessian[b, a] = hessian[a, b]


@njit(cache=True)
def scale_cost_derivatives(dt, gradient, hessian, ndx, Lx, Lu, Lxx, Lxu, Luu):
    """Integrated cost derivatives: dt × the continuous gradient (ndx + nu,) and Hessian blocks,
    read from the Hessian's upper triangle (all a ``symmetric=False`` :func:`cost_rows_derivatives`
    fills)."""
    n = gradient.size
    for i in range(ndx):
        Lx[i] = dt * gradient[i]
        for j in range(i, ndx):
            value = dt * hessian[i, j]
            Lxx[i, j] = value
            Lxx[j, i] = value
        for j in range(ndx, n):
            Lxu[i, j - ndx] = dt * hessian[i, j]
    for i in range(ndx, n):
        Lu[i - ndx] = dt * gradient[i]
        for j in range(i, n):
            value = dt * hessian[i, j]
            Luu[i - ndx, j - ndx] = value
            Luu[j - ndx, i - ndx] = value
