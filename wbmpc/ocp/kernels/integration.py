"""The semi-implicit Euler step of :class:`~wbmpc.ocp.integrator.IntegratedActionModelEuler` and its
Jacobians, compiled: q⁺ = q ⊕ (v dt + a dt²), v⁺ = v + a dt. The node-wise model and the batched
problem call these same kernels."""

from __future__ import annotations

from numba import njit

from wbmpc.ocp.kernels.lie import free_flyer_integrate


@njit(cache=True)
def euler_step_tangent(v, a, dt, dx, v_next):
    """dx = [v dt + a dt², a dt] (2 nv,) and v⁺ = v + a dt (nv,)."""
    nv = v.size
    dt2 = dt * dt
    for i in range(nv):
        dx[i] = v[i] * dt + a[i] * dt2
        dx[nv + i] = a[i] * dt
        v_next[i] = v[i] + a[i] * dt


@njit(cache=True)
def free_flyer_euler_step(x, a, dt, dx, x_next):
    """Semi-implicit Euler step of a free-flyer state: dx = [v dt + a dt², a dt] (2 nv,)
    (:func:`euler_step_tangent`) and x⁺ = [q ⊕ dx[:nv], v + a dt] (nx,)."""
    nv = a.size
    nq = x.size - nv
    euler_step_tangent(x[nq:], a, dt, dx, x_next[nq:])
    free_flyer_integrate(x[:nq], dx[:nv], x_next[:nq])


@njit(cache=True)
def euler_transition_jacobians(da_dx, da_du, J_q, J_dq, dt, n_base, Fx, Fu):
    """Fx (ndx, ndx), Fu (ndx, nu) of q⁺ = q ⊕ (v dt + a dt²), v⁺ = v + a dt.

    Args: da_dx (nv, ndx), da_du (nv, nu) acceleration derivatives; J_q, J_dq (nv, nv) the
    Jacobians of q ⊕ δ with respect to q and δ at δ = v dt + a dt², identity outside their
    leading n_base × n_base block (6 for a free flyer followed by 1-dof joints, nv in general):
    only those rows need the products.
    """
    nv = da_dx.shape[0]
    ndx = 2 * nv
    nu = da_du.shape[1]
    dt2 = dt * dt
    for i in range(n_base):
        for c in range(ndx):
            s = 0.0
            for m in range(n_base):
                s += J_dq[i, m] * da_dx[m, c]
            Fx[i, c] = s * dt2
        for c in range(nu):
            s = 0.0
            for m in range(n_base):
                s += J_dq[i, m] * da_du[m, c]
            Fu[i, c] = s * dt2
        for m in range(n_base):
            Fx[i, nv + m] += J_dq[i, m] * dt
            Fx[i, m] += J_q[i, m]
    for i in range(n_base, nv):
        for c in range(ndx):
            Fx[i, c] = da_dx[i, c] * dt2
        for c in range(nu):
            Fu[i, c] = da_du[i, c] * dt2
        Fx[i, nv + i] += dt
        Fx[i, i] += 1.0
    for i in range(nv):
        for c in range(ndx):
            Fx[nv + i, c] = da_dx[i, c] * dt
        for c in range(nu):
            Fu[nv + i, c] = da_du[i, c] * dt
        Fx[nv + i, nv + i] += 1.0
