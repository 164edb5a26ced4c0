"""Per-node contact schedule: the data a footstep plan hands to the whole-body OCP.

A :class:`ContactSchedule` samples a footstep plan on the OCP's time grid. Node ``k`` is at
time ``t0 + k * dt``; there are ``n_nodes + 1`` rows (running nodes and the terminal node).
Feet are indexed in the order of ``feet`` (the plan's ``feet``, ``("left", "right")`` for the
DCM planner); the robot description maps these names to its frames. Positions are world (x, y)
[m], yaws world yaws about z [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError

SCHEDULE_ROUNDINGS = ("next", "nearest")


@dataclass(frozen=True)
class ContactSchedule:
    """Which feet touch the ground at each OCP node, and where and how each swing ends.

    Attributes:
        t0: time of node 0 [s] (same clock as the plan).
        dt: node spacing [s], > 0.
        feet: foot names, e.g. ``("left", "right")``; column j of every array is ``feet[j]``.
        in_contact: shape (n_nodes + 1, n_feet), bool. True where the foot is in contact
            (single and double support).
        swing_phase: shape (n_nodes + 1, n_feet), fraction of the current swing elapsed at
            the node, in [0, 1]; NaN where the foot is in contact.
        swing_duration: shape (n_nodes + 1, n_feet), total duration of the current swing (lift-off
            to touchdown) [s]; NaN where the foot is in contact.
        touchdown_position: shape (n_nodes + 1, n_feet, 2), world-frame (x, y) of the planned
            foothold ending the current swing [m]; NaN where the foot is in contact.
        touchdown_yaw: shape (n_nodes + 1, n_feet), world yaw of that foothold [rad]; NaN where
            the foot is in contact. Omitted (None): 0 for every swinging foot (a plan without
            heading), NaN in contact.
        contact_yaw: shape (n_nodes + 1, n_feet), world yaw of the foothold a foot in contact
            stands on [rad] (the stance yaw of the plan, or the yaw of the foot's last planned
            touchdown); NaN where the foot swings, and where it landed before the plan was made
            (the trailing foot of a double support at the start of the plan). Omitted (None): 0
            in contact, NaN in swing.
        node_spacing: shape (n_nodes,), the spacing of each running node [s] (node k spans
            [times[k], times[k + 1]]); None: ``dt`` everywhere. Set by :func:`timed_contact_schedule`,
            where every contact phase keeps its number of nodes and the spacing follows the phase's
            duration.
        touchdown_times: shape (m,), the touchdown times inside the horizon that time the phases
            [s] (the continuous parameters of a timed schedule); None for a fixed-spacing one.
        node_spacing_jacobian: shape (n_nodes, m), ∂ node_spacing / ∂ touchdown_times [1].
        swing_phase_jacobian: shape (n_nodes + 1, n_feet, m), ∂ swing_phase / ∂ touchdown_times
            [1/s]; 0 where the foot is in contact.
        swing_phase_next_jacobian: shape (n_nodes + 1, n_feet), ∂ swing_phase / ∂ the touchdown
            ending the swing still running at the horizon's end (after it) [1/s].
    """

    t0: float
    dt: float
    feet: tuple[str, ...]
    in_contact: np.ndarray
    swing_phase: np.ndarray
    swing_duration: np.ndarray
    touchdown_position: np.ndarray
    touchdown_yaw: np.ndarray | None = None
    contact_yaw: np.ndarray | None = None
    node_spacing: np.ndarray | None = None
    touchdown_times: np.ndarray | None = None
    node_spacing_jacobian: np.ndarray | None = None
    swing_phase_jacobian: np.ndarray | None = None
    swing_phase_next_jacobian: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ParameterError(f"dt={self.dt} s must be a finite positive number")
        n_feet = len(self.feet)
        rows = self.in_contact.shape[0]
        if self.touchdown_yaw is None:
            object.__setattr__(self, "touchdown_yaw", np.where(np.asarray(self.in_contact, dtype=bool), np.nan, 0.0))
        if self.contact_yaw is None:
            object.__setattr__(self, "contact_yaw", np.where(np.asarray(self.in_contact, dtype=bool), 0.0, np.nan))
        expected = {
            "in_contact": (rows, n_feet),
            "swing_phase": (rows, n_feet),
            "swing_duration": (rows, n_feet),
            "touchdown_position": (rows, n_feet, 2),
            "touchdown_yaw": (rows, n_feet),
            "contact_yaw": (rows, n_feet),
        }
        for name, shape in expected.items():
            if getattr(self, name).shape != shape:
                raise ParameterError(f"{name} has shape {getattr(self, name).shape}, expected {shape}")

    @property
    def n_nodes(self) -> int:
        """Number of running nodes (the schedule has ``n_nodes + 1`` rows)."""
        return self.in_contact.shape[0] - 1

    @property
    def times(self) -> np.ndarray:
        """Node times [s], shape (n_nodes + 1,)."""
        if self.node_spacing is None:
            return self.t0 + self.dt * np.arange(self.n_nodes + 1)
        return self.t0 + np.concatenate([[0.0], np.cumsum(self.node_spacing)])


def plan_covers_grid(plan, t0: float, dt: float, n_nodes: int) -> bool:
    """Whether ``plan`` holds a touchdown after the grid's end t0 + n_nodes dt [s], as
    :func:`contact_schedule` needs (the last interval must end beyond the last node)."""
    touchdowns = plan.touchdown_times
    return len(touchdowns) > 0 and t0 + dt * n_nodes < touchdowns[-1]


def contact_schedule(plan, t0: float, dt: float, n_nodes: int, rounding: str = "next") -> ContactSchedule:
    """Sample a :class:`sequencer.horizon.FootstepPlan` on the OCP grid ``t0 + k dt``, k = 0..n_nodes.

    The plan is a sequence of touchdowns, one foot each (``plan.steps[i].foot`` lands at
    ``plan.steps[i].touchdown_time``). The foot landing at touchdown i lifts off
    ``plan.double_support`` seconds after the previous touchdown (after ``plan.t_stance_start``
    for the first one; a step with its own ``double_support``, a settled step of a quasi-static
    crossing, that long after) and swings until its touchdown; every other foot is in contact. Nodes before
    ``plan.t_stance_start`` (a plan for a stance that has not begun: a start from standing, see
    :meth:`sequencer.dcm_planner.DcmFootstepPlanner.plan`) have every foot in contact. With
    ``double_support = 0`` (point feet) exactly one foot of a biped is in stance between two
    touchdowns, and at a node exactly on a touchdown time the landing foot is in contact and the
    other foot starts its swing (phase 0). The swing phase and duration run over the swing itself
    (lift-off to touchdown), shortened by the double support.

    ``rounding`` says which node a touchdown (or a lift-off) between two nodes falls on:
    ``"next"`` (default) the first node at or after it, so the sampled contact starts up to one
    node (on average half a node) after the planned time; ``"nearest"`` the node nearest to it
    (half a node earlier or later at most, no bias on average). The closed loop uses "nearest":
    with "next" Bolt's feet landed ~4 ms after the planned touchdowns, when the DCM runs at
    ~0.9 m/s relative to the foot, and the sequencer answered the offset with longer steps
    (docs/closed_loop.md).

    Args:
        plan: FootstepPlan; its ``feet`` name the columns, its ``double_support`` [s] the time both
            feet stay on the ground after each touchdown.
        t0: time of node 0 [s] (before ``plan.t_stance_start``: double support until then).
        dt: node spacing [s], > 0.
        n_nodes: number of running nodes, >= 1; the grid must end before the last planned
            touchdown (the swing in progress there would have no planned end).
        rounding: ``"next"`` or ``"nearest"`` (see above).

    Returns:
        ContactSchedule with ``feet == plan.feet``; ``touchdown_yaw`` and ``contact_yaw`` from the
        plan's ``stance_yaw`` and the steps' ``yaw``.
    """
    t0 = float(t0)
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0):
        raise ParameterError(f"dt={dt} s must be a finite positive number")
    if isinstance(n_nodes, bool) or int(n_nodes) != n_nodes or n_nodes < 1:
        raise ParameterError(f"n_nodes={n_nodes!r} must be an integer >= 1")
    n_nodes = int(n_nodes)
    if rounding not in SCHEDULE_ROUNDINGS:
        raise ParameterError(f"rounding={rounding!r} must be one of {SCHEDULE_ROUNDINGS}")
    if not np.isfinite(t0):
        raise ParameterError(f"t0={t0} s must be finite")
    feet = tuple(plan.feet)
    column = {foot: j for j, foot in enumerate(feet)}
    try:
        stance_column = column[plan.stance_foot]
        landing_columns = [column[step.foot] for step in plan.steps]
    except KeyError:
        unknown = sorted({plan.stance_foot, *(step.foot for step in plan.steps)} - set(column))
        raise ParameterError(f"the plan's stance and steps use feet {unknown} that are not in its feet {feet}") from None
    times = t0 + dt * np.arange(n_nodes + 1)
    touchdowns = plan.touchdown_times
    if not plan_covers_grid(plan, t0, dt, n_nodes):
        raise ParameterError(
            f"the grid ends at t0 + n_nodes*dt = {times[-1]:.4g} s, at or after the plan's last touchdown "
            f"{touchdowns[-1]:.4g} s: plan with a longer horizon or use fewer nodes"
        )
    # index of the stance interval of each node: 0 = current stance, k = after the k-th touchdown
    shift = 0.5 * dt if rounding == "nearest" else 0.0
    interval = np.searchsorted(touchdowns, times + shift, side="right")
    rows = np.arange(n_nodes + 1)
    node_interval, node_times = interval, times
    start = np.concatenate([[plan.t_stance_start], touchdowns])[interval]  # the previous touchdown
    end = touchdowns[interval]
    double_support = _double_supports(plan)[interval]
    start = start + double_support  # lift-off of the landing foot
    short = (double_support > 0.0) & (end <= start)
    if np.any(short):
        late = int(np.argmax(short))
        raise ParameterError(
            f"double_support={float(double_support[late])} s leaves no swing before the touchdown at "
            f"{float(end[late]):.4g} s"
        )
    swinging = times + shift >= start  # (all nodes for point feet, once the stance has begun)
    rows, interval, start, end = rows[swinging], interval[swinging], start[swinging], end[swinging]
    node_times = times[swinging]
    swing = np.array(landing_columns)[interval]
    in_contact = np.ones((n_nodes + 1, len(feet)), dtype=bool)
    in_contact[rows, swing] = False
    swing_phase = np.full((n_nodes + 1, len(feet)), np.nan)
    swing_phase[rows, swing] = np.clip((node_times - start) / (end - start), 0.0, 1.0)
    swing_duration = np.full((n_nodes + 1, len(feet)), np.nan)
    swing_duration[rows, swing] = end - start
    touchdown_position = np.full((n_nodes + 1, len(feet), 2), np.nan)
    touchdown_position[rows, swing] = plan.positions[interval]
    touchdown_yaw = np.full((n_nodes + 1, len(feet)), np.nan)
    touchdown_yaw[rows, swing] = plan.yaws[interval]
    # yaw of the foothold each foot stands on in each stance interval (NaN: it landed before the plan)
    standing = [np.nan] * len(feet)
    standing[stance_column] = plan.stance_yaw
    standing_yaw = [standing]
    for step, j in zip(plan.steps[: int(node_interval[-1])], landing_columns):
        standing = standing.copy()
        standing[j] = step.yaw
        standing_yaw.append(standing)
    contact_yaw = np.array(standing_yaw)[node_interval]
    contact_yaw[rows, swing] = np.nan
    return ContactSchedule(
        t0=t0, dt=dt, feet=feet, in_contact=in_contact, swing_phase=swing_phase,
        swing_duration=swing_duration, touchdown_position=touchdown_position, touchdown_yaw=touchdown_yaw,
        contact_yaw=contact_yaw,
    )


def _double_supports(plan) -> np.ndarray:
    """Double support before each step's swing [s], shape (K,): the step's own ``double_support``, else the
    plan's."""
    default = float(plan.double_support)
    own = [getattr(step, "double_support", None) for step in plan.steps]
    return np.array([default if value is None else float(value) for value in own])


