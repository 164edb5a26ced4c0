"""The footstep-planner interface: what a planner takes and what it returns.

A footstep planner decides where and when each foot lands. The walking controller calls it at
every replan with the current stance, the measured reduced state it needs and the velocity
command, samples the returned :class:`~sequencer.horizon.FootstepPlan` on the OCP grid
(:func:`sequencer.schedule.contact_schedule`) and takes its CoM reference from the plan
(:meth:`~sequencer.horizon.FootstepPlan.com_reference`, model-neutral). The DCM step QP (:mod:`sequencer.dcm_planner`)
implements it; a second planner (the ALIP step-to-step NMPC) is one more module implementing
:class:`FootstepPlanner`, and the controller does not know which one it runs.

Frames: world frame, z up; the *heading frame* of a stance is the world frame rotated about z by
the stance foot's yaw (x forward along the heading, y to the left). Velocity commands are given
in the heading frame of the robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from wbmpc.errors import ParameterError


def _finite_vector(name: str, value, size: int) -> np.ndarray:
    """A read-only float copy of ``value``, shape (size,); built at every replan, so checked on floats."""
    try:
        array = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be {size} finite numbers") from None
    if array.shape != (size,) or not all(map(math.isfinite, array.tolist())):
        raise ParameterError(f"{name}={value!r} must be {size} finite numbers")
    array.setflags(write=False)
    return array


def _finite_scalar(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ParameterError(f"{name}={value!r} must be a real number")
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"{name}={value!r} must be finite")
    return value


def rotate_xy(vector_xy, yaw: float) -> np.ndarray:
    """``vector_xy`` (2,) rotated by ``yaw`` [rad] about z: heading frame -> world frame for a
    heading of yaw (``-yaw``: world -> heading)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array((c * vector_xy[0] - s * vector_xy[1], s * vector_xy[0] + c * vector_xy[1]))


@dataclass(frozen=True)
class VelocityCommand:
    """Desired walking velocity, in the robot's heading frame.

    Attributes:
        v_x: forward velocity [m/s].
        v_y: lateral velocity [m/s], positive to the left.
        yaw_rate: turning rate about the world z axis [rad/s], positive counter-clockwise.
    """

    v_x: float = 0.0
    v_y: float = 0.0
    yaw_rate: float = 0.0

    def __post_init__(self) -> None:
        for name in ("v_x", "v_y", "yaw_rate"):
            object.__setattr__(self, name, _finite_scalar(name, getattr(self, name)))

    @classmethod
    def from_tuple(cls, value) -> "VelocityCommand":
        """From (v_x,), (v_x, v_y) or (v_x, v_y, yaw_rate) [m/s, m/s, rad/s]; a VelocityCommand is kept."""
        if isinstance(value, VelocityCommand):
            return value
        items = tuple(np.atleast_1d(np.asarray(value, dtype=float)).tolist()) if not isinstance(value, str) else ()
        if not 1 <= len(items) <= 3:
            raise ParameterError(
                f"velocity_command={value!r} must be (v_x, v_y, yaw_rate) [m/s, m/s, rad/s] (1 to 3 numbers)"
            )
        return cls(*items)

    def as_tuple(self) -> tuple[float, float, float]:
        """(v_x [m/s], v_y [m/s], yaw_rate [rad/s])."""
        return (self.v_x, self.v_y, self.yaw_rate)


@dataclass(frozen=True)
class StanceState:
    """The foot on the ground when the plan is made.

    Attributes:
        foot: name of the stance foot (one of the planner's ``feet``).
        position: world (x, y) of the stance foothold [m], shape (2,).
        yaw: world yaw of the stance foot's heading frame [rad].
        t_start: time at which this stance began [s].
        swing_liftoff: world (x, y) [m] where the swinging foot lifted off (its last foothold), or None
            (unknown): a planner given obstacles tells from it whether the swing in progress passes over one.
    """

    foot: str
    position: np.ndarray
    yaw: float
    t_start: float
    swing_liftoff: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _finite_vector("stance position", self.position, 2))
        if self.swing_liftoff is not None:
            object.__setattr__(self, "swing_liftoff", _finite_vector("swing_liftoff", self.swing_liftoff, 2))
        object.__setattr__(self, "yaw", _finite_scalar("stance yaw", self.yaw))
        object.__setattr__(self, "t_start", _finite_scalar("t_start", self.t_start))


