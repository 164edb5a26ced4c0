"""Compiled damped KKT contact dynamics and their derivatives (the "kkt" backend of
:class:`~wbmpc.ocp.dynamics.DifferentialActionModelContactFwdDynamics`).

For the joint-space inertia M (nv, nv), the nonlinear effects b (nv,), the joint torques τ (nv,),
the stacked contact Jacobian Jc (nc, nv), the contact drift a0 (nc,), the damping μ >= 0 and the
row scales S = diag(s) (nc,) (ones: uniform damping; a sole's lever arms on its moment rows: the
"sole" damping), the accelerations a and the contact forces λ = S λ̃ solve

    [M   J̃ᵀ] [ a ]   [τ − b]
    [J̃  −μI] [−λ̃] = [ −ã0 ],    J̃ = S Jc,  ã0 = S a0,

i.e. λ̃ = −Y (J̃ a_free + ã0), a = a_free + Aᵀ λ̃ with a_free = M⁻¹ (τ − b), A = J̃ M⁻¹ (nc, nv) and
Y = (A J̃ᵀ + μ I)⁻¹ (nc, nc). The inverse of the KKT matrix is [[M⁻¹ − Aᵀ Y A, Aᵀ Y], [Y A, −Y]], so
for the derivatives D_τ = ∂τ_RNEA(q, v, a, λ)/∂x (nv, ndx) (RNEA with the contact forces as
external forces) and D_c = ∂(Jc a + a0)/∂x at fixed a (nc, ndx) (the contact drift derivatives):

    W = Y (J̃ M⁻¹ D_τ − S D_c),   ∂a/∂x = −M⁻¹ D_τ + Aᵀ W,   ∂λ/∂x = S W,
    ∂a/∂τ = M⁻¹ − Aᵀ Y A,       ∂λ/∂τ = −S Y A,

Crocoddyl's formulas ([∂a/∂x; −∂λ̃/∂x] = −K⁻¹ [D_τ; S D_c]) without forming K⁻¹. M⁻¹ comes from the
Cholesky factor of M (CRBA fills its upper triangle), Y from that of A J̃ᵀ + μ I; with nc = 0
(flight) a = a_free and ∂a/∂x = −M⁻¹ D_τ. The products go to BLAS (``np.dot`` into preallocated
buffers). :class:`KKTBuffers` holds what the dynamics leave for the derivatives. (numba caches these
kernels with the linalg kernels they inline, by this file's stamp: edit this file with those.)
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import cholesky_in_place, lower_triangular_inverse


class KKTBuffers:
    """Work arrays of the kernels for ``nv`` velocities, ``nc`` contact rows and ``ndx`` tangent
    directions (one per contact-set size: BLAS wants whole, contiguous arrays): what the dynamics
    leave for the derivatives (M⁻¹ (nv, nv), A = J̃ M⁻¹ (nc, nv), Y (nc, nc), J̃ (nc, nv)) and scratch."""

    def __init__(self, nv: int, nc: int, ndx: int):
        self.Minv = np.zeros((nv, nv))
        self.factor = np.zeros((nv, nv))  # Cholesky factor of M
        self.factor_inverse = np.zeros((nv, nv))
        self.A = np.zeros((nc, nv))
        self.Y = np.zeros((nc, nc))
        self.G = np.zeros((nc, nc))  # A J̃ᵀ + μ I
        self.G_factor = np.zeros((nc, nc))
        self.G_factor_inverse = np.zeros((nc, nc))
        self.J_scaled = np.zeros((nc, nv))
        self.a_free = np.zeros(nv)
        self.tau_residual = np.zeros(nv)
        self.residual = np.zeros(nc)
        self.force_scaled = np.zeros(nc)
        self.D = np.zeros((nv, ndx))  # D_τ = [∂τ/∂q, ∂τ/∂v]
        self.P = np.zeros((nv, ndx))  # M⁻¹ D_τ
        self.C = np.zeros((nc, ndx))  # J̃ M⁻¹ D_τ − S D_c
        self.W = np.zeros((nc, ndx))  # Y C = ∂λ̃/∂x
        self.YA = np.zeros((nc, nv))
        self.AtW = np.zeros((nv, ndx))
        self.AtYA = np.zeros((nv, nv))

    def dynamics_buffers(self) -> tuple:
        """The arguments of :func:`damped_kkt_dynamics` after its first nine."""
        return (self.Minv, self.factor, self.factor_inverse, self.A, self.Y, self.G, self.G_factor,
                self.G_factor_inverse, self.J_scaled, self.a_free, self.tau_residual, self.residual, self.force_scaled)

    def derivative_buffers(self) -> tuple:
        """The arguments of :func:`damped_kkt_derivatives` after its first eight."""
        return (self.Minv, self.A, self.Y, self.J_scaled, self.D, self.P, self.C, self.W, self.YA, self.AtW,
                self.AtYA)


@njit(cache=True)
def _symmetric_inverse(M, factor, factor_inverse, out):
    """out = M⁻¹ for a symmetric positive definite M (n, n) given by its upper triangle, through its
    Cholesky factor (scratch factor, factor_inverse (n, n)); False if M is not positive definite."""
    n = M.shape[0]
    for i in range(n):
        for j in range(i, n):
            factor[j, i] = M[i, j]  # the lower triangle the factorisation reads
    if not cholesky_in_place(factor):
        return False
    lower_triangular_inverse(factor, factor_inverse)
    np.dot(factor_inverse.T, factor_inverse, out)
    return True


@njit(cache=True)
def damped_kkt_dynamics(M, nle, tau, Jc, a0, scales, mu, a, force, Minv, factor, factor_inverse, A, Y, G, G_factor,
                        G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled):
    """The module's solve: accelerations a (nv,) and contact forces ``force`` (nc,) = S λ̃.

    Args: M (nv, nv) (upper triangle read), nle (nv,), tau (nv,), Jc (nc, nv), a0 (nc,), scales (nc,),
    mu >= 0, outputs a (nv,) and force (nc,); then :meth:`KKTBuffers.dynamics_buffers` (of this nc),
    left holding M⁻¹, A, Y and J̃ for :func:`damped_kkt_derivatives`.

    Returns:
        True, or False when M or A J̃ᵀ + μ I is not positive definite (the outputs are then invalid).
    """
    nv = M.shape[0]
    nc = Jc.shape[0]
    if not _symmetric_inverse(M, factor, factor_inverse, Minv):
        return False
    for i in range(nv):
        tau_residual[i] = tau[i] - nle[i]
    np.dot(Minv, tau_residual, a_free)
    if nc == 0:
        a[:] = a_free
        return True
    for r in range(nc):
        s = scales[r]
        for c in range(nv):
            J_scaled[r, c] = s * Jc[r, c]
    np.dot(J_scaled, Minv, A)
    np.dot(A, J_scaled.T, G)
    for r in range(nc):
        G[r, r] += mu
    if not _symmetric_inverse(G, G_factor, G_factor_inverse, Y):
        return False
    np.dot(J_scaled, a_free, residual)
    for r in range(nc):
        residual[r] += scales[r] * a0[r]
    np.dot(Y, residual, force_scaled)
    for r in range(nc):
        force_scaled[r] = -force_scaled[r]
        force[r] = scales[r] * force_scaled[r]
    np.dot(A.T, force_scaled, a)
    for i in range(nv):
        a[i] += a_free[i]
    return True


@njit(cache=True)
def damped_kkt_derivatives(dtau_dq, dtau_dv, da0_dx, scales, Fx, Fu, df_dx, df_du, Minv, A, Y, J_scaled, D, P, C,
                           W, YA, AtW, AtYA):
    """The module's derivatives after :func:`damped_kkt_dynamics` at the same point.

    Args: dtau_dq, dtau_dv (nv, nv) the RNEA derivatives with the contact forces as external forces
    (D_τ = [dtau_dq, dtau_dv]), da0_dx (nc, ndx) = D_c, scales (nc,); outputs Fx = ∂a/∂x (nv, ndx),
    Fu = ∂a/∂u (nv, nu) (the last nu = nv − 6 torques: a free-flyer actuation), df_dx = ∂λ/∂x
    (nc, ndx), df_du = ∂λ/∂u (nc, nu); then :meth:`KKTBuffers.derivative_buffers` (of this nc).
    """
    nv = Minv.shape[0]
    nc = A.shape[0]
    ndx = 2 * nv
    nu = Fu.shape[1]
    n_base = nv - nu
    D[:, :nv] = dtau_dq
    D[:, nv:] = dtau_dv
    np.dot(Minv, D, P)
    if nc == 0:
        for i in range(nv):
            for c in range(ndx):
                Fx[i, c] = -P[i, c]
            for c in range(nu):
                Fu[i, c] = Minv[i, n_base + c]
        return
    np.dot(J_scaled, P, C)
    for r in range(nc):
        s = scales[r]
        for c in range(ndx):
            C[r, c] -= s * da0_dx[r, c]
    np.dot(Y, C, W)
    np.dot(A.T, W, AtW)
    np.dot(Y, A, YA)
    np.dot(A.T, YA, AtYA)
    for i in range(nv):
        for c in range(ndx):
            Fx[i, c] = AtW[i, c] - P[i, c]
        for c in range(nu):
            Fu[i, c] = Minv[i, n_base + c] - AtYA[i, n_base + c]
    for r in range(nc):
        s = scales[r]
        for c in range(ndx):
            df_dx[r, c] = s * W[r, c]
        for c in range(nu):
            df_du[r, c] = -s * YA[r, n_base + c]
