"""One whole-body walking OCP from a standing start: plan footsteps, sample the schedule, solve.

This is what ``wbmpc ocp`` prints and draws; it is also the shortest path from a robot to a
solved walking problem in Python::

    from wbmpc.walking.standing_start import solve_walking_ocp
    result = solve_walking_ocp("bolt", speed=0.33)
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class StandingStart:
    """A robot standing still at its reference posture and the footstep plan it starts walking with.

    Attributes:
        robot: the ``robots.RobotDescription``; preset: its walking preset (planner with the command).
        x0: the standing state (nx,); com0: its CoM (3,) [m], world; feet: foot -> position (3,) [m], world.
        sequencer: the DCM footstep sequencer; plan: its plan at t = 0 from the left stance foot, with
            the measured DCM the CoM's xy plus ``dcm_offset``.
    """

    robot: object
    preset: object
    x0: np.ndarray
    com0: np.ndarray
    feet: dict
    sequencer: object
    plan: object

    def com_terminal_reference(self, t: float, plan=None) -> np.ndarray:
        """The terminal CoM reference (3,) [m], world, of an OCP ending at ``t`` [s]: the LIPM CoM of
        ``plan`` (None: this start's) at t from the standing CoM, at the standing CoM height."""
        plan = self.plan if plan is None else plan
        return np.append(plan.lipm_com_at(t, self.com0[:2]), self.com0[2])


def standing_start(robot_name: str = "bolt", speed: float | None = None, dcm_offset=(0.0, 0.0)) -> StandingStart:
    """The standing robot and its footstep plan at t = 0 (the DCM of a still robot is its CoM; a
    disturbance ``dcm_offset`` (2,) [m] on the measured DCM changes the plan only)."""
    import pinocchio as pin

    from robots import load_robot
    from sequencer import FootstepSequencer
    from wbmpc.walking.preset import load_walking_preset

    robot = load_robot(robot_name)
    preset = load_walking_preset(robot_name)
    if speed is not None:
        preset = dataclasses.replace(preset, planner=dataclasses.replace(preset.planner, v_x=float(speed)))
    model = robot.pinocchio_model
    data = model.createData()
    x0 = np.concatenate([robot.q_reference, np.zeros(model.nv)])
    q0 = x0[: model.nq]
    pin.framesForwardKinematics(model, data, q0)
    com0 = pin.centerOfMass(model, data, q0).copy()
    feet = {foot: data.oMf[model.getFrameId(name)].translation.copy() for foot, name in robot.foot_frames.items()}
    sequencer = FootstepSequencer(preset.planner)
    plan = sequencer.plan(t=0.0, stance_foot="left", stance_position=feet["left"][:2],
                          dcm_measured=com0[:2] + np.asarray(dcm_offset, dtype=float), t_stance_start=0.0)
    return StandingStart(robot, preset, x0, com0, feet, sequencer, plan)


def solve_walking_ocp(robot_name: str = "bolt", speed: float | None = None, n_nodes: int = 100, dt: float = 0.01,
                      iterations: int = 100, foothold_weight: float | None = 0.0) -> dict:
    """Plan footsteps from a standing start, solve the walking OCP, summarise the solution.

    The planner and the OCP weights are the robot's walking preset's
    (:func:`wbmpc.walking.preset.load_walking_preset`; a robot without one is refused), with the
    command ``speed`` [m/s] (None: the preset's) and ``foothold_weight`` (0, the default: the
    footholds emerge, the paper's choice; None: the preset's closed-loop value).

    Returns a dict with the solver log, term costs, swing apex heights [m] above the ground,
    CoM displacement [m], peak torque [N·m], and the trajectories (times [s], xs, us, foot
    heights (N + 1, 2) [m], CoM (N + 1, 3) [m]).
    """
    import pinocchio as pin

    from sequencer import contact_schedule
    from wbmpc.errors import ParameterError
    from wbmpc.ocp.blas import limit_blas_threads
    from wbmpc.ocp.solvers import SolverFDDP
    from wbmpc.walking.ocp import WalkingOCP, quasi_static_controls

    if int(iterations) != iterations or iterations < 1:
        raise ParameterError(f"iterations={iterations} must be an integer >= 1")
    start = standing_start(robot_name, speed)
    robot, preset, x0, plan = start.robot, start.preset, start.x0, start.plan
    model = robot.pinocchio_model
    data = model.createData()
    feet = start.feet
    schedule = contact_schedule(plan, 0.0, dt, n_nodes)
    com_terminal = start.com_terminal_reference(n_nodes * dt)
    config = preset.ocp if foothold_weight is None else dataclasses.replace(preset.ocp, foothold_weight=foothold_weight)
    ocp = WalkingOCP(robot, config, n_nodes=n_nodes, dt=dt)
    ocp.update(x0, schedule, com_terminal)
    solver = SolverFDDP(ocp.problem)
    u0 = quasi_static_controls(ocp, x0)
    with limit_blas_threads(1):  # small dense blocks: threads only contend (docs/benchmarks.md)
        converged = solver.solve([x0] * (n_nodes + 1), [u0] * n_nodes, maxiter=iterations)
    ocp.problem.calc(solver.xs, solver.us)
    heights = np.zeros((n_nodes + 1, len(feet)))
    coms = np.zeros((n_nodes + 1, 3))
    for k, x in enumerate(solver.xs):
        q = x[: model.nq]
        pin.framesForwardKinematics(model, data, q)
        coms[k] = pin.centerOfMass(model, data, q)
        for j, name in enumerate(robot.foot_frames.values()):
            heights[k, j] = data.oMf[model.getFrameId(name)].translation[2] - robot.contact_frame_height
    in_contact = np.asarray(schedule.in_contact)
    apex = {foot: float(np.max(np.where(in_contact[:, j], -np.inf, heights[:, j]), initial=0.0))
            for j, foot in enumerate(feet)}
    return {
        "robot": robot_name, "n_nodes": n_nodes, "dt_s": dt, "converged": bool(converged),
        "iterations": len(solver.log), "cost": float(solver.cost),
        "log": [dataclasses.asdict(entry) for entry in solver.log],
        "term_costs": ocp.problem.term_costs(),
        "swing_apex_height_m": apex, "swing_apex_reference_m": ocp.config.swing_apex_height,
        "com_displacement_m": (coms[-1] - coms[0]).tolist(), "com_terminal_reference_m": com_terminal.tolist(),
        "peak_torque_Nm": float(np.max(np.abs(solver.us))), "torque_limit_Nm": float(np.max(robot.torque_limit)),
        "times_s": (dt * np.arange(n_nodes + 1)).tolist(), "foot_heights_m": heights, "com_m": coms,
        "feet": list(feet), "xs": solver.xs, "us": solver.us,
    }
