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
def add_gauss_newton_rows(r, values, row_start, cols, row_term, term_scale, w, lb, ub, gradient, hessian):
    """Add the Gauss-Newton gradient Rᵀ c to gradient (n,) and the upper triangle of
    Rᵀ diag(h) R to hessian (n, n), c and h the :func:`dead_zone` coefficients of each row of r.

    R is given by its row-major structural nonzeros: row i holds values[row_start[i]:row_start[i + 1]]
    at the increasing columns cols[row_start[i]:row_start[i + 1]] (a dense R (nrows, n) is the
    pattern of every column: ``R.reshape(-1)``, row_start = n·i). Rows of inactive terms
    (term_scale 0) are skipped. Writes only the entries :func:`hessian_entries` lists for the pattern.
    """
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


@njit(cache=True)
def cost_rows_derivatives(r, values, row_start, cols, row_term, term_scale, w, lb, ub, gradient, hessian):
    """Gauss-Newton gradient Rᵀ c (n,) and Hessian Rᵀ diag(h) R (n, n), both triangles, of the
    stacked residual rows (:func:`add_gauss_newton_rows`, from zero)."""
    n = gradient.size
    gradient[:] = 0.0
    hessian[:, :] = 0.0
    add_gauss_newton_rows(r, values, row_start, cols, row_term, term_scale, w, lb, ub, gradient, hessian)
    for a in range(n):
        for b in range(a + 1, n):
            hessian[b, a] = hessian[a, b]


def hessian_entries(row_start: np.ndarray, cols: np.ndarray, ndx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The entries (a, b), a ≤ b, of the Hessian's upper triangle that rows of this Jacobian
    pattern (row_start, cols as :func:`add_gauss_newton_rows` reads them) can make nonzero: the
    pairs of columns some row holds both of.

    Returns:
        (xx, xu, uu): (m, 2) int64 arrays of (a, b) in Hessian coordinates (columns 0..ndx−1 the
        state tangent, ndx.. the control), the entries falling in the Lxx, Lxu and Luu blocks,
        row-major.
    """
    row_start = np.asarray(row_start, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    n = int(cols.max()) + 1 if cols.size else 0
    incidence = np.zeros((row_start.size - 1, n))
    incidence[np.repeat(np.arange(row_start.size - 1), np.diff(row_start)), cols] = 1.0
    return _blocks_of_entries(*np.nonzero(np.triu(incidence.T @ incidence)), ndx)


def dense_hessian_entries(n: int, ndx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`hessian_entries` of a dense pattern, every row holding the columns 0..n−1 (and of at least one row):
    the whole upper triangle, without the rows' incidence product (0.4-8 ms for a node of the H1's OCP, once per
    node data: at every MPC update, for the node that enters the horizon). The same arrays, in the same order."""
    return _blocks_of_entries(*np.triu_indices(n), ndx)


def _blocks_of_entries(a: np.ndarray, b: np.ndarray, ndx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The entries (a[k], b[k]) of the Hessian's upper triangle, row-major, split into their Lxx, Lxu and Luu
    blocks as (m, 2) int64 arrays (see :func:`hessian_entries`)."""
    pairs = np.stack([a, b], axis=1).astype(np.int64)
    in_x = pairs < ndx
    return (np.ascontiguousarray(pairs[in_x[:, 1]]), np.ascontiguousarray(pairs[in_x[:, 0] & ~in_x[:, 1]]),
            np.ascontiguousarray(pairs[~in_x[:, 0]]))


@njit(cache=True)
def clear_hessian_entries(hessian, xx, xu, uu):
    """Zero the listed entries (a, b) of hessian (n, n) (the ones :func:`add_gauss_newton_rows`
    can write for the pattern of :func:`hessian_entries`). When they are the whole upper triangle
    (a dense pattern, the walking OCPs'), row by row without the lists: the same entries."""
    n = hessian.shape[0]
    if xx.shape[0] + xu.shape[0] + uu.shape[0] == n * (n + 1) // 2:  # the lists hold distinct entries
        for a in range(n):
            for b in range(a, n):
                hessian[a, b] = 0.0
        return
    for entries in (xx, xu, uu):
        for e in range(entries.shape[0]):
            hessian[entries[e, 0], entries[e, 1]] = 0.0


@njit(cache=True)
def _scale_symmetric_block(dt, hessian, start, out):
    """out (m, m) = dt × the symmetric block of hessian whose upper triangle starts at (start, start): the
    upper triangle row by row, then the lower one copied from it."""
    m = out.shape[0]
    for a in range(m):
        for b in range(a, m):
            out[a, b] = dt * hessian[start + a, start + b]
    for a in range(1, m):
        for b in range(a):
            out[a, b] = out[b, a]


@njit(cache=True)
def scale_cost_derivatives(dt, gradient, hessian, xx, xu, uu, Lx, Lu, Lxx, Lxu, Luu):
    """Integrated cost derivatives: Lx (ndx,), Lu (nu,) = dt × the continuous gradient
    (ndx + nu,), and dt × each listed entry (a, b) of the Hessian's upper triangle (the
    :func:`hessian_entries` of its pattern) into its block: Lxx (ndx, ndx) and Luu (nu, nu) at
    (a, b) and (b, a), Lxu (ndx, nu) at (a, b). Block entries not listed are not written (they
    stay structurally zero). A block whose list holds all its entries (a dense pattern, the walking
    OCPs') is written row by row without the list, its lower triangle copied from the upper one: the
    same values (~2.5x faster on the H1's 50 + 19 columns)."""
    ndx = Lx.size
    nu = Lu.size
    for i in range(ndx):
        Lx[i] = dt * gradient[i]
    for i in range(nu):
        Lu[i] = dt * gradient[ndx + i]
    if xx.shape[0] == ndx * (ndx + 1) // 2:
        _scale_symmetric_block(dt, hessian, 0, Lxx)
    else:
        for e in range(xx.shape[0]):
            a, b = xx[e, 0], xx[e, 1]
            value = dt * hessian[a, b]
            Lxx[a, b] = value
            Lxx[b, a] = value
    if xu.shape[0] == ndx * nu:
        for a in range(ndx):
            for b in range(nu):
                Lxu[a, b] = dt * hessian[a, ndx + b]
    else:
        for e in range(xu.shape[0]):
            a, b = xu[e, 0], xu[e, 1]
            Lxu[a, b - ndx] = dt * hessian[a, b]
    if uu.shape[0] == nu * (nu + 1) // 2:
        _scale_symmetric_block(dt, hessian, ndx, Luu)
    else:
        for e in range(uu.shape[0]):
            a, b = uu[e, 0], uu[e, 1]
            value = dt * hessian[a, b]
            Luu[a - ndx, b - ndx] = value
            Luu[b - ndx, a - ndx] = value
