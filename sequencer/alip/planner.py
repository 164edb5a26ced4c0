"""The ALIP step-to-step NMPC behind the :class:`~sequencer.planner.FootstepPlanner` interface.

At each call: the measured ALIP state about the stance contact, in the stance's heading frame ψ_0
(``ReducedState.angular_momentum``; when it is None, the paper's approximation eqs. 14-15 from the CoM
velocity without the centroidal I ω terms, which ReducedState does not carry, at the model height), the
time in stance t_curr = t − stance.t_start (a stance older than t_max is planned as a touchdown now), the
NMPC of eq. (11) solved by the chosen solver, warm-started from the last plan (shifted by one step after a
touchdown), and a :class:`~sequencer.horizon.FootstepPlan`:

- headings ψ_{k+1} = ψ_k + r T_k (r the yaw rate), footholds p_{k+1} = p_k + R_z(ψ_k) ℓ_k (eq. 16),
  touchdowns at t_start + T_0, then + T_k;
- the K optimised steps, then nominal steps (ℓ^des clipped, T_des, τ = 0, the corrected S2S map) until a
  touchdown at or after t + params.horizon, so the controller's grid is covered;
- the DCM at every touchdown and the CoP offset of every stance (the ankle torque), so that
  ``com_reference`` (the LIP formulas about the CoP) is the ALIP CoM prediction exactly.

A failed solve raises :class:`~sequencer.alip.nlp.AlipSolverError` (a ``wbmpc.errors.SolverError``); the
control loop keeps its last plan. :attr:`AlipFootstepPlanner.last_solution` holds the last optimum
(periods, torques, steps, states, active bounds).
"""

from __future__ import annotations

import math

import numpy as np

from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.model import AlipModel
from sequencer.alip.nlp import FEET, AlipInstance, AlipNlp, AlipSolution, desired_steps, orbit
from sequencer.alip.params import AlipParams
from sequencer.alip.s2s import B_D, heading_change_entries
from sequencer.alip.sqp_ import SqpSolver
from sequencer.horizon import FootstepPlan, PlannedStep
from sequencer.planner import ReducedState, StanceState, VelocityCommand, as_velocity_command, rotate_xy
from wbmpc.errors import ParameterError

SOLVERS = {"sqp": SqpSolver, "ipopt": IpoptSolver}


