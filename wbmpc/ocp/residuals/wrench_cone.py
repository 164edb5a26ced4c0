"""Contact wrench cone of a rectangular flat foot, r = A w (17,), for a 6D contact on flat ground.

The wrench w = (f, τ) (6,) [N, N·m] is the one a :class:`~wbmpc.ocp.contacts.ContactModel6D`
computes, at the sole centre in the sole frame (LOCAL). With a sole of half-length X (along the
sole's x) and half-width Y [m] and a friction coefficient μ, the wrenches a rectangular contact
can transmit without sliding, tilting or spinning are (Caron, Pham, Nakamura, "Stability of
surface contacts for humanoid robots: closed-form formulae of the contact wrench cone for
rectangular support areas", ICRA 2015)::

    |f_x| <= μ f_z,   |f_y| <= μ f_z                         friction (4 rows)
    |τ_x| <= Y f_z,   |τ_y| <= X f_z                         centre of pressure inside the sole (4)
    τ_min <= τ_z <= τ_max                                    yaw torque (8 rows, the |.| expanded)
        τ_min = −μ(X+Y) f_z + |Y f_x − μ τ_x| + |X f_y − μ τ_y|
        τ_max = +μ(X+Y) f_z − |Y f_x + μ τ_x| − |X f_y + μ τ_y|
    f_z >= 0                                                 unilateral (1)

With the inner approximation (default) μ is replaced by μ cos(π/4) in every row, the friction
square inside the circular cone, as Crocoddyl's ``WrenchCone`` does.

A rectangle whose centre is not the contact frame's origin but c [m] along its x axis (a support
region reaching further behind the sole frame than in front of it) gets the same rows on the wrench
about its centre, w_c = (f, τ_x, τ_y + c f_z, τ_z − c f_y) = T w: A T.

Rows 0..15 are feasible when <= 0, row 16 (f_z) when >= 0: pair the residual with a quadratic
barrier on ``lower_bounds``/``upper_bounds``. Crocoddyl's ``WrenchCone`` has the same rows in
another order (and optional normal-force bounds): the test suite compares them row for row.
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.residuals.contact_force import ResidualLinearInContactForce
from wbmpc.ocp.state import StateMultibody


def wrench_cone_matrix(mu: float, half_length: float, half_width: float, inner_approximation: bool = True,
                       center_x: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A (17, 6) and bounds (lb, ub) of the rectangular contact wrench cone (module docstring).

    Args:
        mu: friction coefficient, > 0.
        half_length: X, half the sole's length along its x axis [m], > 0.
        half_width: Y, half the sole's width along its y axis [m], > 0.
        inner_approximation: scale μ by cos(π/4) (the friction square inside the cone).
        center_x: c, the rectangle's centre along the contact frame's x axis [m] (0: centred on the frame).
    """
    for name, value in (("mu", mu), ("half_length", half_length), ("half_width", half_width)):
        if not (np.isfinite(value) and value > 0):
            raise ParameterError(f"{name}={value} must be a finite positive number")
    if not np.isfinite(center_x):
        raise ParameterError(f"center_x={center_x} must be a finite number [m]")
    X, Y = float(half_length), float(half_width)
    mu = mu * np.cos(np.pi / 4.0) if inner_approximation else float(mu)
    mu_f = mu
    rows = [
        (1, 0, -mu_f, 0, 0, 0), (-1, 0, -mu_f, 0, 0, 0), (0, 1, -mu_f, 0, 0, 0), (0, -1, -mu_f, 0, 0, 0),
        (0, 0, -Y, 1, 0, 0), (0, 0, -Y, -1, 0, 0), (0, 0, -X, 0, 1, 0), (0, 0, -X, 0, -1, 0),
    ]
    # τ_z >= τ_min: −τ_z − μ(X+Y) f_z ± (Y f_x − μ τ_x) ± (X f_y − μ τ_y) <= 0
    # τ_z <= τ_max:  τ_z − μ(X+Y) f_z ± (Y f_x + μ τ_x) ± (X f_y + μ τ_y) <= 0
    for tz, sign_tau in ((-1.0, -1.0), (1.0, 1.0)):
        for s1 in (1.0, -1.0):
            for s2 in (1.0, -1.0):
                rows.append((s1 * Y, s2 * X, -mu * (X + Y), s1 * sign_tau * mu, s2 * sign_tau * mu, tz))
    rows.append((0, 0, 1, 0, 0, 0))
    A = np.array(rows, dtype=float)
    if center_x != 0.0:
        about_center = np.eye(6)  # T: the wrench about the rectangle's centre (module docstring)
        about_center[4, 2], about_center[5, 1] = center_x, -center_x
        A = A @ about_center
    lower = np.full(17, -np.inf)
    upper = np.zeros(17)
    lower[16], upper[16] = 0.0, np.inf
    return A, lower, upper


class ResidualWrenchCone(ResidualLinearInContactForce):
    """r = A w_contact (17,), the rectangular wrench cone of a 6D contact (module docstring).

    Args:
        state: the multibody state.
        contact_name: name of a 6D contact in the node's contact set.
        mu: friction coefficient.
        half_length, half_width: the support rectangle's half sizes [m].
        nu: control dimension.
        center_x: the rectangle's centre along the contact frame's x axis [m] (0: about the contact frame).
    """

    def __init__(self, state: StateMultibody, contact_name: str, mu: float, half_length: float, half_width: float,
                 nu: int, inner_approximation: bool = True, center_x: float = 0.0):
        A, lower, upper = wrench_cone_matrix(mu, half_length, half_width, inner_approximation, center_x)
        super().__init__(state, contact_name, A, nu)
        self.mu, self.half_length, self.half_width = float(mu), float(half_length), float(half_width)
        self.center_x = float(center_x)
        self.lower_bounds, self.upper_bounds = lower, upper
