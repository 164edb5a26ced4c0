"""What a campaign runs: scenario parameters on a grid and/or random sample, x variants x seeds.

A :class:`CampaignSpec` is plain data (it round-trips through a dict, TOML and ``campaign.json``):

- ``params``: parameters shared by every trial;
- ``grid``: axis name -> list of values; the trials take the full Cartesian product;
- ``random``: ``n`` points drawn uniformly in per-axis ranges (seeded by ``sample_seed``), crossed
  with the grid (so a grid with no axes and a random sample gives exactly ``n`` points);
- ``variants``: named sets of parameter overrides, each run on every point (e.g. adaptive against
  fixed step timing on the same push grid);
- ``seeds``: the run seeds (terrain layout, measurement noise); every point runs once per seed.

Trial order is seed, point, variant (outer to inner), so a campaign stopped early still compares
its variants on the same points.

Parameter names are those of :func:`sim.run_scenario` (scenario, runner and controller options)
plus the campaign parameters of :mod:`sim.campaigns.trial` (``force_x``, ``force_y``, ``phase``,
``push_after``, ``step_timing``), which are translated into scenario/controller arguments.

A campaign file (TOML)::

    name = "push-map-small"
    scenario = "push"
    controller = "walking"
    duration = 6.0           # [s] simulated time of every trial
    seeds = [0]

    [params]
    speed = 0.33             # [m/s]
    push_after = 3.0         # [s], push_time = push_after + phase * T_nom (a multiple of T_nom)

    [grid]
    force_x = {start = -12.0, stop = 12.0, num = 7}    # [N], world frame
    force_y = [0.0, 6.0, 12.0]                           # [N]
    phase = [0.0, 0.2, 0.4, 0.6, 0.8]                    # fraction of the nominal step

    [variants.adaptive]
    step_timing = "adaptive"
    [variants.fixed]
    step_timing = "fixed"
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from wbmpc.config import read_toml
from wbmpc.errors import ParameterError

CONTROLLERS = ("walking", "pd")
DEFAULT_VARIANT = "default"

# Built-in push map (Bolt, 1.254 kg): the G1 map of Fig. 6 of the ALIP paper spans Fx in [-600, 600] N
# and Fy in [0, 400] N on 35 kg; scaled by mass that is about +-21 N and 0-14 N on Bolt. The Bolt
# paper's own push is 6.3 N along y. The default grid covers up to twice the paper's push.
PUSH_FORCE_MAX = 12.0  # [N]
PUSH_FORCE_STEPS_X = 7  # -12, -8, ..., 12 N
PUSH_FORCE_STEPS_Y = 4  # 0, 4, 8, 12 N
PUSH_PHASES = (0.0, 0.2, 0.4, 0.6, 0.8)  # 5 pushes per force, spread over the step (as the paper's 5 repeats)
TIMING_FROM = 2.0  # [s], start of the compared step timing in the timing study (after the start from standing)
PUSH_AFTER = 3.0  # [s], ten nominal steps of 0.3 s: walking is steady by then
PUSH_RECOVERY_TIME = 2.5  # [s] of walking after the latest push ends, to count as recovered
TERRAIN_SEEDS = 10
TERRAIN_DURATION = 10.0  # [s]
OBSTACLE_HEIGHTS = (0.1, 0.2, 0.3, 0.4)  # [m], the seed-000 thesis's (Fig. 5.13)
OBSTACLE_TRIALS = 20  # seeds per height (the thesis's 20 trials)


@dataclass
class RandomSample:
    """``n`` points drawn uniformly in ``ranges`` (axis name -> (low, high)), seeded by ``sample_seed``."""

    n: int
    ranges: dict[str, tuple[float, float]]
    sample_seed: int = 0

    def __post_init__(self) -> None:
        if not (isinstance(self.n, int) and not isinstance(self.n, bool) and self.n >= 1):
            raise ParameterError(f"random.n={self.n!r} must be an integer >= 1")
        if not self.ranges:
            raise ParameterError("random: give at least one axis range, e.g. force_x = [-12.0, 12.0]")
        ranges = {}
        for name, bounds in self.ranges.items():
            if not (isinstance(bounds, (list, tuple)) and len(bounds) == 2):
                raise ParameterError(f"random.{name}={bounds!r} must be a [low, high] pair")
            low, high = float(bounds[0]), float(bounds[1])
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ParameterError(f"random.{name}=[{low}, {high}] must be finite with low <= high")
            ranges[name] = (low, high)
        self.ranges = ranges
        self.sample_seed = int(self.sample_seed)

    def points(self) -> list[dict[str, float]]:
        """The sampled points (same seed, same points)."""
        rng = np.random.default_rng(self.sample_seed)
        names = sorted(self.ranges)
        values = {name: rng.uniform(*self.ranges[name], self.n) for name in names}
        return [{name: float(values[name][i]) for name in names} for i in range(self.n)]


@dataclass
class CampaignSpec:
    """A campaign: which trials to run (see the module docstring).

    Attributes:
        name: label of the campaign (reports, progress bar).
        scenario: registered scenario name ("push", "terrain", ...).
        controller: "walking" (the library's controller, default) or "pd".
        duration: simulated time of each trial [s]; None = the scenario's default.
        robot: registered robot name.
        params: parameters shared by every trial.
        grid: axis name -> values (full factorial).
        random: optional :class:`RandomSample`, crossed with the grid.
        variants: variant name -> parameter overrides; default: one variant "default" with none.
        seeds: run seeds, one trial per point, variant and seed.
    """

    name: str
    scenario: str
    controller: str = "walking"
    duration: float | None = None
    robot: str = "bolt"
    params: dict[str, Any] = field(default_factory=dict)
    grid: dict[str, list[Any]] = field(default_factory=dict)
    random: RandomSample | None = None
    variants: dict[str, dict[str, Any]] = field(default_factory=lambda: {DEFAULT_VARIANT: {}})
    seeds: list[int] = field(default_factory=lambda: [0])

    def __post_init__(self) -> None:
        from sim.scenarios import available_scenarios

        if not (isinstance(self.name, str) and self.name):
            raise ParameterError(f"name={self.name!r} must be a non-empty string")
        if self.scenario not in available_scenarios():
            raise ParameterError(f"scenario={self.scenario!r} is unknown (available: {available_scenarios()})")
        from robots.registry import available_robots

        if self.robot not in available_robots():
            raise ParameterError(f"robot={self.robot!r} is not known; available robots: {', '.join(available_robots())}")
        if self.controller not in CONTROLLERS:
            raise ParameterError(f"controller={self.controller!r} must be one of {CONTROLLERS}")
        if self.duration is not None:
            self.duration = float(self.duration)
            if not (math.isfinite(self.duration) and self.duration > 0):
                raise ParameterError(f"duration={self.duration} s must be a finite positive number")
        self.params = dict(self.params)
        self.grid = {name: _axis_values(name, values) for name, values in self.grid.items()}
        if isinstance(self.random, dict):
            self.random = RandomSample(**self.random)
        if not self.variants:
            self.variants = {DEFAULT_VARIANT: {}}
        self.variants = {str(k): dict(v) for k, v in self.variants.items()}
        seeds = list(self.seeds)
        if not seeds or not all(isinstance(s, (int, np.integer)) and not isinstance(s, bool) for s in seeds):
            raise ParameterError(f"seeds={self.seeds!r} must be a non-empty list of integers")
        if len(set(seeds)) != len(seeds):
            raise ParameterError(f"seeds={self.seeds!r} holds duplicates")
        self.seeds = [int(s) for s in seeds]
        random_axes = set(self.random.ranges) if self.random else set()
        sources = {"params": set(self.params), "grid": set(self.grid), "random": random_axes}
        for (a, names_a), (b, names_b) in itertools.combinations(sources.items(), 2):
            both = sorted(names_a & names_b)
            if both:
                raise ParameterError(f"parameter(s) {both} are set both in {a} and in {b}; set each in one place")
        for variant, overrides in self.variants.items():
            clash = sorted(set(overrides) & (set(self.grid) | random_axes))
            if clash:
                raise ParameterError(f"variant {variant!r} overrides grid/random axis {clash}; that would hide the axis")

    # ------------------------------------------------------------------ points
    def points(self) -> list[dict[str, Any]]:
        """Parameter points (grid x random sample), without the shared params, variants or seeds."""
        names = list(self.grid)
        grid_points = [dict(zip(names, values)) for values in itertools.product(*(self.grid[n] for n in names))]
        if self.random is None:
            return grid_points
        return [{**g, **r} for g in grid_points for r in self.random.points()]

    @property
    def n_trials(self) -> int:
        return len(self.points()) * len(self.variants) * len(self.seeds)

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON/TOML-able); ``CampaignSpec.from_dict(spec.to_dict()) == spec``."""
        data = dataclasses.asdict(self)
        if self.random is None:
            data.pop("random")
        else:
            data["random"]["ranges"] = {k: list(v) for k, v in self.random.ranges.items()}
        if self.duration is None:
            data.pop("duration")
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str = "dict") -> "CampaignSpec":
        """Build a spec from a mapping (unknown keys raise, naming ``source``)."""
        allowed = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(data) - set(allowed))
        if unknown:
            raise ParameterError(f"unknown campaign key(s) {unknown} in {source}; allowed: {allowed}")
        missing = [k for k in ("name", "scenario") if k not in data]
        if missing:
            raise ParameterError(f"campaign {source} lacks required key(s) {missing}")
        data = dict(data)
        if isinstance(data.get("random"), dict):
            random = dict(data["random"])
            n = random.pop("n", None)
            sample_seed = random.pop("sample_seed", 0)
            ranges = random.pop("ranges", None) or random  # TOML form: axis = [low, high] inline
            data["random"] = RandomSample(n=n, ranges=ranges, sample_seed=sample_seed)
        return cls(**data)

    @classmethod
    def from_toml(cls, path: str | Path) -> "CampaignSpec":
        """Load a campaign file (see the module docstring for the format)."""
        return cls.from_dict(read_toml(path, "campaign file"), source=str(path))