def timed_contact_schedule(plan, t0: float, dt: float, n_nodes: int, touchdown_times=None,
                           next_touchdown: float | None = None) -> ContactSchedule:
    """A schedule whose contact phases are timed continuously by the touchdown times in the horizon.

    The contact events are the touchdowns τ_i of the plan and the lift-offs: the foot landing at
    touchdown i + 1 lifts off at ℓ_i = τ_i + d after touchdown i (ℓ_0 = ``plan.t_stance_start`` + d,
    a fixed time), d = ``plan.double_support`` [s]. The double-support duration d is **held fixed**:
    the lift-off moves with the touchdown before it, so a derivative in τ_i is taken at constant
    double support (the swing after it shortens by as much as τ_i is late, the double-support
    phase only moves). With d = 0 a lift-off is its touchdown. The events inside the horizon
    (t0, t_end), t_end = t0 + n_nodes dt (the horizon's end stays put), b_1 < … < b_M split it into
    M + 1 phases (b_0 = t0, b_{M+1} = t_end): single support, the double support after each
    touchdown, standing before ℓ_0. Phase p keeps the n_p nodes it has on the nominal grid sampled
    with ``rounding="nearest"`` (:func:`contact_schedule`, which also gives the contact sets,
    footholds and yaws) whatever the times; its nodes get the spacing h_p = (b_{p+1} − b_p) / n_p and
    the times b_p + j h_p, j = 0 … n_p − 1. Every event is τ_i, τ_i + d or fixed, so ∂b/∂τ_i is 1
    or 0 and ∂h_p/∂τ = (∂b_{p+1}/∂τ − ∂b_p/∂τ) / n_p (0 for a double-support phase: d / n_p).

    The swing phase at a node is s = (t − ℓ) / (T − ℓ) of its time, ℓ the swing's lift-off and T its
    touchdown: j / n_p inside the horizon (it does not depend on the times), and a smooth function
    of τ_1 for the swing in progress at t0 (lift-off before t0), and of ℓ_m = τ_m + d and the plan's
    next touchdown (held fixed, ``next_touchdown``) for the swing still running at t_end. When every
    event's time minus t0 is a multiple of dt the schedule equals ``contact_schedule(plan, t0, dt,
    n_nodes, "nearest")`` with ``node_spacing`` = dt.

    Args:
        plan: FootstepPlan (any ``double_support`` >= 0 [s]).
        t0, dt, n_nodes: the nominal grid (as :func:`contact_schedule`).
        touchdown_times: shape (m,), the times [s] of the plan's m touchdowns before t_end; with the
            lift-offs they imply, the events inside the horizon must stay strictly increasing inside
            (t0, t_end) and those outside it outside, on the same side; None: the plan's.
        next_touchdown: the time [s] of the touchdown ending the swing in progress at t_end (after
            t_end); None: the plan's.

    Returns:
        ContactSchedule with ``node_spacing``, ``touchdown_times`` and their Jacobians.

    Raises:
        ParameterError: an event within half a node of t0, t_end or another event (its phase would
            have no node), or ``touchdown_times`` of the wrong shape, not finite, unordered or
            moving an event into or out of the horizon.
    """
    if any(getattr(step, "double_support", None) is not None for step in plan.steps):
        raise ParameterError("timed_contact_schedule takes one double support for all steps; the plan has steps "
                             "with their own (a quasi-static crossing): use contact_schedule")
    nominal = contact_schedule(plan, t0, dt, n_nodes, rounding="nearest")
    t0, dt, n_nodes = float(t0), float(dt), int(n_nodes)
    t_end = t0 + n_nodes * dt
    d = float(plan.double_support)
    planned = plan.touchdown_times
    m = int(np.searchsorted(planned, t_end, side="left"))  # touchdowns before t_end (contact_schedule: not all)
    grid = t0 + dt * np.arange(n_nodes + 1)
    if touchdown_times is None:
        tau = planned[:m].copy()
    else:
        tau = np.asarray(touchdown_times, dtype=float)
        if tau.shape != (m,):
            raise ParameterError(f"touchdown_times has shape {tau.shape}, expected ({m},): the plan has {m} touchdowns "
                                 f"in the horizon ({t0}, {t_end:.4g}) s")
        if not np.all(np.isfinite(tau)):
            raise ParameterError(f"touchdown_times={tau.tolist()} s must be finite")
    upper = planned[m] if next_touchdown is None else float(next_touchdown)
    if not (math.isfinite(upper) and upper > t_end):
        raise ParameterError(f"next_touchdown={next_touchdown} s must be finite and after the horizon's end {t_end:.6g} s")
    # events in time order: (nominal time, time at tau, the column of tau it moves with or -1); the lift-off
    # ℓ_i after touchdown i (lift_offs[i]: its index in events) and touchdown i + 1 (touchdowns[i])
    events, lift_offs, touchdowns = [], [], []
    for i in range(m + 1):
        if i == 0 or d > 0.0:
            lift = (float(plan.t_stance_start) + d, -1) if i == 0 else (planned[i - 1] + d, i - 1)
            events.append((lift[0], lift[0] if i == 0 else tau[i - 1] + d, lift[1]))
        lift_offs.append(len(events) - 1)
        if i < m:
            touchdowns.append(len(events))
            events.append((planned[i], tau[i], i))
    nominal_times = np.array([e[0] for e in events])
    values = np.array([e[1] for e in events])
    inside = (nominal_times > t0) & (nominal_times < t_end)
    after = nominal_times >= t_end
    near_end = after & (np.searchsorted(grid + 0.5 * dt, nominal_times, side="left") <= n_nodes)
    if np.any(near_end) or planned[m] <= t_end + 0.5 * dt:
        late = float(nominal_times[near_end][0]) if np.any(near_end) else float(planned[m])
        raise ParameterError(f"the plan's contact event at {late:.4g} s is within half a node after the horizon's end "
                             f"t_end={t_end:.6g} s (the terminal node would be sampled past it): change n_nodes or dt")
    node_of = np.searchsorted(grid + 0.5 * dt, nominal_times[inside], side="left")  # the "nearest" rule
    boundaries = np.concatenate([[0], node_of, [n_nodes]])
    if np.any(np.diff(boundaries) < 1):
        raise ParameterError(f"the plan's contact events {np.round(nominal_times[inside], 4).tolist()} s put a contact "
                             f"phase of no node on the grid t0={t0} s, dt={dt} s, n_nodes={n_nodes} (an event within "
                             "half a node of t0, t_end or another event): change n_nodes or dt")
    edges = np.concatenate([[t0], values[inside], [t_end]])  # b_0 … b_{M+1}
    if not np.all(np.diff(edges) > 0):
        raise ParameterError(f"touchdown_times={tau.tolist()} s must be strictly increasing and inside the horizon "
                             f"({t0}, {t_end:.6g}) s, with the lift-offs {d} s after them in between")
    crossed = (after & (values < t_end)) | (~inside & ~after & (values > t0))
    if np.any(crossed):
        raise ParameterError(f"touchdown_times={tau.tolist()} s move the contact event at "
                             f"{float(values[crossed][0]):.6g} s across t0 or t_end (planned at "
                             f"{float(nominal_times[crossed][0]):.6g} s): the phases would change")
    edge_columns = np.concatenate([[-1], [e[2] for e, on in zip(events, inside) if on], [-1]]).astype(int)
    counts = np.diff(boundaries)
    n_feet = len(nominal.feet)
    spacing = np.empty(n_nodes)
    spacing_jacobian = np.zeros((n_nodes, m))
    times = np.empty(n_nodes + 1)
    times_jacobian = np.zeros((n_nodes + 1, m))  # ∂t_k/∂τ
    for p in range(counts.size):
        nodes = np.arange(boundaries[p], boundaries[p + 1])
        spacing[nodes] = (edges[p + 1] - edges[p]) / counts[p]
        fraction = (nodes - boundaries[p]) / counts[p]
        times[nodes] = edges[p] + fraction * (edges[p + 1] - edges[p])
        if edge_columns[p] >= 0:
            spacing_jacobian[nodes, edge_columns[p]] -= 1.0 / counts[p]
            times_jacobian[nodes, edge_columns[p]] += 1.0 - fraction
        if edge_columns[p + 1] >= 0:
            spacing_jacobian[nodes, edge_columns[p + 1]] += 1.0 / counts[p]
            times_jacobian[nodes, edge_columns[p + 1]] += fraction
    times[n_nodes] = t_end
    # the swing at node k runs in the stance interval I_k (touchdowns at or before the node, "nearest"):
    # lift-off ℓ_{I_k}, touchdown τ_{I_k + 1} (the plan's next touchdown for I_k = m), as (value, column or -1)
    interval = np.searchsorted(np.searchsorted(grid + 0.5 * dt, planned[:m], side="left"), np.arange(n_nodes + 1),
                               side="right")
    in_contact = nominal.in_contact
    swing_phase = np.where(in_contact, np.nan, 0.0)
    swing_duration = np.where(in_contact, np.nan, 0.0)
    phase_jacobian = np.zeros((n_nodes + 1, n_feet, m))
    next_jacobian = np.zeros((n_nodes + 1, n_feet))
    for k in range(n_nodes + 1):
        i = int(interval[k])
        lift = events[lift_offs[i]][1:]
        land = events[touchdowns[i]][1:] if i < m else (upper, -1)
        duration = land[0] - lift[0]
        for j in np.flatnonzero(~in_contact[k]):
            s = (times[k] - lift[0]) / duration
            swing_phase[k, j] = s
            swing_duration[k, j] = duration
            ds = times_jacobian[k] / duration
            if lift[1] >= 0:
                ds[lift[1]] += (s - 1.0) / duration
            if land[1] >= 0:
                ds[land[1]] -= s / duration
            else:
                next_jacobian[k, j] = -s / duration
            phase_jacobian[k, j] = ds
    return ContactSchedule(
        t0=t0, dt=dt, feet=nominal.feet, in_contact=in_contact, swing_phase=swing_phase,
        swing_duration=swing_duration, touchdown_position=nominal.touchdown_position,
        touchdown_yaw=nominal.touchdown_yaw, contact_yaw=nominal.contact_yaw, node_spacing=spacing,
        touchdown_times=tau, node_spacing_jacobian=spacing_jacobian, swing_phase_jacobian=phase_jacobian,
        swing_phase_next_jacobian=next_jacobian,
    )
