"""Footholds outside obstacles: the per-step bounds of the step QP and the before/beyond choice.

The step QP (:mod:`sequencer.step_qp`) is a box-bounded QP in the step (ℓ, w) = p_T - p_0 written
in the stance's heading frame (x along the heading), and the duration T of the step. An obstacle
(:class:`sequencer.obstacles.Obstacle`) forbids a region of (ℓ, w): every foothold whose *sole
rectangle* (``sole_front`` ahead of the foot frame, ``sole_rear`` behind it, ``sole_half_width`` to
each side, along the step's heading) overlaps the footprint grown by ``obstacle_margin`` on every
side. In the heading frame that region is bounded by the box (:func:`forbidden_box`)::

    a < ℓ < b  and  c < w < d,   a = near - margin - approach - sole_front,  b = far + margin + sole_rear,
                                 c = right - margin - sole_half_width,  d = left + margin + sole_half_width

with near/far/right/left the extents, in the heading frame relative to p_0, of the grown footprint's
part that the sole can reach within the step's width bounds (exact for a box square to the heading, a
bounding box otherwise: conservative).

The allowed set (outside the box) is not convex: it is the union of four half-planes, each a box
bound of the QP. The choice is made per step, by the planner, not by the QP:

1. solve the step's QP with its nominal bounds; a foothold outside every box is kept as it is
   (so a plan whose footholds miss the obstacles is the plan without obstacles, bit for bit);
2. else, along the heading, the step goes *beyond* the obstacle (ℓ >= b, the far side seen from
   p_0; ℓ <= a walking backwards) when the obstacle lies in the direction of travel (the sign of the
   nominal step; stepping in place crosses nothing), one step can reach it and the DCM can carry that
   step (its offset at touchdown within ``obstacle_offset_tolerance`` of the one it aims at: the
   nominal one, or b_c below):
   b <= max(l_max, obstacle_step_length_max), the crossing step's own length bound, with the
   duration T in [max(t_min, obstacle_step_duration_min), ``SequencerParams.crossing_duration_max``] (a
   crossing swing lifts higher and takes longer, and its DCM needs longer to travel the long step; on a robot
   without ankle roll a shorter bound keeps the lateral DCM's growth exp(ω T) over the swing small);
   otherwise it stays *before* it (ℓ <= a: the last step
   before the obstacle, its toe ``obstacle_margin`` before the near edge at most). That last step
   aims at the DCM offset from which the crossing step reaches its own aim within its longest
   duration, and at least at the nominal offset (a point-foot LIPM cannot make a step four times
   the nominal one from the nominal offset within a walking step's duration: from 4.7 cm the H1's
   DCM needs 0.76 s to travel a 0.48 m crossing); a robot that cannot
   reach beyond from there steps in place before the obstacle (a safe stop);
3. stepping *beside* the obstacle (w <= c or w >= d, within the width bounds) is the other
   candidate; of the candidates that are feasible, the one of least QP cost is taken;
4. repeat while the new foothold lies in another obstacle's box (bounds only tighten, except the
   crossing step's longer length and duration), and give a step whose swing passes over an obstacle
   (the trailing foot's, which lands beyond with a nominal step) the crossing durations and, with
   ``obstacle_swing_length_max`` > 0, a foothold within that travel of its lift-off along the heading:
   ℓ <= ℓ_lift + s_max, ℓ_lift = (lift-off - p_0) · heading. A nominal step from the lead foot, which
   landed a crossing step ahead, asked the H1's trailing foot a 1.0 m swing.

**Two steps ahead.** With that travel bound the lead crossing step (length ℓ_c from the stance p_0,
the trailing foot's lift-off) knows the trailing step that follows it: ℓ_t = min(|l_nom|,
max(0, s_max - |ℓ_c|)) from the lead foothold, lasting T_c,min. The lead step therefore aims at the
DCM offset from which that step ends at the nominal offset b_nom, b_c = (ℓ_t + b_nom) exp(-ω T_c,min)
(eq. 1b; signs along the direction of travel), not at b_nom: aiming at b_nom, the DCM runs a nominal
offset ahead of the lead foot and the short trailing step cannot catch it. The DCM check of step 2
compares the crossing's offset with that aim; the last step before the obstacle aims at
max((ℓ_c + b_c) exp(-ω T_c,aim), b_nom), T_c,aim = T_c,max unless ``obstacle_aim_duration`` > 0.

**Crossing drift.** A crossing swing carries the swing leg (about 9 kg of the H1's 51 kg) 0.5-0.8 m
forward, and the whole-body DCM with it: in closed loop the H1's DCM reached 21 cm further than the
LIPM predicted at the lead touchdown. With ``obstacle_crossing_drift`` κ_c > 0 every swing over an
obstacle (the lead crossing, the trailing swing) is planned with ξ_T = p_0 + b_0 γ + κ_c d (d its travel
from lift-off along the heading, the sign of travel): its QP aims the LIPM's offset at b − κ_c d and the
candidate carries b = h + κ_c d (the DCM check compares that one), and the last step before the obstacle
aims at max((ℓ_c + b_c − κ_c d_c) exp(-ω T_c,aim), b_nom), d_c the crossing swing's travel from that
step's stance.

**The approach.** Greedy, the walk takes nominal steps until the next foothold is bounded by the
obstacle: the remainder before it is whatever is left (on the H1 a short step, then a DCM check that
added a step in place and overshot). With ``obstacle_approach_distance`` > 0 the sequencer (the
'exact' backend) plans the approach backwards from the crossing: once the last foothold's bound a
(:meth:`FootholdConstraints.approach`, along the heading from the stance) is within that distance, the
n = round(a / l_nom) >= 1 steps up to it each get the nominal length a / n, and their DCM offsets the
LIPM chain b_{k-1} = (a / n + b_k) / γ_nom ending at the last step's aim b_n
(:meth:`FootholdConstraints.last_step_aim`, eq. 1b of each step): the crossing begins at the offset it
needs after even steps, not after a leftover one.

**The crossing's centre of pressure.** The LIPM pivots on the foothold; a flat foot's centre of pressure can move
between its heel and its toe, and a whole-body controller moves it to carry a long step or to hold the body over
the stance foot (the H1 crossed the box from a DCM 6 cm ahead of its stance foot, which the point-foot LIPM says
cannot carry a 0.55 m crossing within 0.8 s: its planner kept adding steps in place before the box while the DCM
ran on; after the lead touchdown, with the DCM on the lead foot, the point-foot plan of the trailing swing let the
body fall back and the trailing foot came down on the box). With ``obstacle_crossing_cop`` δ > 0 every swing over
an obstacle (the lead crossing and the trailing swing) pivots on a point δ_c along the heading from its stance
foothold (δ_c > 0 behind it), chosen in [-δ, δ] (:data:`PIVOT_SAMPLES` values, the one of least QP objective, the
nearest the foothold among equals): eq. 1b from that pivot, ξ_T - p_T = (ξ_0 - p_0 + δ_c) γ - (ℓ + δ_c), is the step
QP of the step ℓ + δ_c from the initial offset (ξ_0 - p_0) + δ_c (its length bounds and nominal length shifted by
δ_c). The candidate keeps δ_c (:attr:`StepCandidate.cop`), the plan's CoM prediction pivots there
(``PlannedStep.cop_offset`` of the stance), and the last step before an obstacle aims at the offset from which the
crossing, pivoting on the heel side, reaches its aim, (ℓ_c + δ + b_c) exp(-ω T_c,aim) - δ (at least the nominal
offset).

**The crossing's momentum.** The lead crossing lands with the DCM ahead of its foothold by the nominal offset:
what the trailing swing needs for the body to carry on over the lead foot. A whole-body robot loses part of it at
the lead touchdown (the H1's DCM 5-10 cm behind where it was just before, measured with the lead step 0.6 m long) and
more over the trailing swing (the swing leg accelerated forwards moves the centre of pressure towards the toe), and
fell backwards with the trailing foot beyond the box, where it cannot step back. With ``obstacle_crossing_offset``
Δb > 0 the lead crossing aims at b_nom + Δb (its QP lengthens the crossing's duration, within its bound, for the
DCM to get there), and the last step before the obstacle at the offset from which it does; the DCM check ("cross,
unless the DCM cannot carry it") still compares with the crossing's aim without Δb.

**The landing room.** The lead crossing lands on the far side's bound b (the QP's nominal step is shorter), and
the trailing foot can then land no further back than the lead foot: the box, behind both, bounds it. A whole-body
robot whose DCM lags behind the lead foot (the H1's by 5-9 cm after the trailing swing, measured) then stands with
both feet at the bound, the DCM behind the soles and every next foothold pinned there: it fell back over the box.
With ``obstacle_landing_room`` r > 0 the lead crossing lands at least min(b + r, its length bound) beyond its
stance (forwards; backwards the mirror), and the last step before the obstacle aims at the offset the crossing of
that length needs: the trailing foot can land up to r behind the lead foot, under a lagging DCM.

**The far margin.** Both crossing feet land beyond the far side, the trailing one no further back than the lead
foot's bound; a whole-body robot whose DCM lags (the H1's 9 cm behind both soles at the trailing touchdown, seed 6)
stands there with the DCM behind its heels. ``far_margin_reduction`` grows the side further along the heading by
that much less than ``obstacle_margin`` (only less: the side moved back by the difference still bounds a turned
box's): the lead crossing that much shorter and both feet that much nearer the box, nearer the DCM. The side
facing the stance keeps its margin (the last step before the obstacle is the one a foot overshoots).

**The passed obstacle's centre of pressure.** Once the trailing foot is down beyond the obstacle the walk's next
foothold is bounded by the obstacle's far side behind it. A whole-body robot whose DCM lags behind its feet there (the
H1's 5-9 cm behind both sole frames at the trailing touchdown, with 13.75 cm of heel behind them) can carry the DCM
forwards on its heels; the point-foot plan cannot: it predicts the body falling back, asks for a step back, and every
foothold is pinned at the far bound (the H1 stepped in place and fell back over the box). With
``obstacle_passed_cop`` δ_p > 0 such a step (the option that keeps the foothold on the far side of a box whose middle
lies behind the stance) pivots within δ_p of its stance foothold, chosen by its QP as for a crossing (the heel side
carries the DCM forwards), and the trailing crossing swing within max(δ, δ_p); the plan's CoM prediction pivots there.
A step whose nominal foothold is free of the box plans as the walk does: the pivot ends once the DCM is ahead.

**The trailing swing's duration.** The trailing crossing swing (its stance foot, the lead foot, already beyond the
obstacle) has the crossing's duration bounds by default, though its foothold lies next to the lead foot: its DCM has
no long step to travel, only the swing foot has. On a robot without ankle roll the lateral DCM offset that swing lifts
off with grows by exp(ω T) until it lands, and the width bound stops the foothold from following it: on the H1 10 of
11 traced trailing steps of a 10 cm campaign lasted their 0.6 s bound (the QP asked for less), and two falls after
both feet were across began where the lead foot had landed wide and the trailing one lifted off 10 cm from the DCM
across the heading (up to x 6.7 over 0.6 s: beyond the 0.6 m width bound). With ``obstacle_trailing_duration_min`` > 0
the trailing swing's lower bound is that instead (:attr:`FootholdGeometry.trailing_duration`; with
``obstacle_trailing_height_max`` > 0 only over obstacles up to that high: a higher one's trailing swing lifts higher).
The lead crossing's aim b_c ("Two steps ahead") keeps the crossing's bound for the trailing step. Measured on the H1
(docs/ocp.md "The trailing swing's duration"): 0.45 s crossed 19 of 20 at 10 cm against 16 of 20, but lost trials at
20 and 30 cm; off in its preset.

**The lateral aim.** A crossing step lasts longer than a walking step (T_c against t_nom), and the lateral DCM
offset it starts from grows by exp(ω T_c), not exp(ω t_nom): from the nominal offset b_y,nom the crossing spreads
the feet (on the H1 a 0.6 s crossing lands 0.2 m wider than the nominal width, and the QP's lateral cost bounded the
crossing to its shortest duration, in which the DCM could not carry the crossing step). With
``obstacle_lateral_aim_duration`` T_lat > 0 the last step before an obstacle aims at b_y,nom exp(-ω (T_lat - t_nom))
(:attr:`FootholdGeometry.lateral_aim_fraction`), from which a crossing lasting T_lat ends at the nominal lateral
offset and width (eq. 1b across the heading): it lands nearer its DCM. So does the lead crossing, which the trailing
crossing swing follows (from the nominal lateral offset the H1's trailing swing was planned at its widest bound and
the lateral DCM still ran away). In the even approach below every step from whose planned foothold one step reaches
beyond the obstacle aims there too, whatever the approach's count of steps: its own QP's foothold is kept as it is,
without the choice above, and the sequencer crosses as soon as the DCM lets it (the H1's crossings that lifted off a
step early or short of the bound started 10-11 cm from the DCM across the heading, the others 3-5 cm).

"Cross when one step can reach beyond, else stop at the safe distance" rather than "the cheaper
side": from the last foothold before an obstacle the cheaper step is always in place (the crossing
step is far from the nominal one), and a planner choosing by cost would never cross.

A swing passes over an obstacle when its sole rectangle, carried along the straight path of its foot
frame from lift-off to touchdown, meets the grown footprint (:func:`crossing_of`); the
plan marks that step (``PlannedStep.crossing``, a :class:`Crossing`), so the whole-body OCP lifts
that swing over the obstacle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from sequencer.obstacles import Obstacle
from wbmpc.errors import ParameterError, SolverError

PIVOT_SAMPLES = 9
"""Pivots a crossing swing's QP tries within ``obstacle_crossing_cop`` of its stance foothold (its ends, the
foothold, evenly spaced)."""


class FootholdInfeasible(SolverError):
    """No foothold of a step lies outside the obstacles within the step's bounds (a control loop keeps
    its last plan)."""


@dataclass(frozen=True)
class FootholdGeometry:
    """What the planner knows of obstacles and feet (the ``obstacle_*`` and ``sole_*`` planner parameters).

    Attributes:
        margin: the footprint grown by this on every side [m] (>= 0).
        step_length_max: length bound of a step that goes beyond an obstacle [m] (the planner uses
            max(l_max, this)).
        step_duration_min: duration lower bound of a step whose swing passes over an obstacle [s] (the
            planner uses max(t_min, this)).
        trailing_duration_min: > 0: the duration lower bound [s] of the trailing crossing swing instead (the swing
            over an obstacle whose stance foot is already beyond it: its foothold lies next to the lead foot, so
            its DCM has no long step to travel, and over a robot without ankle roll the lateral DCM offset it
            lifts off with grows as exp(ω T) until it lands; "The trailing swing's duration" in the module
            docstring); 0: ``step_duration_min``.
        trailing_height_max: > 0: ``trailing_duration_min`` holds over obstacles up to this high [m] only (a higher
            one keeps ``step_duration_min``: its trailing swing lifts higher); 0: over any obstacle.
        sole_front, sole_rear: the sole's extent ahead of and behind the foot frame along its heading [m].
        sole_half_width: the sole's half width [m].
        approach_margin: the near side (facing the stance, along the heading) grown by this much more [m]:
            a walking robot's foot overshoots a short step (the H1's by 6 cm), and lands no shorter than planned.
        offset_tolerance: a step crosses only if its DCM offset at touchdown, along the heading, is within
            this of the nominal one [m] (else the robot takes one more step before the obstacle, aiming at
            the offset the crossing needs).
        step_duration_max: duration upper bound of a crossing step [s], above or below the walking one (0: the
            walking bound, t_max).
        swing_length_max: the travel bound of a crossing foot from lift-off to touchdown along the heading [m]
            (0: none; see "Two steps ahead" in the module docstring).
        halt_double_support: > 0: a quasi-static crossing (``SequencerParams.obstacle_double_support`` [s]): the
            crossing swing lifts off after this long a double support that settles the DCM on the stance foot,
            so a step crosses whatever its DCM offset (no tolerance) and the last step before the obstacle
            aims at no particular offset; 0: the dynamic crossing above.
        trailing_double_support: > 0: the trailing crossing swing (its stance foot already beyond the obstacle)
            and the step after it lift off after this long a settling double support
            (``SequencerParams.obstacle_trailing_double_support`` [s]; planned by
            :class:`sequencer.horizon.FootstepSequencer`, the choice of footholds is unchanged); 0: none.
        resume_double_support: > 0: the step that resumes the walk after the trailing crossing swing (both feet
            beyond the obstacle) lifts off after this long a settling double support, the trailing swing itself
            dynamic (``SequencerParams.obstacle_resume_double_support`` [s]; planned by
            :class:`sequencer.horizon.FootstepSequencer` once the trailing foot is down); 0: none (or
            ``trailing_double_support``'s).
        aim_duration: the crossing duration T_c,aim [s] the last step before an obstacle aims for (its offset
            (ℓ_c + b_c) exp(-ω T_c,aim), at least the nominal one); 0: the crossing's longest, ``step_duration_max``.
        crossing_drift: κ_c [-] >= 0: a swing over an obstacle ends with the DCM κ_c d further along the heading than
            the LIPM's, d [m] its travel from lift-off to touchdown along the heading (the swing leg's mass carried
            forward: "Crossing drift" in the module docstring); 0: the LIPM's.
        crossing_cop: δ [m] >= 0: every swing over an obstacle pivots on a centre of pressure within δ of its stance
            foothold along the heading, chosen by its QP ("The crossing's centre of pressure" in the module
            docstring); 0: the foothold.
        passed_cop: δ_p [m] >= 0: a step whose stance foot is beyond an obstacle it has just crossed and whose foothold
            that obstacle bounds pivots on a centre of pressure chosen by its QP: a step pinned at the far bound within
            δ_p of its stance foothold, the trailing crossing swing within max(δ, δ_p) ("The passed obstacle's centre of
            pressure" in the module docstring); 0: the foothold for a pinned step, δ for the trailing swing.
        crossing_offset: Δb [m] >= 0: the lead crossing aims at the nominal DCM offset along the heading plus Δb at
            its touchdown, the last step before the obstacle at the offset that reaches it ("The crossing's momentum"
            in the module docstring); 0: the nominal offset.
        far_margin_reduction: the footprint's side further along the heading grown by ``margin`` minus this [m], in
            [0, margin] ("The far margin" in the module docstring); 0: ``margin``.
        landing_room: r [m] >= 0: the lead crossing lands at least r beyond the obstacle's far bound, within its length
            bound, and the last step before it aims for that crossing ("The landing room" in the module docstring);
            0: on the bound.
        lateral_aim_fraction: the last step before an obstacle and the lead crossing aim at this fraction of the
            nominal lateral DCM offset, exp(-ω (T_lat - t_nom)) in (0, 1] ("The lateral aim" in the module docstring);
            1: the nominal.
        approach_distance: > 0: within this distance [m] of the last foothold before an obstacle the walk must
            cross, the steps towards it are spaced evenly and aim at the DCM offsets that end on that foothold
            with the offset the crossing needs (:meth:`FootholdConstraints.approach`, "The approach" in the
            module docstring); 0: the greedy approach (each step its nominal one until a foothold is bounded).
    """

    margin: float
    step_length_max: float
    step_duration_min: float
    sole_front: float = 0.0
    sole_rear: float = 0.0
    sole_half_width: float = 0.0
    offset_tolerance: float = math.inf
    approach_margin: float = 0.0
    halt_double_support: float = 0.0
    step_duration_max: float = 0.0
    swing_length_max: float = 0.0
    trailing_double_support: float = 0.0
    resume_double_support: float = 0.0
    aim_duration: float = 0.0
    approach_distance: float = 0.0
    crossing_drift: float = 0.0
    lateral_aim_fraction: float = 1.0
    crossing_cop: float = 0.0
    passed_cop: float = 0.0
    crossing_offset: float = 0.0
    landing_room: float = 0.0
    far_margin_reduction: float = 0.0
    trailing_duration_min: float = 0.0
    trailing_height_max: float = 0.0

    @property
    def trailing_duration(self) -> float:
        """The duration lower bound [s] of the trailing crossing swing: ``trailing_duration_min``, or
        ``step_duration_min`` when that is 0."""
        return self.trailing_duration_min or self.step_duration_min

    def landing_length(self, length: float) -> float:
        """|ℓ| [m] of a lead crossing whose far bound is ``length`` [m] (>= 0) along the direction of travel:
        ``length`` + ``landing_room``, at most ``step_length_max`` (never below ``length``)."""
        return max(length, min(length + self.landing_room, self.step_length_max))


@dataclass(frozen=True, slots=True)
class Crossing:
    """A planned swing that passes over an obstacle.

    Attributes:
        obstacle: the obstacle it steps over (the tallest, when it passes over several).
        liftoff: world (x, y) where the swinging foot lifted off [m], shape (2,).
        phase_interval: (s_in, s_out), the fractions of the straight lift-off -> touchdown path of the
            foot frame along which the sole is over the footprint grown by the margin, in [0, 1].
    """

    obstacle: Obstacle
    liftoff: np.ndarray
    phase_interval: tuple[float, float]


@dataclass(frozen=True, slots=True)
class StepCandidate:
    """One solution of a step QP in the stance's heading frame.

    Attributes:
        dx, dy: the step p_T - p_0 (heading frame) [m]; gamma: exp(ω T) [-]; hx, hy: the DCM offset at
        touchdown (heading frame) [m]; bits: active-inequality bits (sequencer.step_qp); objective: the
        QP cost f [-]; duration: T [s]; cop: δ [m], the centre of pressure behind the
        stance foothold along the heading the step was planned with (0: the foothold).
    """

    dx: float
    dy: float
    gamma: float
    hx: float
    hy: float
    bits: int
    objective: float
    duration: float
    cop: float = 0.0


StepBounds = tuple[float, float, float, float, float, float]
"""(ℓ_min, ℓ_max, w_min, w_max, T_min, T_max) of one step, heading frame [m, m, m, m, s, s]."""


def forbidden_box(obstacle: Obstacle, p0, yaw: float, geometry: FootholdGeometry,
                  width_bounds: tuple[float, float] | None = None) -> tuple[float, float, float, float]:
    """(a, b, c, d): a foothold (ℓ, w) = p_T - p_0 in the heading frame of ``yaw`` [rad] puts the sole on
    the footprint grown by ``geometry.margin`` only if a < ℓ < b and c < w < d [m] (see the module docstring).

    The box bounds the grown footprint's part within reach of the sole: with ``width_bounds`` (w_min, w_max)
    [m], the slab w_min - sole_half_width <= w <= w_max + sole_half_width the sole can cover, so that a wide
    obstacle turned from the heading is not as deep as its whole bounding box (inf: the slab misses it)."""
    corners = obstacle.grown(geometry.margin).footprint_corners() - np.asarray(p0, dtype=float)
    c, s = math.cos(yaw), math.sin(yaw)
    polygon = np.column_stack((corners @ np.array([c, s]), corners @ np.array([-s, c])))
    if width_bounds is not None:
        polygon = _clip_slab(polygon, width_bounds[0] - geometry.sole_half_width,
                             width_bounds[1] + geometry.sole_half_width)
        if polygon.shape[0] == 0:
            return (math.inf, math.inf, math.inf, math.inf)
    a, b = float(polygon[:, 0].min()) - geometry.sole_front, float(polygon[:, 0].max()) + geometry.sole_rear
    b -= geometry.far_margin_reduction  # the far side's own margin: the grown side moved back by the difference
    if a + b > 0.0:  # the near side is the one facing the stance
        a -= geometry.approach_margin
    else:
        b += geometry.approach_margin
    return (a, b, float(polygon[:, 1].min()) - geometry.sole_half_width,
            float(polygon[:, 1].max()) + geometry.sole_half_width)


def along_heading(point, p0, yaw: float) -> float:
    """(point - p0) · heading [m]: how far the world (x, y) ``point`` [m] lies ahead of ``p0`` along the
    heading of ``yaw`` [rad]."""
    return float((np.asarray(point, dtype=float) - p0) @ np.array([math.cos(yaw), math.sin(yaw)]))


def _clip_slab(polygon: np.ndarray, low: float, high: float) -> np.ndarray:
    """The convex ``polygon`` (n, 2) cut to low <= y <= high (Sutherland-Hodgman, two half-planes); (0, 2) if empty."""
    for sign, bound in ((1.0, low), (-1.0, high)):  # keep sign * (y - bound) >= 0
        if polygon.shape[0] == 0:
            break
        kept = []
        for i in range(polygon.shape[0]):
            p, q = polygon[i], polygon[(i + 1) % polygon.shape[0]]
            fp, fq = sign * (p[1] - bound), sign * (q[1] - bound)
            if fp >= 0.0:
                kept.append(p)
            if fp * fq < 0.0:
                kept.append(p + (q - p) * (fp / (fp - fq)))
        polygon = np.array(kept).reshape(-1, 2)
    return polygon


PATH_SAMPLES = 41
"""Positions of the sole along a swing's straight path at which :func:`crossing_of` tests it (every 2.5 %)."""


def sole_corners(center_xy, yaw: float, geometry: FootholdGeometry) -> np.ndarray:
    """The sole rectangle's corners, world (x, y) [m], shape (..., 4, 2), of feet at ``center_xy`` (..., 2)
    with heading ``yaw`` [rad] (``sole_front`` ahead, ``sole_rear`` behind, ``sole_half_width`` aside)."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([[-geometry.sole_rear, -geometry.sole_half_width], [geometry.sole_front, -geometry.sole_half_width],
                      [geometry.sole_front, geometry.sole_half_width], [-geometry.sole_rear, geometry.sole_half_width]])
    world = local @ np.array([[c, s], [-s, c]])
    return np.asarray(center_xy, dtype=float)[..., None, :] + world


def rectangles_overlap(corners, other) -> np.ndarray:
    """True where rectangle ``corners`` (..., 4, 2) and the rectangle ``other`` (4, 2) overlap with a positive
    area (separating axes: the four edge normals; rectangles that only touch do not overlap). A rectangle of
    zero size (a point foot) overlaps when it lies strictly inside the other one."""
    corners = np.asarray(corners, dtype=float)
    other = np.asarray(other, dtype=float)
    overlap = np.ones(corners.shape[:-2], dtype=bool)
    for polygon in (corners, other):
        for edge in (0, 1):
            axis = polygon[..., edge + 1, :] - polygon[..., edge, :]
            axis = np.stack((-axis[..., 1], axis[..., 0]), axis=-1)[..., None, :]
            mine = np.sum(corners * axis, axis=-1)
            theirs = np.sum(other * axis, axis=-1)
            separated = (mine.max(axis=-1) <= theirs.min(axis=-1) + 1e-9) | (theirs.max(axis=-1) <= mine.min(axis=-1) + 1e-9)
            degenerate = np.linalg.norm(axis[..., 0, :], axis=-1) < 1e-12  # a point foot's zero-length edges
            overlap &= ~separated | degenerate
    return overlap


def sole_on_obstacle(obstacles: Sequence[Obstacle], position, yaw: float, geometry: FootholdGeometry) -> bool:
    """Whether a sole at world ``position`` (x, y) [m] with heading ``yaw`` [rad] overlaps the footprint of any of
    ``obstacles`` grown by the margin (a foothold the planner keeps its steps out of)."""
    corners = sole_corners(position, yaw, geometry)
    return any(bool(rectangles_overlap(corners, obstacle.grown(geometry.margin).footprint_corners()))
               for obstacle in obstacles)


def crossing_of(obstacles: Sequence[Obstacle], liftoff, touchdown, yaw: float,
                geometry: FootholdGeometry) -> Crossing | None:
    """The :class:`Crossing` of a swing from ``liftoff`` to ``touchdown`` (world (x, y) [m]), its sole heading
    ``yaw`` [rad], over the tallest of ``obstacles`` whose footprint grown by the margin the sole meets
    somewhere on the straight path (tested at :data:`PATH_SAMPLES` positions), or None. A swing that lifts off within
    an obstacle's margin and leaves it (the grown footprint met from the lift-off on, not at the touchdown, the
    obstacle's own footprint nowhere) does not cross that obstacle: a foot that landed a few millimetres short of the
    far bound would otherwise step away from the box as a crossing (the slower swing, its plateau and clearance; the
    H1's step after the trailing touchdown, session 22)."""
    if liftoff is None or not obstacles:
        return None
    start = np.array(liftoff, dtype=float)
    phases = np.linspace(0.0, 1.0, PATH_SAMPLES)
    soles = sole_corners(start + phases[:, None] * (np.asarray(touchdown, dtype=float) - start), yaw, geometry)
    best = None
    for obstacle in obstacles:
        over = np.flatnonzero(rectangles_overlap(soles, obstacle.grown(geometry.margin).footprint_corners()))
        if over.size and over[0] == 0 and over[-1] < PATH_SAMPLES - 1 \
                and not rectangles_overlap(soles, obstacle.footprint_corners()).any():
            continue  # lifts off within the margin and leaves it
        if over.size and (best is None or obstacle.height > best[0].height):
            best = (obstacle, (float(phases[over[0]]), float(phases[over[-1]])))
    if best is None:
        return None
    start.setflags(write=False)
    return Crossing(best[0], start, best[1])


class FootholdConstraints:
    """The per-step choice of the module docstring for a set of obstacles.

    Args:
        obstacles: the obstacles (world frame).
        geometry: margins, the crossing step's bounds and the sole.
        omega: the LIPM's natural frequency [1/s] (the DCM offset the last step before an obstacle aims at).
    """

    def __init__(self, obstacles: Sequence[Obstacle], geometry: FootholdGeometry, omega: float) -> None:
        obstacles = tuple(obstacles)
        for obstacle in obstacles:
            if not isinstance(obstacle, Obstacle):
                raise ParameterError(f"obstacles must be sequencer.obstacles.Obstacle, got {type(obstacle).__name__}")
        self.obstacles = obstacles
        self.geometry = geometry
        self.omega = float(omega)

    def choose(self, p0, yaw: float, bounds: StepBounds, nominal: StepCandidate,
               solve: Callable[..., StepCandidate], liftoff, step_length_nominal: float,
               offset_nominal: float, cross: bool | None = None) -> tuple[StepCandidate, bool]:
        """The step of stance ``p0`` (world (x, y) [m]) in the heading frame ``yaw`` [rad] whose foothold
        avoids every obstacle: (candidate, changed). ``nominal`` is the QP's solution with its nominal
        ``bounds``; ``solve(bounds, aim, lateral=1.0)`` solves the same QP with other bounds (and, unless ``aim`` is
        None, the DCM offset b_x [m] it aims at along the heading instead of ``offset_nominal``; the lateral offset
        aimed at: ``lateral`` times the nominal one); ``liftoff`` is where the swinging
        foot lifted off (world (x, y) [m], None: unknown), for the crossing duration; the sign of
        ``step_length_nominal`` [m] (the nominal step along the heading) is the direction of travel: only
        an obstacle in that direction is crossed (0: stepping in place crosses none). ``cross`` keeps a decision
        already made (the swing in progress: True crosses when one step reaches beyond, whatever the DCM, also
        when the step's own foothold stops short of the obstacle (the DCM fallen back: the H1's at the last step's
        touchdown turned a planned crossing into a step in place in the double support before it, and fell);
        False stays before); None decides.

        Raises:
            FootholdInfeasible: no candidate side is feasible within the bounds.
        """
        p0 = np.asarray(p0, dtype=float)
        boxes = [forbidden_box(obstacle, p0, yaw, self.geometry, (bounds[2], bounds[3])) for obstacle in self.obstacles]
        lift_along = None if liftoff is None else along_heading(liftoff, p0, yaw)
        sign = 1.0 if step_length_nominal > 0.0 else -1.0
        candidate, changed, aim = nominal, False, None
        lengthened = False
        for _ in range(2 * len(boxes) + 2):
            hit = next((box for box in boxes if box[0] < candidate.dx < box[1] and box[2] < candidate.dy < box[3]),
                       None)
            if hit is None and cross and not changed:  # a kept crossing, whatever the step's own foothold
                hit = self._kept_crossing(boxes, candidate, sign)
            if hit is None:
                if lengthened or not self._crosses(p0, yaw, candidate, liftoff):
                    return candidate, changed
                trailing = self._trailing_bounds(bounds, lift_along, sign, boxes, candidate.dx)
                if trailing[0] <= candidate.dx <= trailing[1] \
                        and trailing[4] - 1e-12 <= candidate.duration <= trailing[5] + 1e-12:
                    return candidate, changed
                bounds = trailing
                candidate = self.swing_solve(solve, bounds, aim, offset_nominal, lift_along,
                                             cop_bound=self._trailing_cop_bound(boxes, sign, lift_along))
                changed, lengthened = True, True
                continue
            along, beside = self._options(hit, bounds, step_length_nominal, offset_nominal)
            checked = None  # (candidate, bounds, aim) of the crossing option, once solved
            if along and along[0][2]:  # cross, unless the DCM cannot carry it: then one more step before
                if cross is None and self.geometry.halt_double_support > 0.0:
                    late = False  # quasi-static: the double support before the swing settles the DCM
                elif cross is None:
                    checked = self._solve_option(solve, along[0][0], None, True, step_length_nominal, offset_nominal,
                                                 lift_along)
                    # the crossing's aim without its momentum Δb: whether the DCM can carry the crossing at all
                    target = offset_nominal if checked[2] is None else checked[2] - sign * self.geometry.crossing_offset
                    late = sign * (target - checked[0].hx) > self.geometry.offset_tolerance
                else:
                    late = not cross
                along = along[1:2] if late and len(along) > 1 else along[:1]
            options = along + beside
            if not options:
                raise FootholdInfeasible(
                    f"no foothold outside the obstacle box (a, b, c, d) = {tuple(round(v, 4) for v in hit)} m "
                    f"within the step bounds {tuple(round(v, 4) for v in bounds)} (stance p0={p0.tolist()} m)")
            solved = [checked if checked is not None and option is checked[1]  # solved for the DCM check
                      else self._solve_option(solve, option, far, crossing, step_length_nominal, offset_nominal,
                                              lift_along, passed)
                      for option, far, crossing, passed in options]
            candidate, bounds, aim = min(solved, key=lambda triple: triple[0].objective)
            changed = True
        raise FootholdInfeasible(f"the footholds of the stance p0={p0.tolist()} m did not settle outside the "
                                 f"{len(boxes)} obstacles")

    def _trailing_cop_bound(self, boxes, sign: float, lift_along: float | None) -> float | None:
        """The pivot bound [m] of a swing over an obstacle (:meth:`swing_solve`): max(``crossing_cop``, ``passed_cop``)
        for the trailing swing (a box (a, b, c, d) whose middle lies behind the stance in the direction of travel
        ``sign`` and ahead of the lift-off ``lift_along`` [m], when known), else None (``crossing_cop``)."""
        if self.geometry.passed_cop <= 0.0 or not self._passed(boxes, sign, lift_along):
            return None
        return max(self.geometry.crossing_cop, self.geometry.passed_cop)

    def _passed(self, boxes, sign: float, lift_along: float | None) -> list[Obstacle]:
        """The obstacles of ``boxes`` (a, b, c, d), :attr:`obstacles`' boxes in their order, that a trailing swing
        crosses: the box's middle behind the stance in the direction of travel ``sign`` and ahead of the lift-off
        ``lift_along`` [m] along the heading (None: unknown, any box behind the stance)."""
        return [obstacle for obstacle, (a, b, _, _) in zip(self.obstacles, boxes)
                if sign * (a + b) < 0.0 and (lift_along is None or sign * (0.5 * (a + b) - lift_along) > 0.0)]

    @staticmethod
    def _kept_crossing(boxes, candidate: StepCandidate, sign: float):
        """The box (a, b, c, d) a kept crossing decision is about when ``candidate`` stops short of every box: the
        nearest one ahead in the direction of travel ``sign`` (its middle ahead, the foothold at or before its near
        bound) across the foothold's lateral position; None: no such box."""
        ahead = [box for box in boxes if sign * (box[0] + box[1]) > 0.0 and box[2] < candidate.dy < box[3]
                 and (candidate.dx <= box[0] if sign > 0.0 else candidate.dx >= box[1])]
        return min(ahead, key=lambda box: abs(box[0] if sign > 0.0 else box[1]), default=None)

    def _options(self, box, bounds: StepBounds, step_length_nominal: float,
                 offset_nominal: float) -> tuple[list, list]:
        """The feasible candidates (bounds, far side for a last step before it or None, crossing?, passed?) of a
        foothold outside ``box``, as (along the heading, beside it): along, the crossing step first when the obstacle
        (the box's middle) lies in the direction of travel and one step reaches beyond it, then the step
        before it (both sides, no crossing, when the stance sole is itself within the box); beside it, either
        side within the width bounds. Passed: the step along the direction of travel away from a box whose middle
        lies behind the stance (a foothold pinned at the far bound of an obstacle just crossed)."""
        a, b, c, d = box
        l_lo, l_hi, w_lo, w_hi, t_lo, t_hi = bounds
        reach, t_cross = self.geometry.step_length_max, max(t_lo, self.geometry.step_duration_min)
        t_cross_hi = self.geometry.step_duration_max or t_hi
        inside = a < 0.0 < b and c < 0.0 < d  # the stance sole itself is within the grown footprint
        ahead = a + b > 0.0  # the box's middle ahead of the stance along the heading
        prepare = None  # the far side the next step crosses, when this may be the last step before it
        if not inside and (ahead == (step_length_nominal > 0.0)) and step_length_nominal != 0.0 and b - a <= reach \
                and self.geometry.halt_double_support == 0.0:
            prepare = b if ahead else a  # crossable from the foothold at the safe distance
        forwards, backwards = step_length_nominal > 0.0, step_length_nominal < 0.0
        if inside:  # either side, no crossing step
            along = [((l_lo, min(l_hi, a), w_lo, w_hi, t_lo, t_hi), None, False, backwards and ahead),
                     ((max(l_lo, b), l_hi, w_lo, w_hi, t_lo, t_hi), None, False, forwards and not ahead)]
        elif ahead:  # beyond (crossing, when walking forwards) or before
            along = [((max(l_lo, self.geometry.landing_length(b)), max(l_hi, reach), w_lo, w_hi, t_cross, t_cross_hi),
                       None, True, False)] if forwards else []
            along.append(((l_lo, min(l_hi, a), w_lo, w_hi, t_lo, t_hi), prepare, False, backwards))
        else:  # behind: beyond it backwards (walking backwards), or stay
            along = [((min(l_lo, -reach), min(l_hi, -self.geometry.landing_length(-a)), w_lo, w_hi, t_cross,
                       t_cross_hi), None, True, False)] if backwards else []
            along.append(((max(l_lo, b), l_hi, w_lo, w_hi, t_lo, t_hi), prepare, False, forwards))
        beside = [(l_lo, l_hi, w_lo, min(w_hi, c), t_lo, t_hi), (l_lo, l_hi, max(w_lo, d), w_hi, t_lo, t_hi)]
        return ([option for option in along if self._feasible(option[0])],
                [(option, None, False, False) for option in beside if self._feasible(option)])

    def _solve_option(self, solve, bounds: StepBounds, far: float | None, crossing: bool, step_length_nominal: float,
                      offset_nominal: float, lift_along: float | None = None, passed: bool = False
                      ) -> tuple[StepCandidate, StepBounds, float | None]:
        """(candidate, bounds, aimed offset) of one option. ``far`` (the far side b of the obstacle the next step
        crosses, relative to this stance [m]) marks the last step before it: that step aims at the DCM offset
        that makes the crossing step from its foothold ℓ (length |b - ℓ|, within T_c,aim: its longest duration
        unless ``aim_duration`` > 0) end at the offset the crossing aims at, b_x = (|b - ℓ| + b_c) exp(-ω T_c,aim)
        (eq. 1b), and at least the
        nominal offset (the walk's own: a larger aim leans the robot into a short step, and the H1's DCM ran
        13 cm past the foot that should have stopped it). ``crossing`` (a step
        beyond, with a swing travel bound) aims at b_c of "Two steps ahead" in the module docstring. Three
        fixed-point passes: the foothold moves with the aim. A crossing's candidate carries the crossing drift
        (:meth:`swing_solve`; ``lift_along``: its lift-off along the heading from this stance [m], None: unknown).
        A ``passed`` option (a foothold pinned at the far bound of an obstacle behind the stance) pivots on the centre
        of pressure within ``passed_cop`` of its stance foothold (:meth:`pivot_solve`)."""
        sign = 1.0 if step_length_nominal > 0.0 else -1.0
        if far is None and not (crossing and self.geometry.swing_length_max > 0.0):
            if crossing:  # the lead crossing: the trailing crossing swing follows it (the lateral aim)
                aim = offset_nominal + sign * self.geometry.crossing_offset if self.geometry.crossing_offset else None
                return self.swing_solve(solve, bounds, aim, offset_nominal, lift_along,
                                        self.geometry.lateral_aim_fraction), bounds, aim
            if passed:
                return self.pivot_solve(solve, bounds, None, bound=self.geometry.passed_cop), bounds, None
            return solve(bounds, None), bounds, None
        foothold = bounds[1] if sign > 0.0 else bounds[0]
        aim, candidate = None, None
        for _ in range(3):
            if far is None:  # the crossing itself
                aim = self._crossing_aim(abs(foothold), sign, step_length_nominal, offset_nominal)
                candidate = self.swing_solve(solve, bounds, aim, offset_nominal, lift_along,
                                             self.geometry.lateral_aim_fraction)
            else:  # the last step before it: at least the nominal offset; the crossing lifts off this stance
                aim = self.last_step_aim(abs(far - foothold), sign, step_length_nominal, offset_nominal,
                                         travel=abs(far))
                candidate = solve(bounds, aim, self.geometry.lateral_aim_fraction)
            foothold = candidate.dx
        return candidate, bounds, aim

    def swing_solve(self, solve, bounds: StepBounds, aim: float | None, offset_nominal: float,
                    lift_along: float | None, lateral: float = 1.0, cop_bound: float | None = None) -> StepCandidate:
        """``solve(bounds, aim)`` for a swing over an obstacle with the crossing drift κ_c d ("Crossing drift" in
        the module docstring; d = ℓ - ``lift_along`` [m], the swing's signed travel along the heading, ℓ with
        the lift-off unknown): the QP's LIPM offset aimed at b - κ_c d (b = ``aim``, or ``offset_nominal`` for
        None), the candidate's offset h + κ_c d (two fixed-point passes: d moves with the foothold). κ_c = 0:
        ``solve(bounds, aim)``. Every solve pivots on the crossing's centre of pressure (:meth:`pivot_solve`, within
        ``cop_bound`` [m], None: ``crossing_cop``) and aims at ``lateral`` times the nominal lateral offset."""
        kappa = self.geometry.crossing_drift
        candidate = self.pivot_solve(solve, bounds, aim, lateral, cop_bound)
        if kappa <= 0.0:
            return candidate
        target = offset_nominal if aim is None else aim
        drift = 0.0
        for _ in range(2):
            drift = kappa * (candidate.dx - (0.0 if lift_along is None else lift_along))
            candidate = self.pivot_solve(solve, bounds, target - drift, lateral, cop_bound)
        return replace(candidate, hx=candidate.hx + drift)

    def pivot_solve(self, solve, bounds: StepBounds, aim: float | None, lateral: float = 1.0,
                    bound: float | None = None) -> StepCandidate:
        """``solve(bounds, aim, lateral, cop=δ_c)`` at the pivot δ_c in [-δ, δ] (δ = ``bound`` [m], None:
        ``crossing_cop``; :data:`PIVOT_SAMPLES` values) of least QP objective, the nearest the foothold among equal ones
        (relative 1e-9); δ = 0: ``solve(bounds, aim, lateral)``."""
        if bound is None:
            bound = self.geometry.crossing_cop
        if bound <= 0.0:
            return solve(bounds, aim, lateral)
        best = None
        for cop in sorted(np.linspace(-bound, bound, PIVOT_SAMPLES).tolist(), key=abs):
            candidate = solve(bounds, aim, lateral, cop=cop)
            if best is None or candidate.objective < best.objective - 1e-9 * max(1.0, abs(best.objective)):
                best = candidate
        return best

    def last_step_aim(self, crossing_length: float, sign: float, step_length_nominal: float,
                      offset_nominal: float, travel: float = 0.0) -> float:
        """b_x [m], heading frame: the DCM offset the last step before an obstacle aims at, from which the crossing
        step of ``crossing_length`` [m] to the far bound (plus its landing room) reaches its own aim (b_c, or without a
        travel bound the nominal offset plus
        the crossing's momentum sign Δb)
        within T_c,aim, and at least the nominal offset: sign max((ℓ_c + δ + sign b_c - κ_c d_c) exp(-ω T_c,aim) - δ,
        sign b_nom), d_c = ``travel`` [m] the crossing swing's travel from its lift-off (the crossing drift), δ the
        crossing's centre of pressure behind its stance foothold (``crossing_cop``)."""
        decay = math.exp(-self.omega * (self.geometry.aim_duration or self.geometry.step_duration_max))
        room = self.geometry.landing_length(crossing_length) - crossing_length  # the landing room
        crossing_length += room
        target = self._crossing_aim(crossing_length, sign, step_length_nominal, offset_nominal) \
            if self.geometry.swing_length_max > 0.0 else offset_nominal + sign * self.geometry.crossing_offset
        drift = self.geometry.crossing_drift * (abs(travel) + room if travel else 0.0)
        cop = self.geometry.crossing_cop
        return sign * max((crossing_length + cop + sign * target - drift) * decay - cop, sign * offset_nominal)

    def approach(self, p0, yaw: float, width_bounds: tuple[float, float],
                 step_length_nominal: float) -> tuple[float, float] | None:
        """(a, b) [m] along the heading of ``yaw`` [rad] from the stance ``p0`` (world (x, y) [m]): the bound
        ℓ <= a of the last foothold before the nearest obstacle ahead that the walk has to cross (its box spans
        the step's ``width_bounds`` (w_min, w_max) [m]: no foothold beside it; one crossing step reaches beyond
        it) and its far side ℓ >= b; None without ``approach_distance``, when walking in place or backwards, or
        when no such obstacle's a lies in (0, approach_distance]."""
        if self.geometry.approach_distance <= 0.0 or step_length_nominal <= 0.0:
            return None
        nearest = None
        for obstacle in self.obstacles:
            a, b, c, d = forbidden_box(obstacle, p0, yaw, self.geometry, width_bounds)
            if 0.0 < a <= self.geometry.approach_distance and c <= width_bounds[0] and d >= width_bounds[1] \
                    and b - a <= self.geometry.step_length_max and (nearest is None or a < nearest[0]):
                nearest = (a, b)
        return nearest

    def _crossing_aim(self, crossing_length: float, sign: float, step_length_nominal: float,
                      offset_nominal: float) -> float:
        """b_c [m], heading frame: the DCM offset at the touchdown of a crossing step of ``crossing_length`` [m]
        from which the trailing step, ℓ_t = min(|l_nom|, max(0, s_max - crossing_length)) long and lasting the
        crossing's least duration (the trailing swing's own bound, when shorter, is left out: this aim is that of
        the longest trailing swing), ends at ``offset_nominal``: sign (ℓ_t + sign b_nom) exp(-ω T_c,min), plus the
        crossing's momentum sign Δb (``crossing_offset``)."""
        trailing = min(abs(step_length_nominal), max(0.0, self.geometry.swing_length_max - crossing_length))
        return sign * ((trailing + sign * offset_nominal) * math.exp(-self.omega * self.geometry.step_duration_min)
                       + self.geometry.crossing_offset)

    def _trailing_bounds(self, bounds: StepBounds, lift_along: float | None, sign: float, boxes=(),
                         free: float | None = None) -> StepBounds:
        """``bounds`` of a step whose swing passes over an obstacle with a foothold outside it (the trailing foot):
        the crossing durations (the trailing swing's, :attr:`FootholdGeometry.trailing_duration`, over the boxes
        :meth:`_passed` finds for a known lift-off, in the direction of travel ``sign``, when none of those obstacles
        is higher than ``trailing_height_max``) and, with a swing travel bound s_max and a known lift-off
        ``lift_along`` [m] (along the heading from the stance, None: unknown), ℓ within ℓ_lift ± s_max (never
        tighter than the step's other bound).
        A travel bound that would end inside one of ``boxes`` (a, b, c, d) the swing crosses, between the lift-off
        and ``free`` (the foothold ℓ found without the bound, outside every box), is moved to that box's far side
        (b forwards, a backwards): a bound shorter than what clears the box put the foothold inside it (the
        step infeasible, the plan with it: the H1 with s_max = 0.3 m from 2.7 s on)."""
        l_lo, l_hi = bounds[0], bounds[1]
        reach = self.geometry.swing_length_max
        if reach > 0.0 and lift_along is not None:
            upper, lower = lift_along + reach, lift_along - reach
            if free is not None:
                for a, b, _, _ in sorted(boxes, key=lambda box: box[1]):  # forwards: the far side b
                    if lift_along < b <= free + 1e-12 and a < upper < b:
                        upper = b
                for a, b, _, _ in sorted(boxes, key=lambda box: -box[0]):  # backwards: the far side a
                    if free - 1e-12 <= a < lift_along and a < lower < b:
                        lower = a
            l_lo, l_hi = min(max(l_lo, lower), l_hi), max(min(l_hi, upper), l_lo)
        passed = [] if lift_along is None else self._passed(boxes, sign, lift_along)
        highest = self.geometry.trailing_height_max or math.inf
        shortest = self.geometry.trailing_duration if passed and max(o.height for o in passed) <= highest \
            else self.geometry.step_duration_min
        return (l_lo, l_hi, bounds[2], bounds[3], max(bounds[4], shortest),
                self.geometry.step_duration_max or bounds[5])

    def _feasible(self, bounds: StepBounds) -> bool:
        return bounds[0] <= bounds[1] and bounds[2] <= bounds[3] and bounds[4] <= bounds[5]

    def _crosses(self, p0, yaw: float, candidate: StepCandidate, liftoff) -> bool:
        c, s = math.cos(yaw), math.sin(yaw)
        touchdown = p0 + np.array([c * candidate.dx - s * candidate.dy, s * candidate.dx + c * candidate.dy])
        return crossing_of(self.obstacles, liftoff, touchdown, yaw, self.geometry) is not None