def _axis_values(name: str, values: Any) -> list[Any]:
    """Grid axis values from a list or a ``{start, stop, num}`` linear range (both ends included)."""
    if isinstance(values, dict):
        keys = set(values)
        if keys != {"start", "stop", "num"}:
            raise ParameterError(f"grid.{name}={values!r}: a range needs exactly the keys start, stop, num")
        num = values["num"]
        if not (isinstance(num, int) and num >= 1):
            raise ParameterError(f"grid.{name}.num={num!r} must be an integer >= 1")
        return [float(v) for v in np.linspace(float(values["start"]), float(values["stop"]), num)]
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise ParameterError(f"grid.{name}={values!r} must be a list of values or a {{start, stop, num}} range")
    values = [v.item() if isinstance(v, np.generic) else v for v in values]
    if not values:
        raise ParameterError(f"grid.{name} is empty")
    if len(set(map(repr, values))) != len(values):
        raise ParameterError(f"grid.{name}={values!r} holds duplicates")
    return values


# ---------------------------------------------------------------------- built-in campaigns
def push_map(
    force_max_x: float = PUSH_FORCE_MAX,
    force_max_y: float = PUSH_FORCE_MAX,
    steps_x: int = PUSH_FORCE_STEPS_X,
    steps_y: int = PUSH_FORCE_STEPS_Y,
    phases: tuple[float, ...] = PUSH_PHASES,
    seeds: tuple[int, ...] = (0,),
    compare_timing: str | None = None,
    timing_from: float = TIMING_FROM,
    controller: str = "walking",
    push_after: float = PUSH_AFTER,
    duration: float | None = None,
    params: dict[str, Any] | None = None,
    robot: str = "bolt",
) -> CampaignSpec:
    """Push-recovery map (ALIP paper, Fig. 6): 0.1 s pushes, Fx in [-Fx, Fx], Fy in [0, Fy] [N].

    Each force is applied at every gait phase in ``phases``: the push starts at
    ``push_after + phase * T_nom`` (T_nom the nominal step period of the robot's footstep planner,
    :func:`sim.campaigns.trial.nominal_step_period`; ``push_after`` a multiple of it,
    so phase 0 is a nominal touchdown; the phase measured from the controller's stance switches is
    recorded beside it). With the default five phases that is the paper's five repeats per force
    "at different times to account for varying step phases".

    Args:
        force_max_x, force_max_y: largest push along x and y [N], world frame.
        steps_x, steps_y: number of force values per axis (both ends included).
        phases: gait phases of the push, each in [0, 1).
        seeds: run seeds (matter only with measurement noise: pushes on flat ground are deterministic).
        compare_timing: None (adaptive step timing only), "fixed" (T_min = T_max = T_nom) or
            "stiff" (timing weight alpha_2 made very large): runs both variants on the same grid.
        timing_from: time [s] from the first touchdown after which the compared variant's step
            timing applies (before it both variants walk with adaptive timing: a start from
            standing with fixed timing falls); 0 applies it from the start.
        controller: "walking" or "pd".
        push_after: time before the pushes [s] (walking reaches steady state).
        duration: simulated time per trial [s]; None = latest push end + ``PUSH_RECOVERY_TIME``.
        params: extra shared parameters (scenario, runner, controller options); the push acts on the
            robot's base body (:func:`base_body_name`) unless they set ``base_body``.
        robot: registered robot name.
    """
    for name, value in (("force_max_x", force_max_x), ("force_max_y", force_max_y)):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f"{name}={value} N must be a finite positive number")
    for name, value in (("steps_x", steps_x), ("steps_y", steps_y)):
        if not (isinstance(value, int) and value >= 1):
            raise ParameterError(f"{name}={value!r} must be an integer >= 1")
    shared = {"push_after": float(push_after), "push_duration": 0.1, "base_body": base_body_name(robot),
              **(params or {})}
    variants: dict[str, dict[str, Any]] = {DEFAULT_VARIANT: {}}
    if compare_timing is not None:
        from sim.campaigns.trial import STEP_TIMINGS

        if compare_timing not in STEP_TIMINGS[1:]:
            raise ParameterError(f"compare_timing={compare_timing!r} must be one of {STEP_TIMINGS[1:]}")
        if not (math.isfinite(timing_from) and 0.0 <= timing_from < push_after):
            raise ParameterError(f"timing_from={timing_from} s must be in [0, push_after={push_after} s)")
        compared: dict[str, Any] = {"step_timing": compare_timing}
        if timing_from > 0:
            compared["step_timing_from"] = float(timing_from)
        variants = {"adaptive": {"step_timing": "adaptive"}, compare_timing: compared}
    if duration is None:
        from sim.campaigns.trial import nominal_step_period

        t_nom = nominal_step_period(robot, "push", shared if controller == "walking" else {})
        latest_end = push_after + max(phases) * t_nom + shared["push_duration"]
        duration = round(latest_end + PUSH_RECOVERY_TIME, 3)
    return CampaignSpec(
        name="push-map" if compare_timing is None else f"push-map-timing-{compare_timing}",
        scenario="push",
        controller=controller,
        duration=duration,
        robot=robot,
        params=shared,
        grid={
            "force_x": {"start": -float(force_max_x), "stop": float(force_max_x), "num": steps_x},
            "force_y": {"start": 0.0, "stop": float(force_max_y), "num": steps_y},
            "phase": list(phases),
        },
        variants=variants,
        seeds=list(seeds),
    )