class AlipFootstepPlanner:
    """Footstep planner of the ALIP S2S NMPC (seed 001 eq. 11), implementing :class:`~sequencer.planner.FootstepPlanner`.

    Args:
        params: AlipParams (e.g. ``AlipParams.preset("g1")``).
        solver: ``"sqp"`` (fast path, default) or ``"ipopt"`` (reference).
        warm_start: start each solve from the last solution (shifted after a touchdown).
    """

    feet: tuple[str, ...] = FEET
    #: reads ``ReducedState.angular_momentum`` (about the stance contact; approximated when None): a controller
    #: that can measure it hands it over (:class:`wbmpc.walking.planning.PlanningStage`)
    uses_angular_momentum: bool = True

    avoids_obstacles = False  # plan(obstacles=...) raises ParameterError

    def __init__(self, params: AlipParams, solver: str = "sqp", warm_start: bool = True) -> None:
        if not isinstance(params, AlipParams):
            raise ParameterError(f"params must be an AlipParams, got {type(params).__name__}")
        if solver not in SOLVERS:
            raise ParameterError(f"solver={solver!r} must be one of {sorted(SOLVERS)}")
        if not isinstance(warm_start, bool):
            raise ParameterError(f"warm_start={warm_start!r} must be True or False")
        self.params = params
        self.model = params.model
        self.nlp = AlipNlp(params)
        self.solver = SOLVERS[solver](self.nlp)
        self.warm_start = warm_start
        self.last_solution: AlipSolution | None = None
        self.last_instance: AlipInstance | None = None
        self._last_key = None

    # ------------------------------------------------------------------ interface attributes
    @property
    def omega(self) -> float:
        """ALIP natural frequency sqrt(g / z) [1/s]."""
        return self.params.omega

    @property
    def com_height(self) -> float:
        """The ALIP's CoM height z [m]."""
        return self.params.com_height

    @property
    def double_support(self) -> float:
        """Both feet on the ground after each touchdown for this long [s] (``params.double_support``; the
        contact schedule's only: the ALIP transfers the support at the touchdown)."""
        return self.params.double_support

    def command_range(self) -> dict[str, tuple[float, float]]:
        """v_x, v_y [m/s] whose desired steps (eqs. 12-13) lie in the step boxes; yaw_rate unbounded."""
        return {**self.params.velocity_range(), "yaw_rate": (-math.inf, math.inf)}

    def check_command(self, command: VelocityCommand) -> None:
        command = as_velocity_command(command)
        self.params.check_velocity(command.v_x, command.v_y)

    # ------------------------------------------------------------------ planning
    def measured_state(self, stance: StanceState, measured: ReducedState) -> np.ndarray:
        """ALIP state (p_x, L_y, p_y, L_x) about the stance contact, stance heading frame, shape (4,)
        (:func:`alip_state_about_contact`; without a measured angular momentum at the model height)."""
        return alip_state_about_contact(self.model, stance, measured.com, measured.com_velocity,
                                        measured.angular_momentum)

    def instance(self, t: float, stance: StanceState, measured: ReducedState, command) -> AlipInstance:
        """The NMPC instance of a call (validated; ParameterError names the bad argument)."""
        if not isinstance(stance, StanceState):
            raise ParameterError(f"stance must be a StanceState, got {type(stance).__name__}")
        if not isinstance(measured, ReducedState):
            raise ParameterError(f"measured must be a ReducedState, got {type(measured).__name__}")
        if stance.foot not in self.feet:
            raise ParameterError(f"stance foot={stance.foot!r} must be one of {self.feet}")
        command = as_velocity_command(command)
        t = float(t)
        if not math.isfinite(t):
            raise ParameterError(f"t={t} s must be finite")
        self.params.check_velocity(command.v_x, command.v_y)
        if t < stance.t_start:  # a start from standing (see plan)
            return AlipInstance(self.stance_start_state(stance.foot, command), 0.0, stance.foot, command.v_x,
                                command.v_y, command.yaw_rate)
        return AlipInstance(self.measured_state(stance, measured), t - stance.t_start, stance.foot, command.v_x,
                            command.v_y, command.yaw_rate)

    def stance_start_state(self, stance_foot: str, command) -> np.ndarray:
        """The ALIP state (p_x, L_y, p_y, L_x) of the nominal gait of ``command`` when a stance on ``stance_foot``
        begins, about its contact, heading frame, shape (4,): the post-impact state x⁺ = x⁻ + B_d ℓ^des of the
        desired orbit (:func:`sequencer.alip.nlp.orbit`, τ = 0, T = T_des, not turning) at the end of a stance
        on the other foot, with that stance's desired step (eqs. 12-13). The ALIP counterpart of
        :meth:`sequencer.dcm_planner.DcmFootstepPlanner.stance_start_dcm`."""
        if stance_foot not in self.feet:
            raise ParameterError(f"stance foot={stance_foot!r} must be one of {self.feet}")
        command = as_velocity_command(command)
        previous = self.feet[1 - self.feet.index(stance_foot)]
        pre_impact = orbit(self.params, command.v_x, command.v_y)[previous]
        return pre_impact + B_D @ desired_steps(self.params, command.v_x, command.v_y, previous)

    def solve(self, instance: AlipInstance, warm: AlipSolution | None = None) -> AlipSolution:
        """Solve eq. (11) for ``instance`` (raises AlipSolverError)."""
        return self.solver.solve(instance, warm)

    def plan(self, t: float, stance: StanceState, measured: ReducedState, command: VelocityCommand,
             obstacles=()) -> FootstepPlan:
        """Footsteps from ``t`` [s]: the NMPC's K steps, then nominal ones until t + params.horizon.

        ``obstacles``: the ALIP NMPC has no foothold constraints for obstacles: given any, it raises
        ParameterError (the DCM planner, :mod:`sequencer.footholds`, steps over them).

        A stance that has not begun (``t < stance.t_start``) is a start from standing, as for the DCM planner
        (:meth:`sequencer.dcm_planner.DcmFootstepPlanner.plan`): both feet stay on the ground until
        ``stance.t_start`` (the contact schedule holds them there) and the steps are planned from
        ``stance.t_start`` (t_curr = 0) and from the nominal gait's state at the start of a stance on this foot
        (:meth:`stance_start_state`), not from the measured one (the CoM between the feet, at rest): the
        whole-body OCP moves the centre of pressure over the double support to bring the robot there.

        Raises:
            ParameterError: bad input, a command outside :meth:`command_range`, or obstacles.
            AlipSolverError: the NMPC failed; a control loop keeps its last plan.
        """
        if len(obstacles):
            raise ParameterError(f"obstacles: the ALIP planner cannot avoid obstacles (given {len(obstacles)}); "
                                 "use the DCM planner (footstep_planner.kind = 'dcm')")
        instance = self.instance(t, stance, measured, command)
        key = (stance.foot, stance.t_start)
        warm = None
        if self.warm_start and self.last_solution is not None:
            warm = self.last_solution if key == self._last_key else self._shifted(self.last_solution, instance)
        solution = self.solve(instance, warm)
        self.last_solution, self.last_instance, self._last_key = solution, instance, key
        return self.footstep_plan(max(float(t), stance.t_start), stance, measured, instance, solution)

    def _shifted(self, solution: AlipSolution, instance: AlipInstance) -> AlipSolution:
        """The last solution one step on (after a touchdown), its last step from the orbit; duals zero."""
        K = self.nlp.K
        ell, x_des = self.nlp.desired(instance)
        w = np.concatenate([np.append(solution.periods[1:], self.params.t_des),
                            np.vstack([solution.torques[1:], np.zeros((1, 2))]).ravel(),
                            np.vstack([solution.steps[1:], ell[-1:]]).ravel(),
                            np.vstack([solution.states[1:], x_des[-1:]]).ravel()])
        return AlipSolution(w[:K], w[K:3 * K].reshape(K, 2), w[3 * K:5 * K].reshape(K, 2), w[5 * K:].reshape(K, 4),
                            solution.cost, 0, solution.solver, (), w, np.zeros(self.nlp.n_w), np.zeros(self.nlp.n_g))

    def footstep_plan(self, t: float, stance: StanceState, measured: ReducedState, instance: AlipInstance,
                      solution: AlipSolution) -> FootstepPlan:
        """The FootstepPlan of a solution (eq. 16 composition, nominal tail, DCM and CoP per stance)."""
        params, model = self.params, self.model
        omega, mz = model.omega, model.mz

        def dcm_offset(x):  # DCM relative to the contact, heading frame: p + v / ω, v = (L_y, -L_x) / (m z)
            return np.array([x[0] + x[1] / (mz * omega), x[2] - x[3] / (mz * omega)])

        periods, torques, steps = list(solution.periods), list(solution.torques), list(solution.steps)
        states = list(solution.states)
        # nominal tail: ℓ^des (within its box), T_des, τ = 0, until a touchdown at or after t + horizon
        foot, yaw = instance.stance_foot, stance.yaw
        feet = self.nlp.stance_sequence(instance.stance_foot)
        touchdown = stance.t_start + float(np.sum(periods))
        stance_k = feet[-1]
        other = {"left": "right", "right": "left"}
        x = states[-1]
        rate = instance.yaw_rate
        lb, ub = self.nlp.bounds(instance)
        box = {f: (lb[3 * self.nlp.K + 2 * i: 3 * self.nlp.K + 2 * i + 2], ub[3 * self.nlp.K + 2 * i: 3 * self.nlp.K + 2 * i + 2])
               for i, f in enumerate(feet[:2])}
        while touchdown < t + params.horizon:
            post = np.array(heading_change_entries(rate * periods[-1])) @ (x + B_D @ steps[-1])
            stance_k = other[stance_k]
            x = model.flow(post, (0.0, 0.0), params.t_des)
            periods.append(params.t_des)
            torques.append(np.zeros(2))
            steps.append(np.clip(desired_steps(params, instance.v_x, instance.v_y, stance_k), *box[stance_k]))
            states.append(x)
            touchdown += params.t_des
        # composition (eq. 16) in the world frame
        position, start = stance.position.copy(), stance.t_start
        planned = []
        for k, (period, ell, state) in enumerate(zip(periods, steps, states)):
            touchdown = start + period
            landing = other[foot]
            foothold = position + rotate_xy(ell, yaw)
            zeta = position + rotate_xy(dcm_offset(state), yaw)  # DCM continuous through the impact
            yaw_next = yaw + rate * period
            next_torque = torques[k + 1] if k + 1 < len(torques) else np.zeros(2)
            cop = rotate_xy(model.cop_offset(next_torque), yaw_next)
            planned.append(PlannedStep(landing, foothold, touchdown, zeta - foothold, zeta, start,
                                       solution.active if k == 0 else (), yaw_next, cop))
            position, start, foot, yaw = foothold, touchdown, landing, yaw_next
        x0 = instance.x0
        dcm0 = stance.position + rotate_xy(dcm_offset(x0), stance.yaw)
        return FootstepPlan(
            t0=t, stance_foot=stance.foot, stance_position=stance.position.copy(), dcm_measured=dcm0, omega=omega,
            steps=tuple(planned), t_stance_start=stance.t_start, horizon=params.horizon, com_height=params.com_height,
            stance_yaw=stance.yaw, double_support=params.double_support, feet=self.feet,
            stance_cop_offset=rotate_xy(model.cop_offset(solution.torques[0]), stance.yaw),
        )


