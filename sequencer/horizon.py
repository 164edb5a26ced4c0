"""Fixed-horizon footstep sequencer: Algorithm 1 of Roux et al. 2024 (eqs. 13-16).

From the measured DCM and the time elapsed in the current stance, solve the one-step QP, then
repeat from the planned touchdown (new stance foot = the foot that just landed, measured DCM =
p_T + b_T, elapsed time 0), alternating the stance foot and the width bounds, until a touchdown
time is at or after ``t + horizon``.

Time convention (documented deviation, see docs/sequencer.md): every QP of the sequence is
written in the time of its own stance (Gamma = exp(omega (T_{k+1} - T_k))). Eqs. (13)-(16) write
Gamma in the clock of the first stance; the constraints are identical, but the absolute form
multiplies alpha2 by exp(2 omega T_k) for the k-th step (about 1e14 at the end of a 3 s horizon),
which would freeze the timing of all later steps and depend on the choice of time origin.

Heading frame (turning and lateral commands): with ``stance_yaw`` ψ_0 and ``yaw_rate`` r given,
the QP of step k is written in the frame of its stance rotated about z by the planned heading
ψ_k (x along the heading), ψ_{k+1} = ψ_k + r T_k with T_k the planned duration of step k; the
composition and its exactness are described in :mod:`sequencer.dcm_planner`. With ψ_0 = 0 and
r = 0 no rotation is applied: the plan is bit for bit the paper's world-frame Algorithm 1.

Command and corrections per call: ``velocity`` (v_x, v_y) and ``corrections``
(:class:`sequencer.corrections.LipmCorrections`) override the parameter set's ``v_x``, ``v_y``,
``swing_drift`` and ``dcm_offset_bias`` for one plan without rebuilding the sequencer; the nominal
steps and offsets of the last distinct (command, corrections) are kept (:meth:`FootstepSequencer.nominal_gait`).

Failure: :meth:`FootstepSequencer.plan` raises :class:`sequencer.step_qp.InfeasibleStep` (a
:class:`sequencer.step_qp.StepQPError`, itself a :class:`wbmpc.errors.SolverError`) carrying the
failing :class:`StepProblem` and the solver status. A closed loop that wants to keep running
catches ``StepQPError`` and keeps its previous plan; ``clamp_elapsed=True`` avoids the most
common cause (the foot has not landed by T_max) by planning as if the elapsed time were T_max.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from sequencer.backends import make_backend
from sequencer.corrections import LipmCorrections
from sequencer.footholds import Crossing, FootholdConstraints, StepCandidate, crossing_of, sole_on_obstacle
from sequencer.nominal import FEET, NominalGait, other_foot
from sequencer.params import SequencerParams
from sequencer.step_qp import CONSTRAINT_NAMES, InfeasibleStep, StepProblem, solve_exact_scalars
from wbmpc.errors import ParameterError

# the obstacle options only the 'exact' backend plans: (SequencerParams field, its value's unit and what it plans)
EXACT_ONLY_OPTIONS = (("obstacle_double_support", "s (a quasi-static crossing)"),
                      ("obstacle_trailing_double_support", "s"),
                      ("obstacle_resume_double_support", "s"),
                      ("obstacle_crossing_cop", "m (the crossing's centre of pressure)"),
                      ("obstacle_passed_cop", "m (the passed obstacle's centre of pressure)"),
                      ("obstacle_approach_distance", "m (the even approach)"),
                      ("obstacle_width_min", "m (the narrower steps of a negotiation)"))
#: options of the 'exact' backend only, with or without obstacles
EXACT_ONLY_STEP_OPTIONS = (("swing_commit_time", "s (the committed swing foothold)"),)
_ACTIVE_NAMES = tuple(tuple(CONSTRAINT_NAMES[i] for i in range(6) if (bits >> i) & 1) for bits in range(64))


@dataclass(frozen=True, slots=True)
class PlannedStep:
    """One planned touchdown.

    Attributes:
        foot: ``"left"`` or ``"right"``, the foot that LANDS at this step.
        position: world (x, y) of the foothold p_T [m], shape (2,).
        touchdown_time: absolute touchdown time [s] (same clock as the plan's t0).
        dcm_offset: b_T = zeta_T - p_T, world frame [m], shape (2,).
        dcm_at_touchdown: zeta_T = p_T + b_T, world (x, y) [m], shape (2,).
        stance_start_time: when the stance preceding this touchdown began [s].
        active: names of the active inequalities of this step's QP (see step_qp.CONSTRAINT_NAMES).
        yaw: world yaw of the foothold [rad] (not wrapped): the heading ψ_{k+1} = ψ_k + yaw_rate T_k
            of the stance this touchdown starts, the frame the next step's QP is written in.
        cop_offset: world (x, y) offset [m] of the constant centre of pressure from this foothold during the
            stance this touchdown starts (the pendulum's pivot is position + cop_offset), or None: the
            foothold itself (the DCM planner, point feet). The ALIP planner's ankle torque τ is such a
            constant CoP shift (c_x = -τ_y / (m g), c_y = τ_x / (m g)), so its CoM reference stays exact.
        crossing: the obstacle this step's swing passes over (a :class:`sequencer.footholds.Crossing`: the
            obstacle, the lift-off point and the part of the path over it), or None: the whole-body OCP lifts
            a crossing swing over the obstacle (``docs/sequencer.md``, "Obstacles").
        double_support: None (the plan's ``double_support``), or this step's own [s]: a *settled* step of a
            quasi-static crossing (``SequencerParams.obstacle_double_support``), or the trailing crossing swing and
            the step after it (``SequencerParams.obstacle_trailing_double_support``): its swing lifts off this long
            after the stance began, and until ``double_support - plan.double_support`` after it the planner's
            model holds the DCM (the pendulum's pivot under it): where the touchdown left it for the first half
            of that time, at ``settle_dcm`` for the second (the centre of pressure moving within both soles is
            modelled as a jump of the DCM to that point; half way, so that the CoM reference does not move on
            before the foot is down), the LIPM from it after that.
        settle_dcm: world (x, y) [m] the DCM settles at in that double support (the stance foothold before a
            crossing swing; the nominal stance-start offset for the step resuming the walk), or None.
    """

    foot: str
    position: np.ndarray
    touchdown_time: float
    dcm_offset: np.ndarray
    dcm_at_touchdown: np.ndarray
    stance_start_time: float
    active: tuple[str, ...] = ()
    yaw: float = 0.0
    cop_offset: np.ndarray | None = None
    crossing: Crossing | None = None
    double_support: float | None = None
    settle_dcm: np.ndarray | None = None

    @property
    def duration(self) -> float:
        """Step duration: touchdown_time - stance_start_time [s]."""
        return self.touchdown_time - self.stance_start_time


@dataclass(frozen=True, slots=True)
class FootstepPlan:
    """Output of Algorithm 1: the stance at planning time and the planned touchdowns.

    Attributes:
        t0: planning (measurement) time [s].
        stance_foot: foot in stance at t0.
        stance_position: world (x, y) of the stance foot [m], shape (2,).
        dcm_measured: world (x, y) DCM at t0 [m], shape (2,).
        omega: LIPM natural frequency [1/s].
        steps: planned touchdowns in time order; the last one is at or after t0 + horizon.
        t_stance_start: when the current stance began [s] (<= t0).
        horizon: H_u [s].
        com_height: CoM height of the planner's model above the ground [m] (the LIPM's z_c).
        stance_yaw: world yaw of the stance foot's heading frame [rad].
        double_support: time both feet stay on the ground after each touchdown [s] (0 = point feet).
        feet: names of the feet the plan alternates, in the order schedules index them.
        stance_cop_offset: world (x, y) offset [m] of the constant CoP from the stance foothold until the
            first touchdown (the pivot of the current stance), or None (the foothold); see PlannedStep.cop_offset.
    """

    t0: float
    stance_foot: str
    stance_position: np.ndarray
    dcm_measured: np.ndarray
    omega: float
    steps: tuple[PlannedStep, ...]
    t_stance_start: float
    horizon: float
    com_height: float
    stance_yaw: float = 0.0
    double_support: float = 0.0
    feet: tuple[str, ...] = FEET
    stance_cop_offset: np.ndarray | None = None

    # ------------------------------------------------------------------ queries
    @property
    def touchdown_times(self) -> np.ndarray:
        """Touchdown times [s], shape (K,)."""
        return np.array([s.touchdown_time for s in self.steps])

    @property
    def positions(self) -> np.ndarray:
        """Footholds, world (x, y) [m], shape (K, 2)."""
        return np.array([s.position for s in self.steps])

    @property
    def yaws(self) -> np.ndarray:
        """World yaw of each planned foothold [rad], shape (K,)."""
        return np.array([s.yaw for s in self.steps])

    def _segments(self):
        """(start time, pendulum pivot, DCM at start) of every stance, the current one first (the pivot is the
        foothold, shifted by the CoP offset when the plan has one)."""
        pivot = self.stance_position if self.stance_cop_offset is None else self.stance_position + self.stance_cop_offset
        start, dcm = self.t0, self.dcm_measured
        for step in self.steps:
            if step.settle_dcm is not None:  # a settled stance: the DCM held, then at settle_dcm, until the LIPM resumes
                resume = step.stance_start_time + step.double_support - self.double_support
                hold = 0.5 * (step.stance_start_time + resume)
                if start < hold:
                    yield start, dcm, dcm
                    start = hold
                if start < resume:
                    yield start, step.settle_dcm, step.settle_dcm
                    start, dcm = resume, step.settle_dcm
            yield start, pivot, dcm
            start, dcm = step.touchdown_time, step.dcm_at_touchdown
            pivot = step.position if step.cop_offset is None else step.position + step.cop_offset
        yield start, pivot, dcm

    def _check_times(self, t) -> np.ndarray:
        times = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(times)):
            raise ParameterError(f"t={t!r} must be finite")
        if np.any(times < self.t0 - 1e-12):
            raise ParameterError(f"t={t!r} s must be >= the plan's t0={self.t0} s")
        return times

    def dcm_at(self, t) -> np.ndarray:
        """LIPM DCM prediction (eq. 1b through the planned steps), world (x, y) [m].

        Args:
            t: time(s) [s] >= t0, scalar or shape (n,). Returns shape (2,) or (n, 2).
        """
        times = self._check_times(t)
        flat = np.atleast_1d(times)
        out = np.empty((flat.size, 2))
        segments = list(self._segments())
        for i, (start, foot, dcm0) in enumerate(segments):
            end = segments[i + 1][0] if i + 1 < len(segments) else np.inf
            mask = (flat >= start) & (flat < end) if i > 0 else (flat < end)
            if np.any(mask):
                tau = flat[mask] - start
                out[mask] = foot + np.outer(np.exp(self.omega * tau), dcm0 - foot)
        return out[0] if times.ndim == 0 else out

    def lipm_com_at(self, t, com_xy_measured) -> np.ndarray:
        """LIPM CoM prediction (eqs. 1a/1b integrated through the planned steps), world (x, y) [m].

        Within a stance on foot p starting at s with CoM c0 and DCM z0 (exact solution)::

            c(s + tau) = p + (c0 - p) e^{-omega tau} + (z0 - p) (e^{omega tau} - e^{-omega tau}) / 2

        After the last planned touchdown the last foothold stays in stance.

        Args:
            t: time(s) [s] >= t0, scalar or shape (n,).
            com_xy_measured: CoM (x, y) at t0 [m], shape (2,).
        Returns:
            shape (2,) for a scalar t, else (n, 2).
        """
        com0 = np.asarray(com_xy_measured, dtype=float)
        if com0.shape != (2,) or not np.all(np.isfinite(com0)):
            raise ParameterError(f"com_xy_measured={com_xy_measured!r} must be a finite (x, y) pair")
        times = self._check_times(t)
        if times.ndim == 0:
            return self._lipm_com_scalar(float(times), com0)
        flat = np.atleast_1d(times)
        out = np.empty((flat.size, 2))
        segments = list(self._segments())
        com = com0
        for i, (start, foot, dcm0) in enumerate(segments):
            end = segments[i + 1][0] if i + 1 < len(segments) else np.inf
            mask = (flat >= start) & (flat < end) if i > 0 else (flat < end)
            if np.any(mask):
                tau = (flat[mask] - start)[:, None]
                out[mask] = (
                    foot + (com - foot) * np.exp(-self.omega * tau)
                    + (dcm0 - foot) * (np.exp(self.omega * tau) - np.exp(-self.omega * tau)) / 2.0
                )
            if np.isfinite(end):
                tau = end - start
                com = (
                    foot + (com - foot) * math.exp(-self.omega * tau)
                    + (dcm0 - foot) * (math.exp(self.omega * tau) - math.exp(-self.omega * tau)) / 2.0
                )
        return out[0] if times.ndim == 0 else out

    def com_reference(self, t, com_xy_measured) -> np.ndarray:
        """The planner model's CoM prediction, world frame [m]: (x, y) of :meth:`lipm_com_at`, z = com_height.

        Model-neutral: what a whole-body OCP tracks (e.g. its terminal CoM), whatever planner made the plan.

        Args:
            t: time(s) [s] >= t0, scalar or shape (n,).
            com_xy_measured: CoM (x, y) at t0 [m], shape (2,).
        Returns:
            shape (3,) for a scalar t, else (n, 3).
        """
        com_xy = self.lipm_com_at(t, com_xy_measured)
        if com_xy.ndim == 1:
            return np.array((com_xy[0], com_xy[1], self.com_height))
        return np.column_stack((com_xy, np.full(com_xy.shape[0], self.com_height)))

    def _lipm_com_scalar(self, t: float, com0: np.ndarray) -> np.ndarray:
        """lipm_com_at for one time, on plain floats (called every control cycle)."""
        if any(step.settle_dcm is not None for step in self.steps):
            return self.lipm_com_at(np.array([t]), com0)[0]
        omega = self.omega
        cx, cy = float(com0[0]), float(com0[1])
        start = self.t0
        fx, fy = float(self.stance_position[0]), float(self.stance_position[1])
        if self.stance_cop_offset is not None:
            fx, fy = fx + float(self.stance_cop_offset[0]), fy + float(self.stance_cop_offset[1])
        zx, zy = float(self.dcm_measured[0]), float(self.dcm_measured[1])
        for step in self.steps:
            end = step.touchdown_time
            if t < end:
                break
            grow, decay = math.exp(omega * (end - start)), math.exp(-omega * (end - start))
            cx = fx + (cx - fx) * decay + (zx - fx) * (grow - decay) / 2.0
            cy = fy + (cy - fy) * decay + (zy - fy) * (grow - decay) / 2.0
            start = end
            fx, fy = float(step.position[0]), float(step.position[1])
            if step.cop_offset is not None:
                fx, fy = fx + float(step.cop_offset[0]), fy + float(step.cop_offset[1])
            zx, zy = float(step.dcm_at_touchdown[0]), float(step.dcm_at_touchdown[1])
        grow, decay = math.exp(omega * (t - start)), math.exp(-omega * (t - start))
        return np.array((fx + (cx - fx) * decay + (zx - fx) * (grow - decay) / 2.0,
                         fy + (cy - fy) * decay + (zy - fy) * (grow - decay) / 2.0))

    def mean_velocity(self) -> np.ndarray:
        """Average foothold velocity over the plan, (x, y) [m/s], from the stance foot to the last step.

        Uses the two feet's mean position at the first and last pair of footholds so that the
        lateral zig-zag cancels.
        """
        if len(self.steps) < 3:
            raise ParameterError(f"mean_velocity needs at least 3 planned steps, the plan has {len(self.steps)}")
        first_mid = 0.5 * (self.steps[0].position + self.steps[1].position)
        last_mid = 0.5 * (self.steps[-2].position + self.steps[-1].position)
        t_first = 0.5 * (self.steps[0].touchdown_time + self.steps[1].touchdown_time)
        t_last = 0.5 * (self.steps[-2].touchdown_time + self.steps[-1].touchdown_time)
        return (last_mid - first_mid) / (t_last - t_first)


class FootstepSequencer:
    """Receding-horizon footstep sequencer (Algorithm 1) with one warm QP workspace.

    Args:
        params: SequencerParams (weights, bounds, default command, horizon).
        backend: ``"exact"`` (default: closed-form active-set solution of the same QP, ~10x faster,
            verified against OSQP and ProxQP in the tests), ``"osqp"`` (the paper's solver) or
            ``"proxqp"``.
    """

    def __init__(self, params: SequencerParams, backend: str = "exact"):
        if not isinstance(params, SequencerParams):
            raise ParameterError(f"params must be a SequencerParams, got {type(params).__name__}")
        self.base_params = params
        self.backend_name = backend
        self.backend = make_backend(backend)
        self._use(params.at_speed(params.v_x))

    def set_speed(self, v_x: float) -> SequencerParams:
        """Plan with ``base_params.at_speed(v_x)`` from now on (the speed schedule at forward command ``v_x``
        [m/s]; ``plan`` calls it with its command) and return them."""
        params = self.base_params.at_speed(v_x)
        if params is not self.params:
            self._use(params)
        return params

    def _use(self, params: SequencerParams) -> None:
        """``params`` (the schedule's set at one speed) and the values derived from them."""
        self.params = params
        omega = params.omega
        self._omega = omega
        self._gamma_nom = math.exp(omega * params.t_nom)
        self._gamma_hi = math.exp(omega * params.t_max)
        self._gamma_lo0 = math.exp(omega * params.t_min)
        self._width_bounds = {foot: params.width_bounds(foot) for foot in FEET}
        self._max_steps = int(math.ceil(params.horizon / params.t_min)) + 2
        own_key = (params.v_x, params.v_y, params.swing_drift, params.dcm_offset_bias, params.stance_drift)
        self._own_gait = self._build_gait_tables(own_key)  # the parameters' own command and corrections
        self._gait_key, self._gait = own_key, self._own_gait  # the last distinct one asked for

    def nominal_gait(self, velocity=None, corrections: LipmCorrections | None = None) -> NominalGait:
        """Nominal steps and aimed offsets for ``velocity`` (v_x, v_y) [m/s] (None: the params') and
        ``corrections`` (None: the params' swing_drift, dcm_offset_bias and stance_drift).

        The last distinct (command, corrections) is kept: a repeated call costs one comparison.

        Raises:
            ParameterError: the command is outside ``params.velocity_range()`` (names the component).
        """
        return self._gait_tables(velocity, corrections)[0]

    def _gait_tables(self, velocity, corrections) -> tuple[NominalGait, dict]:
        """(gait, stance foot -> (w_nom, (b_x, b_y), (w_min, w_max))): the gait and what one step QP reads of it."""
        if velocity is None and corrections is None:
            return self._own_gait
        params = self.params
        v_x, v_y = (params.v_x, params.v_y) if velocity is None else velocity
        if corrections is None:
            key = (v_x, v_y, params.swing_drift, params.dcm_offset_bias, params.stance_drift)
        else:
            key = (v_x, v_y, *corrections.as_tuple())
        if key != self._gait_key:
            self._gait, self._gait_key = self._build_gait_tables(key), key
        return self._gait

    def _build_gait_tables(self, key: tuple[float, ...]) -> tuple[NominalGait, dict]:
        """The gait tables of (v_x, v_y, swing_drift, dcm_offset_bias, stance_drift); raises
        ParameterError out of range."""
        gait = self.params.nominal_gait(*key)
        per_stance = {foot: (w_nom, b_nom, self._width_bounds[foot]) for foot, (w_nom, b_nom) in gait.per_stance.items()}
        return gait, per_stance

    def problem(self, stance_foot: str, stance_position, dcm_measured, elapsed: float,
                gait: NominalGait | None = None) -> StepProblem:
        """The one-step QP (eqs. 2-5) for this sequencer's weights and bounds and ``gait``'s nominal
        values (None: the parameters' own), with p0 and the DCM in the frame the QP is written in."""
        gait = self.nominal_gait() if gait is None else gait
        return StepProblem.from_params(self.params, stance_foot, stance_position, dcm_measured, elapsed, gait)

    def plan(
        self,
        t: float,
        stance_foot: str,
        stance_position,
        dcm_measured,
        t_stance_start: float,
        clamp_elapsed: bool = False,
        *,
        stance_yaw: float = 0.0,
        yaw_rate: float = 0.0,
        velocity=None,
        corrections: LipmCorrections | None = None,
        obstacles=(),
        liftoff=None,
        first_crossing: bool | None = None,
        first_resume: bool = False,
        first_lateral: tuple[float, float] | None = None,
    ) -> FootstepPlan:
        """Run Algorithm 1 from the measured state.

        Args:
            t: measurement time [s].
            stance_foot: ``"left"`` or ``"right"``, the foot on the ground at t.
            stance_position: world (x, y) of the stance foot [m], shape (2,).
            dcm_measured: world (x, y) of the measured DCM at t [m], shape (2,).
            t_stance_start: when the current stance began [s], <= t (t - t_stance_start is the
                paper's "time elapsed since the last contact").
            clamp_elapsed: if True and the elapsed time exceeds T_max, plan as if it were T_max
                (touchdown now) instead of raising InfeasibleStep.
            stance_yaw: world yaw ψ_0 of the stance foot's heading frame [rad].
            yaw_rate: commanded turning rate r [rad/s]; step k's QP is written in the heading frame
                ψ_k, ψ_{k+1} = ψ_k + r T_k.
            velocity: (v_x, v_y) [m/s] in the heading frame; None = ``params.v_x``, ``params.v_y``. The plan's
                timing is the speed schedule's at v_x (:meth:`set_speed`).
            corrections: live LIPM corrections; None = ``params.swing_drift``, ``params.dcm_offset_bias``.
            obstacles: :class:`sequencer.obstacles.Obstacle` s the footholds avoid (:mod:`sequencer.footholds`,
                the before/beyond choice per step); empty: the plan without obstacles, bit for bit.
            liftoff: world (x, y) [m] where the swinging foot lifted off (None: unknown; the first step's
                swing is then not marked as a crossing, nor lengthened).
            first_crossing: the before/beyond decision of the first step kept (True: it crosses when one step
                reaches beyond; False: it stays before), None: decided now (see :mod:`sequencer.footholds`).
            first_resume: the current stance began with the touchdown of a settled crossing swing (quasi-static
                crossing, ``params.obstacle_double_support`` > 0): its next step, unless it crosses too, is the
                settled step that resumes the walk (``PlannedStep.settle_dcm``).
            first_lateral: (low, high) [m]: the first step's lateral component (across the stance's heading, from
                the stance foothold) also within this window, intersected with its width bounds (the nearest bound
                when they do not meet; ``swing_commit_time``); None: its width bounds only. The 'exact' backend.

        Returns:
            FootstepPlan whose last step lands at or after t + horizon.

        Raises:
            ParameterError: bad input (names the argument and value).
            InfeasibleStep / StepQPError: a QP failed; carries the problem data and solver status.
        """
        if stance_foot not in FEET:
            raise ParameterError(f"stance_foot={stance_foot!r} must be 'left' or 'right'")
        t = float(t)
        t_stance_start = float(t_stance_start)
        if not (math.isfinite(t) and math.isfinite(t_stance_start)):
            raise ParameterError(f"t={t} s and t_stance_start={t_stance_start} s must be finite")
        elapsed = t - t_stance_start
        if elapsed < 0:
            raise ParameterError(f"t_stance_start={t_stance_start} s must be <= t={t} s")
        p0 = np.asarray(stance_position, dtype=float)
        dcm = np.asarray(dcm_measured, dtype=float)
        if p0.shape != (2,) or not (math.isfinite(p0[0]) and math.isfinite(p0[1])):
            raise ParameterError(f"stance_position={stance_position!r} must be a finite (x, y) pair [m]")
        if dcm.shape != (2,) or not (math.isfinite(dcm[0]) and math.isfinite(dcm[1])):
            raise ParameterError(f"dcm_measured={dcm_measured!r} must be a finite (x, y) pair [m]")
        stance_yaw, yaw_rate = float(stance_yaw), float(yaw_rate)
        if not (math.isfinite(stance_yaw) and math.isfinite(yaw_rate)):
            raise ParameterError(f"stance_yaw={stance_yaw} rad and yaw_rate={yaw_rate} rad/s must be finite")
        self.set_speed(self.base_params.v_x if velocity is None else velocity[0])
        gait, per_stance = self._gait_tables(velocity, corrections)
        params = self.params
        constraints = None
        if first_lateral is not None:
            first_lateral = (float(first_lateral[0]), float(first_lateral[1]))
            if not (math.isfinite(first_lateral[0]) and math.isfinite(first_lateral[1])
                    and first_lateral[0] <= first_lateral[1]):
                raise ParameterError(f"first_lateral={first_lateral} m must be a finite (low, high) with low <= high")
        for name, unit in EXACT_ONLY_STEP_OPTIONS:
            if getattr(params, name) > 0.0 and self.backend_name != "exact":
                raise ParameterError(f"{name}={getattr(params, name)} {unit} is planned by the 'exact' backend only, "
                                     f"not {self.backend_name!r}")
        if len(obstacles):
            constraints = FootholdConstraints(obstacles, params.foothold_geometry(), self._omega)
            for name, unit in EXACT_ONLY_OPTIONS:
                value = getattr(params, name)
                if value > 0.0 and self.backend_name != "exact":
                    raise ParameterError(f"{name}={value} {unit} is planned by the 'exact' backend only, "
                                         f"not {self.backend_name!r}")
            if params.obstacle_width_min > 0.0:  # the inner width bound of a negotiation's steps
                per_stance = {foot: (w_nom, b_nom, params.width_bounds(foot, negotiating=True))
                              for foot, (w_nom, b_nom, _) in per_stance.items()}
            if liftoff is not None:
                liftoff = np.asarray(liftoff, dtype=float)
                if liftoff.shape != (2,) or not np.all(np.isfinite(liftoff)):
                    raise ParameterError(f"liftoff={liftoff!r} must be a finite (x, y) pair [m] or None")
        if elapsed > params.t_max:
            if clamp_elapsed:
                elapsed = params.t_max
            else:
                raise InfeasibleStep(
                    f"elapsed time t - t_stance_start = {elapsed:.4g} s exceeds T_max={params.t_max} s",
                    self.problem(stance_foot, p0, dcm, 0.0, gait),
                    "primal infeasible",
                    self.backend_name,
                )
        if self.backend_name == "exact":
            steps, stance_cop = self._plan_exact(t, stance_foot, p0, dcm, t - elapsed, elapsed, stance_yaw, yaw_rate,
                                     gait.step_length, per_stance, constraints, liftoff, first_crossing,
                                     t - t_stance_start, first_resume, first_lateral)
        else:
            stance_cop = None
            steps = self._plan_backend(t, stance_foot, p0, dcm, t - elapsed, elapsed, stance_yaw, yaw_rate, gait,
                                       constraints, liftoff, first_crossing)
        if constraints is not None:
            steps = self._mark_crossings(steps, p0, liftoff, constraints)
        return FootstepPlan(
            t0=t, stance_foot=stance_foot, stance_position=p0.copy(), dcm_measured=dcm.copy(), omega=self._omega,
            steps=tuple(steps), t_stance_start=t_stance_start, horizon=params.horizon, com_height=params.z_c,
            stance_yaw=stance_yaw, double_support=params.double_support, feet=FEET, stance_cop_offset=stance_cop,
        )

    def _plan_exact(self, t, stance, p0, dcm, stance_start, elapsed, yaw, yaw_rate, l_nom, per_stance,
                    constraints: FootholdConstraints | None = None, liftoff=None,
                    first_crossing: bool | None = None, elapsed_true: float | None = None,
                    first_resume: bool = False, first_lateral: tuple[float, float] | None = None
                    ) -> tuple[list[PlannedStep], np.ndarray | None]:
        """The steps of the 'exact' backend and the centre of pressure's offset from the current stance foothold
        (world (x, y) [m], None: the foothold) its swing is planned with (``first_lateral``: the first step's lateral
        window, :meth:`plan`)."""
        params = self.params
        omega = self._omega
        elapsed_true = elapsed if elapsed_true is None else elapsed_true
        true_start = t - elapsed_true if elapsed_true != elapsed else stance_start  # not clamped to t_max
        t_end = t + params.horizon
        rotate = yaw != 0.0 or yaw_rate != 0.0  # else the world frame is every stance's heading frame
        p0x, p0y = float(p0[0]), float(p0[1])
        p0_first = (p0x, p0y)
        zx, zy = float(dcm[0]), float(dcm[1])
        steps, vectors = [], []  # (foot, touchdown, stance start, active bits, yaw), (p_T, b_T, zeta_T)
        pivots = []  # the centre of pressure's offset from each stance's foothold (world (x, y) [m]) or None
        halt = constraints.geometry.halt_double_support if constraints is not None else 0.0
        # a settle before the trailing crossing swing (and the step resuming the walk after it) only
        halt_trailing = constraints.geometry.trailing_double_support if constraints is not None else 0.0
        # a settle before the step resuming the walk after the trailing crossing swing
        halt_resume = constraints.geometry.resume_double_support if constraints is not None else 0.0
        resume_next = first_resume  # the step ending the current stance resumes the walk after a crossing
        for _ in range(self._max_steps):
            lift = liftoff if not steps else (vectors[-2][:2] if len(steps) >= 2 else p0_first)
            cross_kept = None if steps else first_crossing
            window = None if steps else first_lateral
            px, py, gamma, bx, by, bits, cop = self._exact_step(
                p0x, p0y, zx, zy, elapsed, yaw, rotate, stance, per_stance, l_nom, constraints, lift, cross_kept,
                approach=self._approach(p0x, p0y, yaw, stance, per_stance, l_nom, constraints), lateral_window=window)
            settle, start_qp, own_halt = None, stance_start, 0.0
            if halt > 0.0 or halt_trailing > 0.0 or halt_resume > 0.0:  # settled crossing swings and resuming
                # steps (obstacle_double_support, obstacle_trailing_double_support, obstacle_resume_double_support)
                c, s = math.cos(yaw), math.sin(yaw)
                ox, oy = per_stance[other_foot(stance)][1]
                walking = (p0x + c * ox - s * oy, p0y + s * ox + c * oy)  # the nominal DCM at a stance start
                # the step crosses when the nominal gait's step from this stance would (not the measured DCM's:
                # settled on the stance foot, the DCM asks for a step in place and would never cross)
                tx, ty, *_ = self._exact_step(p0x, p0y, *walking, 0.0, yaw, rotate, stance, per_stance, l_nom,
                                              constraints, lift, cross_kept)
                crosses = crossing_of(constraints.obstacles, lift, (tx, ty), yaw, constraints.geometry) is not None
                # the trailing crossing: its stance foot has crossed already (lift-off -> stance passes over it, the
                # stance sole itself off it: a stance sole within the margin, before the box, is no lead foot)
                trailing = crosses and crossing_of(constraints.obstacles, lift, (p0x, p0y), yaw,
                                                   constraints.geometry) is not None \
                    and not sole_on_obstacle(constraints.obstacles, (p0x, p0y), yaw, constraints.geometry)
                if crosses:  # the trailing settle once the lead foot is down (the plan's first step): planned
                    # earlier, it changed the H1's approach to the box or its lead swing (docs/ocp.md)
                    own_halt = halt_trailing if trailing and halt_trailing > 0.0 and not steps else halt
                else:  # resuming the walk after the trailing crossing (a resuming settle alone: once the trailing
                    # foot is down, the resuming step the plan's first)
                    own_halt = (0.0 if steps else halt_resume) if halt_resume > 0.0 else (halt_trailing or halt)
                if (crosses or resume_next) and own_halt > 0.0:
                    # before a crossing swing on the stance foot along the heading and across it where the crossing
                    # duration's LIPM carries the DCM to its nominal offset at a nominal width, (b_y + w_nom)
                    # exp(-ω T) (held on the stance foot, the QP widened the step to its bound: the H1's lead foot
                    # 0.6 m aside, out of reach; with the walk's offset the OCP diverged); the walking offset when
                    # the walk resumes
                    w_nom, (_, bny), _ = per_stance[stance]
                    across = (bny + w_nom) * math.exp(-omega * constraints.geometry.step_duration_min)
                    settle = (p0x - s * across, p0y + c * across) if crosses else walking
                    shift = own_halt - params.double_support
                    if not steps:
                        stance_start = true_start
                    start_qp = stance_start + shift
                    measured = not steps and elapsed_true >= shift  # the swing has begun: the measured DCM
                    qz = (zx, zy) if measured else settle
                    q_elapsed = min(elapsed_true - shift, params.t_max) if measured else 0.0
                    t_min = constraints.geometry.step_duration_min if crosses else 0.0
                    step = self._exact_step(p0x, p0y, *qz, q_elapsed, yaw, rotate, stance, per_stance, l_nom,
                                            constraints, lift, True if crosses else cross_kept, duration_min=t_min,
                                            lateral_window=window)
                    if crosses and crossing_of(constraints.obstacles, lift, step[:2], yaw,
                                               constraints.geometry) is None:  # short of it: where the gait crosses
                        step = self._exact_step(p0x, p0y, *qz, q_elapsed, yaw, rotate, stance, per_stance, l_nom,
                                                constraints, lift, True, duration_min=t_min,
                                                length_min=c * (tx - p0x) + s * (ty - p0y), lateral_window=window)
                    px, py, gamma, bx, by, bits, cop = step
                # quasi-static: the walk resumes after the trailing crossing (the step after the lead crosses too);
                # a trailing settle alone: after the settled trailing crossing
                resume_next = crosses if halt > 0.0 else (trailing and (own_halt > 0.0 or halt_resume > 0.0))
            pivots.append((-cop * math.cos(yaw), -cop * math.sin(yaw)) if cop != 0.0 else None)
            duration = math.log(gamma) / omega
            touchdown = max(start_qp + duration, t) if settle is not None else start_qp + duration
            yaw = yaw + yaw_rate * (duration if settle is None else touchdown - stance_start)
            landing = "right" if stance == "left" else "left"
            zx, zy = px + bx, py + by
            steps.append((landing, touchdown, stance_start, bits, yaw, settle, own_halt if settle is not None else 0.0))
            vectors.append((px, py, bx, by, zx, zy))
            if touchdown >= t_end:
                break
            stance, p0x, p0y, stance_start, elapsed, elapsed_true = landing, px, py, touchdown, 0.0, 0.0
        values = np.array(vectors)  # one array for all steps: their vectors are rows of it
        pivots.append(None)  # the stance after the last step: no swing planned in it
        cop_offsets = [None if pivot is None else np.array(pivot) for pivot in pivots]
        planned = [
            PlannedStep(landing, values[k, 0:2], touchdown, values[k, 2:4], values[k, 4:6], start, _ACTIVE_NAMES[bits],
                        yaw, cop_offset=cop_offsets[k + 1])
            if settle is None else
            PlannedStep(landing, values[k, 0:2], touchdown, values[k, 2:4], values[k, 4:6], start, _ACTIVE_NAMES[bits],
                        yaw, cop_offset=cop_offsets[k + 1], double_support=own, settle_dcm=np.array(settle))
            for k, (landing, touchdown, start, bits, yaw, settle, own) in enumerate(steps)
        ]
        return planned, cop_offsets[0]

    def _approach(self, p0x, p0y, yaw, stance, per_stance, l_nom,
                  constraints: FootholdConstraints | None) -> tuple[float, float, float] | None:
        """(ℓ_nom, b_x,nom, b) [m], heading frame: the even approach's nominal length and DCM offset for the step
        from the stance (p0x, p0y) towards the last foothold before an obstacle ("The approach" in
        :mod:`sequencer.footholds`), and the obstacle's far bound b from the stance (a step from whose foothold one
        step reaches it may be the last before the obstacle); None: the gait's (no obstacle within
        ``obstacle_approach_distance``, or less than half a nominal step before its foothold bound)."""
        if constraints is None:
            return None
        approach = constraints.approach((p0x, p0y), yaw, per_stance[stance][2], l_nom)
        if approach is None:
            return None
        a, b = approach
        steps = round(a / l_nom)
        if steps < 1:
            return None
        length = a / steps
        aim = constraints.last_step_aim(b - a, 1.0, l_nom, per_stance[other_foot(stance)][1][0]
                                        if steps % 2 == 0 else per_stance[stance][1][0],
                                        travel=b - length * (steps - 1))  # the crossing lifts off step n - 1
        for _ in range(steps - 1):  # eq. 1b backwards: b_{k-1} = (ℓ + b_k) / γ_nom
            aim = (length + aim) / self._gamma_nom
        return length, aim, b

    def _exact_step(self, p0x, p0y, zx, zy, elapsed, yaw, rotate, stance, per_stance, l_nom,
                    constraints: FootholdConstraints | None, lift, cross, duration_min: float = 0.0,
                    length_min: float | None = None, approach: tuple[float, float, float] | None = None,
                    lateral_window: tuple[float, float] | None = None) -> tuple:
        """(p_x, p_y, γ, b_x, b_y, active bits, δ) of one step QP (closed form) from the stance foothold (p0x, p0y)
        and the DCM (zx, zy) ``elapsed`` [s] into the stance (world frame [m]), in the heading frame of ``yaw``
        [rad] (``rotate``: else the world frame is the heading frame), with its foothold outside the obstacles
        of ``constraints`` (``lift``: where the swinging foot lifted off; ``cross``: the before/beyond decision
        kept, or None), its duration at least ``duration_min``
        [s], its length along the heading at least ``length_min`` [m] (None: ``l_min``) and, with ``approach``
        (ℓ_nom, b_x,nom, b) (:meth:`_approach`), that nominal length and DCM offset along the heading in its QP instead
        of the gait's, and the lateral aim's offset across it if one step reaches beyond b from the foothold so
        planned (the before/beyond choice keeps the gait's); with ``lateral_window`` (low, high) [m] its lateral
        component within that window too (the nearest width bound when they do not meet)."""
        params = self.params
        omega = self._omega
        a1, a2, a3 = params.alpha1, params.alpha2, params.alpha3
        l_min, l_max = params.l_min, params.l_max
        if length_min is not None:
            l_min, l_max = length_min, max(l_max, length_min)
        gamma_nom, g_hi = self._gamma_nom, self._gamma_hi
        w_nom, (bnx, bny), (w_lo, w_hi) = per_stance[stance]
        if lateral_window is not None:  # the committed swing foothold (swing_commit_time)
            low, high = max(w_lo, lateral_window[0]), min(w_hi, lateral_window[1])
            if low > high:
                low = high = w_hi if lateral_window[0] > w_hi else w_lo
            w_lo, w_hi = low, high
        l_gait, bnx_gait = l_nom, bnx
        far = None  # the obstacle's far bound of the even approach [m], heading frame
        if approach is not None:
            l_nom, bnx, far = approach
        if elapsed > 0.0:
            decay = math.exp(-omega * elapsed)
            g_lo = math.exp(omega * max(params.t_min, elapsed))
        else:
            decay = 1.0
            g_lo = self._gamma_lo0
        if duration_min > 0.0:
            g_lo = max(g_lo, math.exp(omega * duration_min))
        ax, ay = (zx - p0x) * decay, (zy - p0y) * decay
        c, s = math.cos(yaw), math.sin(yaw)

        def step_qp(lateral_offset):  # (p_x, p_y, γ, b_x, b_y, bits) aiming at that DCM offset across the heading
            if rotate:  # solve in the heading frame of the stance, rotate the step and the offset back
                dx, dy, gamma, hx, hy, bits = solve_exact_scalars(
                    0.0, 0.0, c * ax + s * ay, c * ay - s * ax, a1, a2, a3, l_nom, w_nom, gamma_nom, bnx,
                    lateral_offset, l_min, l_max, w_lo, w_hi, g_lo, g_hi,
                )
                return p0x + (c * dx - s * dy), p0y + (s * dx + c * dy), gamma, c * hx - s * hy, s * hx + c * hy, bits
            return solve_exact_scalars(p0x, p0y, ax, ay, a1, a2, a3, l_nom, w_nom, gamma_nom, bnx, lateral_offset,
                                       l_min, l_max, w_lo, w_hi, g_lo, g_hi)

        step = None
        if far is not None and constraints.geometry.lateral_aim_fraction != 1.0:
            # a possible last step before the obstacle (one step from its foothold reaches beyond it, and the sequencer
            # crosses whenever the DCM lets it) aims at the lateral aim's offset, judged from the foothold its QP
            # plans (the H1's closed loop crossed a step early and from short of the bound, from the walking offset,
            # and its steps planned short of the bound were followed by one more)
            aimed = step_qp(bny * constraints.geometry.lateral_aim_fraction)
            if far - (c * (aimed[0] - p0x) + s * (aimed[1] - p0y)) <= constraints.geometry.step_length_max:
                step = aimed
        px, py, gamma, bx, by, bits = step_qp(bny) if step is None else step
        cop = 0.0  # the centre of pressure behind the stance foothold the step was planned with [m]
        if constraints is not None:  # footholds outside the obstacles (sequencer.footholds)
            hax, hay = c * ax + s * ay, c * ay - s * ax  # the DCM growth in the heading frame

            def solve(bounds, aim, lateral=1.0, cop=0.0):
                low = math.exp(omega * max(bounds[4], elapsed, duration_min))
                high = max(math.exp(omega * bounds[5]), low)
                bx_nom = bnx if aim is None else aim
                by_nom = bny * lateral
                # the centre of pressure cop [m] behind the foothold: the step QP of ℓ + cop from the offset to it
                dx, dy, g, hx, hy, b = solve_exact_scalars(
                    0.0, 0.0, hax + cop * decay, hay, a1, a2, a3, l_nom + cop, w_nom, gamma_nom, bx_nom, by_nom,
                    bounds[0] + cop, bounds[1] + cop, bounds[2], bounds[3], low, high)
                if cop:  # back to the step from the foothold, on its bound exactly when the bound is active
                    dx = min(max(dx - cop, bounds[0]), bounds[1])
                cost = a1 * ((dx - l_nom) ** 2 + (dy - w_nom) ** 2) + a2 * (g - gamma_nom) ** 2 \
                    + a3 * ((hx - bx_nom) ** 2 + (hy - by_nom) ** 2)
                return StepCandidate(dx, dy, g, hx, hy, b, cost, math.log(g) / omega, cop)

            rx, ry = px - p0x, py - p0y
            nominal = StepCandidate(c * rx + s * ry, c * ry - s * rx, gamma, c * bx + s * by, c * by - s * bx,
                                    bits, 0.0, math.log(gamma) / omega)
            chosen, changed = constraints.choose(
                (p0x, p0y), yaw, (l_min, l_max, w_lo, w_hi, max(params.t_min, duration_min), params.t_max), nominal,
                solve, lift, l_gait, bnx_gait, cross)
            if changed:
                px, py = p0x + (c * chosen.dx - s * chosen.dy), p0y + (s * chosen.dx + c * chosen.dy)
                bx, by = c * chosen.hx - s * chosen.hy, s * chosen.hx + c * chosen.hy
                gamma, bits, cop = chosen.gamma, chosen.bits, chosen.cop
        return px, py, gamma, bx, by, bits, cop

    def _plan_backend(self, t, stance, p0, dcm, stance_start, elapsed, yaw, yaw_rate, gait,
                      constraints: FootholdConstraints | None = None, liftoff=None,
                      first_crossing: bool | None = None) -> list[PlannedStep]:
        t_end = t + self.params.horizon
        rotate = yaw != 0.0 or yaw_rate != 0.0
        steps = []
        first_stance = p0
        for _ in range(self._max_steps):
            c, s = math.cos(yaw), math.sin(yaw)
            to_heading = np.array(((c, s), (-s, c)))
            if rotate:  # the QP in the stance's heading frame: p0 and the DCM rotated by -yaw
                problem = self.problem(stance, to_heading @ p0, to_heading @ dcm, elapsed, gait)
                solution = self.backend.solve(problem)
                position = to_heading.T @ solution.step_position
                offset = to_heading.T @ solution.dcm_offset
            else:
                problem = self.problem(stance, p0, dcm, elapsed, gait)
                solution = self.backend.solve(problem)
                position = solution.step_position.copy()
                offset = solution.dcm_offset.copy()
            duration, active = solution.duration, tuple(solution.active_names)
            if constraints is not None:  # footholds outside the obstacles (sequencer.footholds)
                chosen, changed = constraints.choose(
                    p0, yaw, (*problem.length_bounds, *problem.width_bounds, *problem.time_bounds),
                    self._candidate(problem, solution, to_heading, rotate),
                    lambda bounds, aim, lateral=1.0, cop=0.0, problem=problem, to_heading=to_heading:
                    self._solve_bounded(problem, bounds, aim, to_heading, rotate, lateral),  # cop: exact backend only
                    liftoff if not steps else (steps[-2].position if len(steps) >= 2 else first_stance),
                    gait.step_length, float(problem.b_nominal[0]), None if steps else first_crossing)
                if changed:
                    position = p0 + to_heading.T @ np.array((chosen.dx, chosen.dy))
                    offset = to_heading.T @ np.array((chosen.hx, chosen.hy))
                    duration = chosen.duration
                    active = _ACTIVE_NAMES[chosen.bits]
            touchdown = stance_start + duration
            yaw = yaw + yaw_rate * duration
            landing = other_foot(stance)
            dcm = position + offset
            steps.append(PlannedStep(landing, position, touchdown, offset, dcm.copy(), stance_start, active, yaw))
            if touchdown >= t_end:
                break
            stance, p0, stance_start, elapsed = landing, position, touchdown, 0.0
        return steps

    def _solve_bounded(self, problem: StepProblem, bounds, aim, to_heading: np.ndarray, rotate: bool,
                       lateral: float = 1.0) -> StepCandidate:
        """The backend's solution of ``problem`` with the step bounds (ℓ_min, ℓ_max, w_min, w_max, T_min, T_max) and,
        unless ``aim`` is None, the nominal DCM offset b_x = aim [m] (heading frame); the lateral one scaled by
        ``lateral``."""
        bounded = dataclasses.replace(problem, length_bounds=(bounds[0], bounds[1]), width_bounds=(bounds[2], bounds[3]),
                                      time_bounds=(bounds[4], bounds[5]))
        if aim is not None or lateral != 1.0:
            bx = problem.b_nominal[0] if aim is None else aim
            bounded = dataclasses.replace(bounded, b_nominal=np.array((bx, problem.b_nominal[1] * lateral)))
        return self._candidate(bounded, self.backend.solve(bounded), to_heading, rotate)

    @staticmethod
    def _candidate(problem: StepProblem, solution, to_heading: np.ndarray, rotate: bool) -> StepCandidate:
        """A backend's solution as a heading-frame :class:`StepCandidate` (the QP is in that frame when ``rotate``)."""
        step = solution.step_position - problem.p0
        offset = solution.dcm_offset
        if not rotate:
            step, offset = to_heading @ step, to_heading @ offset
        bits = int(sum(1 << i for i, on in enumerate(solution.active) if on))
        return StepCandidate(float(step[0]), float(step[1]), float(solution.x[2]), float(offset[0]), float(offset[1]),
                             bits, float(solution.objective), float(solution.duration))

    @staticmethod
    def _mark_crossings(steps: list[PlannedStep], p0, liftoff, constraints: FootholdConstraints) -> list[PlannedStep]:
        """Each step with the :class:`Crossing` of its swing (lift-off: ``liftoff`` for the first step, the
        current stance for the second, the foothold two steps back after that; the sole's heading: the
        foothold's yaw)."""
        marked = []
        for k, step in enumerate(steps):
            start = liftoff if k == 0 else (p0 if k == 1 else steps[k - 2].position)
            crossing = crossing_of(constraints.obstacles, start, step.position, step.yaw, constraints.geometry)
            marked.append(step if crossing is None else dataclasses.replace(step, crossing=crossing))
        return marked