def base_body_name(robot: str) -> str:
    """The name of ``robot``'s floating base body (the body of its free-flyer joint, where pushes are applied:
    Bolt's ``base_link``, the G1's and H1's ``pelvis``)."""
    import pinocchio as pin

    from robots import load_robot

    model = load_robot(robot).pinocchio_model
    return next(frame.name for frame in model.frames
                if frame.parentJoint == 1 and frame.type == pin.FrameType.BODY)


def terrain(
    seeds: int | list[int] = TERRAIN_SEEDS,
    densities: tuple[float, ...] = (10.0,),
    controller: str = "walking",
    duration: float = TERRAIN_DURATION,
    params: dict[str, Any] | None = None,
    robot: str = "bolt",
) -> CampaignSpec:
    """Cluttered-ground trials (Bolt paper, section IV.C): one random box layout per seed.

    Args:
        seeds: number of terrain seeds (0..n-1) or the list of seeds.
        densities: box densities [1/m²] (paper: 10).
        controller: "walking" or "pd".
        duration: simulated time per trial [s].
        params: extra shared parameters (e.g. ``speed``, ``height_max``).
        robot: registered robot name.
    """
    if isinstance(seeds, int):
        if seeds < 1:
            raise ParameterError(f"seeds={seeds} must be >= 1 (number of terrain layouts)")
        seeds = list(range(seeds))
    return CampaignSpec(
        name="terrain",
        scenario="terrain",
        controller=controller,
        duration=duration,
        robot=robot,
        params=dict(params or {}),
        grid={"density": list(densities)},
        seeds=list(seeds),
    )