@dataclass(frozen=True)
class ReducedState:
    """The measured reduced (centroidal) state a planner may use, world frame.

    Attributes:
        com: centre of mass [m], shape (3,).
        com_velocity: centre-of-mass velocity [m/s], shape (3,).
        dcm: divergent component of motion c_xy + ċ_xy / ω [m], shape (2,), with the run's ω
            (the planner's :attr:`FootstepPlanner.omega`).
        angular_momentum: centroidal angular momentum about the stance contact point
            [kg·m²/s], shape (3,), or None when the caller does not measure it (the ALIP
            planner needs it, the DCM planner does not).
    """

    com: np.ndarray
    com_velocity: np.ndarray
    dcm: np.ndarray
    angular_momentum: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "com", _finite_vector("com", self.com, 3))
        object.__setattr__(self, "com_velocity", _finite_vector("com_velocity", self.com_velocity, 3))
        object.__setattr__(self, "dcm", _finite_vector("dcm", self.dcm, 2))
        if self.angular_momentum is not None:
            object.__setattr__(self, "angular_momentum",
                               _finite_vector("angular_momentum", self.angular_momentum, 3))


def as_velocity_command(command) -> VelocityCommand:
    """``command`` as a :class:`VelocityCommand` (one, or a (v_x, v_y, yaw_rate) tuple or list)."""
    if isinstance(command, VelocityCommand):
        return command
    if isinstance(command, (tuple, list)):
        return VelocityCommand.from_tuple(command)
    raise ParameterError(f"command must be a VelocityCommand or (v_x, v_y, yaw_rate), got {type(command).__name__}")


@runtime_checkable
class FootstepPlanner(Protocol):
    """Plans the next footsteps from the measured reduced state and a velocity command.

    Attributes:
        feet: names of the feet the planner alternates, e.g. ``("left", "right")``.
        omega: natural frequency of the planner's pendulum model [1/s]; the controller uses the
            same ω for the DCM it measures (one ω per run).
        com_height: the planner model's CoM height above the ground [m] (the terminal CoM
            height reference of the whole-body OCP).
        double_support: duration of the double-support phase that follows each touchdown [s]
            (0 for point feet); the contact schedule keeps both feet on the ground for it.
        avoids_obstacles: (optional, False when absent) whether :meth:`plan` keeps the footholds off the
            ``obstacles`` it is given (else it raises ParameterError when given any); a controller that
            negotiates obstacles needs it.
    """

    feet: tuple[str, ...]
    omega: float
    com_height: float
    double_support: float

    def plan(self, t: float, stance: StanceState, measured: ReducedState,
             command: VelocityCommand, obstacles=()) -> "FootstepPlan":  # noqa: F821 (sequencer.horizon)
        """Footsteps from time ``t`` [s] until at least the planner's horizon.

        ``obstacles``: the :class:`sequencer.obstacles.Obstacle` s the footholds must avoid (world frame);
        empty: the plan without obstacles. A planner that cannot avoid them raises ParameterError when
        given some (never a silent ignore).

        Raises:
            ParameterError: bad input (names the argument and value).
            sequencer.step_qp.StepQPError (a ``wbmpc.errors.SolverError``): the planner's
                optimisation failed; a control loop keeps its last plan.
        """

    def check_command(self, command: VelocityCommand) -> None:
        """Raise ParameterError (naming the component, its value and the allowed range) when
        ``command`` cannot be planned with this planner's bounds; called before a run starts."""

    def command_range(self) -> dict[str, tuple[float, float]]:
        """``{"v_x": (min, max), "v_y": (min, max), "yaw_rate": (min, max)}`` [m/s, m/s, rad/s], heading
        frame: the commands :meth:`check_command` accepts (infinite where the planner has no bound).
        A controller clips a corrected command to it before :meth:`plan`."""
