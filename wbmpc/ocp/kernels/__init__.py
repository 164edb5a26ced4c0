"""Numba kernels of the OCP core, one module per concept: ``linalg`` (3x3 products), ``lie``
(free-flyer integrate, difference and their Jacobians), ``integration`` (Euler step and its
Jacobians), ``costs`` (dead-zone quadratic over residual rows), ``contact`` (point-contact
terms), ``tree`` (the kinematic tree's placements, velocities and Jacobian columns),
``joint_space`` (the joint-space inertia M and nonlinear effects b on that tree), ``rnea_derivatives``
(the derivatives of the inverse dynamics on that tree), ``frames``
(frame kinematics over a horizon), ``feedback`` (the feedback law), ``horizon_contacts`` (a horizon's
contact sets as padded arrays), ``rollout`` (a horizon's rollout of KKT nodes in one call),
``derivative_pass`` (a horizon's KKT nodes' dynamics and derivatives in one call). Compiled on first use and
cached on disk. A helper shared by two modules is public in one of them."""