def obstacles(
    heights: tuple[float, ...] = OBSTACLE_HEIGHTS,
    trials: int = OBSTACLE_TRIALS,
    controller: str = "walking",
    duration: float | None = None,
    params: dict[str, Any] | None = None,
    robot: str = "h1",
) -> CampaignSpec:
    """Obstacle step-over trials (issue 15; the seed-000 thesis's Fig. 5.13): a box of each height across
    the path, ``trials`` seeds per height (each seed draws the box's distance, depth and friction).

    Args:
        heights: box heights [m] (each within the scenario's range, ``sim.scenarios.obstacle.HEIGHT_RANGE``).
        trials: seeds per height (0..trials-1).
        controller: "walking" or "pd".
        duration: simulated time per trial [s]; None = the scenario's default.
        params: extra shared parameters (scenario, runner or controller options, e.g. ``speed``).
        robot: registered robot name (its walking preset should enable ``[perception]``).
    """
    from sim.scenarios.obstacle import HEIGHT_RANGE

    if not (isinstance(trials, int) and not isinstance(trials, bool) and trials >= 1):
        raise ParameterError(f"trials={trials!r} must be an integer >= 1")
    heights = [float(h) for h in heights]
    if not heights:
        raise ParameterError("heights=[] must hold at least one box height [m]")
    for height in heights:
        if not (math.isfinite(height) and HEIGHT_RANGE[0] <= height <= HEIGHT_RANGE[1]):
            raise ParameterError(f"height={height} m must be in [{HEIGHT_RANGE[0]}, {HEIGHT_RANGE[1]}] m")
    return CampaignSpec(
        name="obstacles",
        scenario="obstacle",
        controller=controller,
        duration=duration,
        robot=robot,
        params=dict(params or {}),
        grid={"height": heights},
        seeds=list(range(trials)),
    )


BUILTIN_CAMPAIGNS = {"push-map": push_map, "terrain": terrain, "obstacles": obstacles}


def builtin_campaign(name: str, **options: Any) -> CampaignSpec:
    """A built-in campaign by name ("push-map", "terrain", "obstacles") with its options."""
    if name not in BUILTIN_CAMPAIGNS:
        raise ParameterError(f"campaign={name!r} is not built in (available: {sorted(BUILTIN_CAMPAIGNS)})")
    return BUILTIN_CAMPAIGNS[name](**options)
