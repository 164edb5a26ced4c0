"""Compiled residual rows shared by the node-wise residuals and their batched evaluation: each
residual of :mod:`wbmpc.ocp.residuals` that can be batched computes its rows with these kernels
at one node (``calc``/``calcDiff``) and over every active node of a horizon (``batch_calc``/
``batch_calc_diff``, which loop over the same per-node kernel)."""

from __future__ import annotations

from numba import njit

from wbmpc.ocp.kernels.lie import free_flyer_ddifference_second, free_flyer_state_difference


@njit(cache=True, inline="always")
def subtract_rows(value, reference, r):
    """r = value − reference (the residual of every reference-tracking term)."""
    for i in range(r.size):
        r[i] = value[i] - reference[i]


@njit(cache=True)
def subtract_rows_many(values, references, mask, r):
    """r[k] = values[k] − references[k] for the nodes with mask[k], values, references, r (N, d)."""
    for k in range(mask.size):
        if mask[k]:
            subtract_rows(values[k], references[k], r[k])


@njit(cache=True)
def state_difference_many(references, xs, nq, mask, r, ok):
    """r[k] = xs[k] ⊖ references[k] (the free-flyer difference of ``StateMultibody.diff``) for the
    nodes with mask[k]; ok[k] False where Pinocchio must take over (half turn). True if none did."""
    all_ok = True
    for k in range(mask.size):
        ok[k] = True
        if mask[k] and not free_flyer_state_difference(references[k], xs[k], nq, r[k]):
            ok[k] = False
            all_ok = False
    return all_ok


@njit(cache=True)
def state_jacobian_many(references, xs, nq, mask, n_base, J, values, ok):
    """The Jacobian nonzeros values[k] of x ⊖ x_ref at the nodes with mask[k]: the n_base × n_base
    configuration block of ∂(xs[k] ⊖ references[k])/∂q (``StateMultibody.Jdiff_second_q``, computed
    in the scratch J (nv, nv)) row-major, then the identity entries. ok[k] False where Pinocchio
    must take over (half turn; values[k] then holds only the identity entries). True if none did."""
    all_ok = True
    nb2 = n_base * n_base
    for k in range(mask.size):
        ok[k] = True
        if not mask[k]:
            continue
        for i in range(nb2, values.shape[1]):
            values[k, i] = 1.0
        if not free_flyer_ddifference_second(references[k, :nq], xs[k, :nq], J):
            ok[k] = False
            all_ok = False
            continue
        for a in range(n_base):
            for b in range(n_base):
                values[k, a * n_base + b] = J[a, b]
    return all_ok


@njit(cache=True)
def frame_rows_many(positions, axes, references, mask, r):
    """Frame-position residual rows r[k, a] = positions[k, axes[a]] − references[k, a] [m] for
    the nodes with mask[k]; positions (N, 3) world."""
    for k in range(mask.size):
        if mask[k]:
            for a in range(axes.size):
                r[k, a] = positions[k, axes[a]] - references[k, a]


@njit(cache=True)
def frame_jacobian_rows_many(jacobians, axes, mask, values):
    """Their Jacobian rows values[k] = jacobians[k, axes, :] (row-major; jacobians (N, 3, nv), the
    world-aligned linear rows) for the nodes with mask[k]."""
    nv = jacobians.shape[2]
    for k in range(mask.size):
        if mask[k]:
            for a in range(axes.size):
                for c in range(nv):
                    values[k, a * nv + c] = jacobians[k, axes[a], c]
