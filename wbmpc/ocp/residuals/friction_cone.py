"""Linearised friction-cone residual r = A f (nf + 1,) for a point contact with a flat ground.

Rows 0..nf-1 are the cone facets (feasible when ≤ 0), row nf is the normal force (feasible when
≥ 0); pair it with a quadratic barrier on ``lower_bounds``/``upper_bounds``. The facets follow
Crocoddyl's ``FrictionCone`` (inner approximation: μ cos(π/nf)).
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.residuals.contact_force import ResidualLinearInContactForce
from wbmpc.ocp.state import StateMultibody


def friction_cone_matrix(mu: float, n_facets: int = 4, inner_approximation: bool = True,
                         rotation_world_surface: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facet matrix A (n_facets + 1, 3) and its bounds (lb, ub) for a force in the world frame.

    Args:
        mu: friction coefficient, > 0.
        n_facets: number of facets, even, ≥ 2.
        inner_approximation: scale μ by cos(π / n_facets) so the polygon is inside the cone.
        rotation_world_surface: orientation of the contact surface (3, 3); identity = flat ground.
    """
    if not (np.isfinite(mu) and mu > 0):
        raise ParameterError(f"mu={mu} must be a finite positive friction coefficient")
    if n_facets < 2 or n_facets % 2:
        raise ParameterError(f"n_facets={n_facets} must be an even number >= 2")
    R = np.eye(3) if rotation_world_surface is None else np.asarray(rotation_world_surface, dtype=float)
    theta = 2.0 * np.pi / n_facets
    mu_eff = mu * np.cos(theta / 2.0) if inner_approximation else mu
    A = np.zeros((n_facets + 1, 3))
    for i in range(n_facets // 2):
        tangent = np.array([np.cos(theta * i), np.sin(theta * i), 0.0])
        normal = np.array([0.0, 0.0, -mu_eff])
        A[2 * i] = (normal + tangent) @ R.T
        A[2 * i + 1] = (normal - tangent) @ R.T
    A[n_facets] = R[:, 2]
    lower = np.full(n_facets + 1, -np.inf)
    upper = np.zeros(n_facets + 1)
    lower[n_facets] = 0.0
    upper[n_facets] = np.inf
    return A, lower, upper


class ResidualFrictionCone(ResidualLinearInContactForce):
    """r = A f_contact (world-aligned point-contact force), Rx = A ∂f/∂x, Ru = A ∂f/∂u.

    Args:
        state: the multibody state.
        contact_name: name of a 3D point contact in the node's contact set.
        mu: friction coefficient; n_facets, inner_approximation: see :func:`friction_cone_matrix`.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, contact_name: str, mu: float, nu: int, n_facets: int = 4,
                 inner_approximation: bool = True):
        A, self.lower_bounds, self.upper_bounds = friction_cone_matrix(mu, n_facets, inner_approximation)
        super().__init__(state, contact_name, A, nu)
        self.mu = float(mu)
