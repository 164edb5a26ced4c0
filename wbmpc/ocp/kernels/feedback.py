"""The feedback law u = u_k − α k_k − K_k (x ⊖ x_k) (Crocoddyl's sign of k and K), compiled once: the
solver's rollout (line search, α k the step) and :class:`~wbmpc.ocp.policy.RiccatiPolicy` (α = 0,
K of the opposite sign) call :func:`feedback_control`."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.lie import free_flyer_integrate, free_flyer_interpolate, free_flyer_state_difference


@njit(cache=True)
def feedback_control(u, k, K, dx, alpha, out):
    """out = u − α k − K dx (Crocoddyl's sign); returns False if the result is not finite."""
    nu, ndx = K.shape
    ok = True
    for i in range(nu):
        s = u[i] - alpha * k[i]
        for j in range(ndx):
            s -= K[i, j] * dx[j]
        out[i] = s
        if not np.isfinite(s):
            ok = False
    return ok


@njit(cache=True)
def free_flyer_feedback_control(x_ref, x, u, k, K, alpha, nq, dx, out):
    """dx = x ⊖ x_ref (free-flyer models) and out = u − α k − K dx (Crocoddyl's sign) in one call.

    Returns 0 on success, 1 when the difference needs Pinocchio (relative rotation near a half
    turn; nothing written to out), 2 when the control is not finite.
    """
    if not free_flyer_state_difference(x_ref, x, nq, dx):
        return 1
    return 0 if feedback_control(u, k, K, dx, alpha, out) else 2


@njit(cache=True)
def rollout_node_start(t, x_prev, fs, alpha, closing, xs, us, k, K, x_try, dx, u_try, tau):
    """One node of the FDDP rollout before its dynamics: x_try = x_prev ⊕ (α − 1) fs[t] when
    closing gaps (else x_prev), dx[t] = x_try ⊖ xs[t], u_try[t] = us[t] − α k[t] − K[t] dx[t]
    (Crocoddyl's sign) and the joint torques tau[6:] = u_try[t]. Returns 0 on success, 1 when the
    difference needs Pinocchio (half turn; x_try is written, not dx, u_try, tau), 2 when the
    control is not finite."""
    nv = dx.shape[1] // 2
    nq = x_try.size - nv
    if closing:
        step = (alpha - 1.0) * fs[t]
        free_flyer_integrate(x_prev[:nq], step[:nv], x_try[:nq])
        for i in range(nv):
            x_try[nq + i] = x_prev[nq + i] + step[nv + i]
    else:
        x_try[:] = x_prev
    code = free_flyer_feedback_control(xs[t], x_try, us[t], k[t], K[t], alpha, nq, dx[t], u_try[t])
    if code != 0:
        return code
    for i in range(u_try.shape[1]):
        tau[6 + i] = u_try[t, i]
    return 0


@njit(cache=True)
def policy_control(xs, us, K, k_zero, node, alpha, x, feedback, nq, x_ref, dx, out):
    """out (nu,) = u + K (x ⊖ x_ref) of :class:`~wbmpc.ocp.policy.RiccatiPolicy` at ``node``, free-flyer
    state: u, x_ref = us[node], xs[node] (alpha < 0) or interpolated towards node + 1 by alpha in
    [0, 1] (``pin.interpolate`` on q). K is passed with Crocoddyl's sign (−K of the library), k_zero
    (nu,) zeros: :func:`feedback_control` with α = 0. Returns 0 on success, 1 when a difference
    needs Pinocchio (half-turn relative rotation; out is then to be recomputed)."""
    nu = out.size
    if alpha >= 0.0:
        for i in range(nu):
            out[i] = (1.0 - alpha) * us[node, i] + alpha * us[node + 1, i]
        if not feedback:
            return 0
        nv = x.size - nq
        if not free_flyer_interpolate(xs[node, :nq], xs[node + 1, :nq], alpha, dx[:nv], x_ref[:nq]):
            return 1
        for i in range(nv):
            x_ref[nq + i] = (1.0 - alpha) * xs[node, nq + i] + alpha * xs[node + 1, nq + i]
        reference = x_ref
    else:
        for i in range(nu):
            out[i] = us[node, i]
        if not feedback:
            return 0
        reference = xs[node]
    if not free_flyer_state_difference(reference, x, nq, dx):
        return 1
    feedback_control(out, k_zero, K[node], dx, 0.0, out)
    return 0