def alip_state_about_contact(model: AlipModel, stance: StanceState, com, com_velocity, angular_momentum=None,
                             p_z: float | None = None) -> np.ndarray:
    """ALIP state (p_x, L_y, p_y, L_x) about the stance contact point, in the stance's heading frame (world
    rotated about z by stance.yaw), shape (4,).

    Args:
        com, com_velocity: CoM position [m] and velocity [m/s], world frame, shape (3,).
        angular_momentum: angular momentum about the contact point [kg·m²/s], world frame, shape (3,)
            (e.g. :func:`wbmpc.walking.alip_state.contact_angular_momentum`); None: the paper's approximation,
            eqs. 14-15 without the centroidal I ω terms (:meth:`AlipModel.state_from_velocity`), with the CoM
            height ``p_z`` [m] above the contact (None: the model's height, as the planner does).
    """
    p = rotate_xy(np.asarray(com, dtype=float)[:2] - stance.position, -stance.yaw)
    if angular_momentum is None:
        velocity = np.asarray(com_velocity, dtype=float)
        v = np.concatenate([rotate_xy(velocity[:2], -stance.yaw), velocity[2:]])
        return model.state_from_velocity(p, v, p_z)
    L = rotate_xy(np.asarray(angular_momentum, dtype=float)[:2], -stance.yaw)  # (L_x, L_y)
    return np.array([p[0], L[1], p[1], L[0]])


def desired_orbit(params: AlipParams, command: VelocityCommand) -> dict[str, np.ndarray]:
    """The desired pre-impact states of ``command`` (see :func:`sequencer.alip.nlp.orbit`)."""
    return orbit(params, command.v_x, command.v_y)

