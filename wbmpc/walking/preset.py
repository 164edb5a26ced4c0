"""Walking presets: every tuned number of a robot's walking pipeline, in one TOML file per robot.

``wbmpc/walking/presets/<robot>.toml`` has five sections, each loaded into a validated dataclass, and two
optional ones:

- ``[planner]``: the DCM step QP (:class:`sequencer.SequencerParams`);
- ``[ocp]`` (and ``[ocp.state_weights]``): the whole-body OCP (:class:`~wbmpc.walking.ocp.WalkingOCPConfig`);
- ``[controller]``: horizon, rates, touchdown handling, estimator gains
  (:class:`~wbmpc.walking.controller_config.WalkingControllerConfig`);
- ``[fall]``: fall thresholds (:class:`FallThresholds`);
- ``[command]``: the velocity commands the robot can follow (:class:`CommandRange`);
- ``[footstep_planner]`` (optional): which footstep planner the controller runs
  (:class:`FootstepPlannerChoice`): ``kind = "dcm"`` (default, the ``[planner]`` section) or ``"alip"``
  (the ALIP step-to-step NMPC of :mod:`sequencer.alip`, its parameters from a named ALIP preset with the
  fields of a ``[footstep_planner.alip]`` sub-table over them);
- ``[perception]`` (optional): the rangefinder array and terrain estimate that report obstacles in
  ``Measurement.obstacles`` (:class:`~wbmpc.walking.perception_config.PerceptionConfig`); a preset without
  it has no perception (``WalkingPreset.perception`` is None) unless an override addresses
  ``perception.*`` (the fields it does not set are the class's defaults, the H1's);
- ``[scenarios.<name>]`` (optional, one table per scenario of :mod:`sim.scenarios`): overrides (the keys
  below) that runs of that scenario apply before their own, for settings a robot needs in one kind of run
  only. The G1 walks with the ALIP planner, which avoids no obstacle; its ``[scenarios.obstacle]`` switches its
  obstacle runs to the DCM step QP with the negotiation and the clearance terms (off in its walking, whose
  recorded runs they would change at the rounding level). ``load_walking_preset(robot, scenario=name)``
  applies them (:func:`sim.runner.run_scenario` does) and :attr:`WalkingPreset.scenario_overrides` records
  them.

Overrides address a value as ``"section.name"`` (``"planner.l_max"``, ``"ocp.state_weights.joint_position"``),
a bare name addresses ``[controller]``; a whole section can be replaced by a dataclass instance
(``{"planner": SequencerParams(...)}``). ``wbmpc walk --set planner.l_max=0.25`` and
``run_scenario(..., **{"planner.l_max": 0.25})`` both go through :func:`load_walking_preset`.

A robot without a preset file cannot walk yet: :func:`load_walking_preset` refuses it with the list
of robots that can (docs/extending.md shows how to add one).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from robots.registry import check_robot_name
from sequencer.alip.params import PRESET_DIR as ALIP_PRESET_DIR
from sequencer.alip.params import AlipParams
from sequencer.params import SequencerParams
from sequencer.planner import VelocityCommand
from wbmpc.config import read_toml
from wbmpc.errors import ParameterError
from wbmpc.walking.controller_config import WalkingControllerConfig
from wbmpc.walking.ocp import StateWeights, WalkingOCPConfig
from wbmpc.walking.perception_config import PerceptionConfig

PRESET_DIR = Path(__file__).resolve().parent / "presets"

SECTIONS = ("planner", "ocp", "controller", "fall", "command")
OPTIONAL_SECTIONS = ("footstep_planner", "perception")
ALL_SECTIONS = SECTIONS + OPTIONAL_SECTIONS
SCENARIO_TABLE = "scenarios"
"""The preset file's optional table of per-scenario overrides (``[scenarios.<name>]``; not an override section)."""
PLANNER_KINDS = ("dcm", "alip")
ALIP_SOLVERS = ("sqp", "ipopt")
ANGULAR_MOMENTUM_SOURCES = ("exact", "approximate")


@dataclass(frozen=True)
class FallThresholds:
    """When a run counts as a fall (the simulation's fall detector reads them).

    Attributes:
        min_base_height: base height below which the robot has fallen [m].
        max_tilt_deg: largest angle between the base z axis and the vertical [deg].
    """

    min_base_height: float
    max_tilt_deg: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.min_base_height) and self.min_base_height >= 0.0):
            raise ParameterError(f"fall.min_base_height={self.min_base_height} m must be finite and >= 0")
        if not (math.isfinite(self.max_tilt_deg) and 0.0 < self.max_tilt_deg <= 180.0):
            raise ParameterError(f"fall.max_tilt_deg={self.max_tilt_deg} deg must be in (0, 180]")


def _interval(name: str, value) -> tuple[float, float]:
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ParameterError(f"command.{name}={value!r} must be a [min, max] pair") from None
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise ParameterError(f"command.{name}={value!r} must be finite with min <= max")
    return low, high


@dataclass(frozen=True)
class CommandRange:
    """The velocity commands (heading frame) a robot's walking preset can follow.

    Attributes:
        v_x: (min, max) forward velocity [m/s].
        v_y: (min, max) lateral velocity [m/s].
        yaw_rate: (min, max) yaw rate [rad/s].
        yaw_rate_note: why the yaw-rate range is what it is (said when a command is refused).
    """

    v_x: tuple[float, float]
    v_y: tuple[float, float]
    yaw_rate: tuple[float, float]
    yaw_rate_note: str = ""

    def __post_init__(self) -> None:
        for name in ("v_x", "v_y", "yaw_rate"):
            object.__setattr__(self, name, _interval(name, getattr(self, name)))

    def check(self, command: VelocityCommand, robot: str = "") -> None:
        """Raise ParameterError naming the first component of ``command`` outside its range."""
        units = {"v_x": "m/s", "v_y": "m/s", "yaw_rate": "rad/s"}
        for name, unit in units.items():
            value = getattr(command, name)
            low, high = getattr(self, name)
            if not low - 1e-12 <= value <= high + 1e-12:
                who = f" for robot {robot!r}" if robot else ""
                allowed = f"must be 0 {unit}" if low == high == 0.0 else f"must be in [{low}, {high}] {unit}"
                note = f" ({self.yaw_rate_note})" if name == "yaw_rate" and self.yaw_rate_note else ""
                raise ParameterError(f"velocity command {name}={value} {unit}{who} {allowed}{note}")


@dataclass(frozen=True)
class FootstepPlannerChoice:
    """Which footstep planner the walking controller runs (section ``[footstep_planner]``, optional).

    Attributes:
        kind: ``"dcm"`` (the DCM step QP with the preset's ``[planner]``, the default) or ``"alip"``
            (:class:`sequencer.alip.AlipFootstepPlanner` with :attr:`alip`).
        alip_preset: the ALIP parameters' source: a name of ``sequencer/presets/alip/`` (``"g1"``) or the path
            of an ALIP TOML file; ``""`` = the robot's name.
        alip_solver: the ALIP NMPC's solver, ``"sqp"`` (fast path) or ``"ipopt"`` (reference).
        angular_momentum: the ALIP planner's measured angular momentum about the stance contact:
            ``"exact"`` (the whole body's, :func:`wbmpc.walking.alip_state.contact_angular_momentum`) or
            ``"approximate"`` (the planner's eqs. 14-15 from the CoM velocity, without the I ω terms).
            The DCM planner reads neither.
        alip: the resolved ALIP parameters (kind ``"alip"``; None otherwise): the preset's, with the fields
            of ``[footstep_planner.alip]`` over them. Their ``double_support`` [s], unless that sub-table sets
            it, is the walking preset's ``[planner] double_support``: the ALIP preset describes the planner
            alone (0: the ALIP's instantaneous transfer of the support) while the contact schedule's double
            support is what the robot's whole-body OCP needs (the G1's flat feet: 0.1 s), the same whichever
            planner plans the steps.
    """

    kind: str = "dcm"
    alip_preset: str = ""
    alip_solver: str = "sqp"
    angular_momentum: str = "exact"
    alip: AlipParams | None = None

    def __post_init__(self) -> None:
        for name, allowed in (("kind", PLANNER_KINDS), ("alip_solver", ALIP_SOLVERS),
                              ("angular_momentum", ANGULAR_MOMENTUM_SOURCES)):
            if getattr(self, name) not in allowed:
                raise ParameterError(f"footstep_planner.{name}={getattr(self, name)!r} must be one of {allowed}")
        if not isinstance(self.alip_preset, str):
            raise ParameterError(f"footstep_planner.alip_preset={self.alip_preset!r} must be a preset name or a path")
        if self.alip is not None and not isinstance(self.alip, AlipParams):
            raise ParameterError(f"footstep_planner.alip must be AlipParams or None, got {type(self.alip).__name__}")


def _footstep_planner_from_table(table: Mapping[str, Any], robot: str,
                                 planner: SequencerParams) -> FootstepPlannerChoice:
    """The ``[footstep_planner]`` section, its ALIP parameters resolved (see :class:`FootstepPlannerChoice`)."""
    table = dict(table)
    alip_fields = table.pop("alip", None) or {}
    if not isinstance(alip_fields, Mapping):
        raise ParameterError(f"[footstep_planner] alip={alip_fields!r} must be a table of ALIP parameters")
    allowed = [f.name for f in dataclasses.fields(FootstepPlannerChoice) if f.name != "alip"]
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ParameterError(f"[footstep_planner] has no field {unknown} (allowed: {allowed + ['alip']})")
    choice = FootstepPlannerChoice(**table)
    if choice.kind != "alip":
        return choice
    source = choice.alip_preset or robot
    if source.endswith(".toml") or "/" in source:
        base = AlipParams.from_toml(source)
    else:
        available = sorted(p.stem for p in ALIP_PRESET_DIR.glob("*.toml"))
        if source not in available:
            raise ParameterError(f"footstep_planner.alip_preset={source!r}: no ALIP preset of that name (available: "
                                 f"{available}); give a name or the path of an ALIP TOML file")
        base = AlipParams.preset(source)
    fields = {"double_support": planner.double_support, **dict(alip_fields)}
    try:
        params = AlipParams.from_dict({**base.to_dict(), **fields}, source=f"[footstep_planner.alip] over {source!r}")
    except ParameterError as err:
        raise ParameterError(f"[footstep_planner.alip] over the ALIP preset {source!r}: {err}") from None
    return dataclasses.replace(choice, alip_preset=source, alip=params)


@dataclass(frozen=True)
class WalkingPreset:
    """A robot's walking pipeline, all of its tuned numbers (see the module docstring)."""

    robot: str
    planner: SequencerParams
    ocp: WalkingOCPConfig
    controller: WalkingControllerConfig
    fall: FallThresholds
    command: CommandRange
    source: str = ""
    footstep_planner: FootstepPlannerChoice = FootstepPlannerChoice()
    perception: PerceptionConfig | None = None
    scenario: str = ""
    scenario_overrides: tuple[tuple[str, Any], ...] = ()
    """The ``[scenarios.<scenario>]`` overrides of the file that were applied, as (key, value) pairs in file
    order (empty: none; ``scenario`` is the scenario the preset was loaded for, "" for none)."""

    @property
    def planner_params(self) -> SequencerParams | AlipParams:
        """The parameters of the footstep planner the controller runs: ``[planner]`` (kind "dcm") or the
        resolved ALIP parameters (kind "alip")."""
        if self.footstep_planner.kind == "dcm":
            return self.planner
        if self.footstep_planner.alip is None:
            raise ParameterError("footstep_planner.kind='alip' without its resolved ALIP parameters "
                                 "(load the preset with load_walking_preset)")
        return self.footstep_planner.alip

    @property
    def omega(self) -> float:
        """The run's pendulum frequency sqrt(g / z) [1/s] (the running planner's, the logged DCM's)."""
        return self.planner_params.omega

    @property
    def step_period(self) -> float:
        """The running planner's nominal step period [s] (DCM ``t_nom``, ALIP ``t_des``)."""
        params = self.planner_params
        return params.t_nom if isinstance(params, SequencerParams) else params.t_des


def available_walking_presets() -> list[str]:
    """Robots that have a walking preset."""
    return sorted(path.stem for path in PRESET_DIR.glob("*.toml"))


def _build(cls, table: Mapping[str, Any], section: str):
    allowed = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ParameterError(f"[{section}] has no field {unknown} (allowed: {allowed})")
    try:
        return cls(**table)
    except TypeError as err:  # a required field missing
        raise ParameterError(f"[{section}]: {err}") from None


def _tuples(value):
    """TOML arrays (nested lists) as tuples, the form the frozen dataclasses hold."""
    return tuple(_tuples(v) for v in value) if isinstance(value, (list, tuple)) else value


def _ocp_from_table(table: Mapping[str, Any]) -> WalkingOCPConfig:
    table = dict(table)
    weights = table.pop("state_weights", {})
    if isinstance(weights, Mapping):
        weights = _build(StateWeights, {k: _tuples(v) for k, v in weights.items()}, "ocp.state_weights")
    if "baumgarte_gains" in table:
        table["baumgarte_gains"] = tuple(table["baumgarte_gains"])
    return _build(WalkingOCPConfig, {**table, "state_weights": weights}, "ocp")


def _controller_from_table(table: Mapping[str, Any]) -> WalkingControllerConfig:
    table = dict(table)
    if "mpc_failure_times" in table:
        table["mpc_failure_times"] = tuple(float(t) for t in table["mpc_failure_times"])
    return _build(WalkingControllerConfig, table, "controller")


_BUILDERS = {
    "planner": lambda table: SequencerParams.from_dict(table, source="[planner]"),
    "ocp": _ocp_from_table,
    "controller": _controller_from_table,
    "fall": lambda table: _build(FallThresholds, table, "fall"),
    "command": lambda table: _build(CommandRange, table, "command"),
}


def _as_table(value) -> dict[str, Any]:
    """A section's values as a plain (nested) table."""
    if dataclasses.is_dataclass(value):
        return {f.name: _as_table(getattr(value, f.name)) if dataclasses.is_dataclass(getattr(value, f.name))
                else getattr(value, f.name) for f in dataclasses.fields(value)}
    return dict(value)


def _apply_override(tables: dict[str, dict[str, Any]], key: str, value: Any) -> None:
    parts = key.split(".")
    if parts[0] not in ALL_SECTIONS:
        parts = ["controller", *parts]
    section, path = parts[0], parts[1:]
    if not path:  # a whole section: a dataclass instance or a table of fields
        tables[section] = _as_table(value) if dataclasses.is_dataclass(value) else {**tables[section], **dict(value)}
        return
    table = tables[section]
    for name in path[:-1]:
        if not isinstance(table.get(name), dict):
            raise ParameterError(f"override {key!r}: [{section}] has no sub-table {name!r}")
        table = table[name]
    table[path[-1]] = value


def load_walking_preset(robot: str, overrides: Mapping[str, Any] | None = None,
                        path: str | Path | None = None, scenario: str | None = None) -> WalkingPreset:
    """The walking preset of ``robot`` with ``overrides`` applied (see the module docstring).

    Args:
        robot: a registered robot name.
        overrides: values replacing the file's (``"section.field"`` keys, bare controller fields,
            whole sections).
        path: a preset file to read instead of ``wbmpc/walking/presets/<robot>.toml`` (a robot
            of your own, or a variant of a preset).
        scenario: the scenario of the run (a name of :mod:`sim.scenarios`): the file's
            ``[scenarios.<scenario>]`` overrides, if it has them, go before ``overrides``; None: none.

    Raises:
        ParameterError: the robot has no walking preset (the message lists those that do), the
            file is not valid, an override names no field, or a value is out of its range.
    """
    check_robot_name(robot)
    available = available_walking_presets()
    if path is None and robot not in available:
        raise ParameterError(
            f"robot={robot!r} has no walking preset yet (robots that walk: {', '.join(available)}); "
            f"add wbmpc/walking/presets/{robot}.toml to make it walk (docs/extending.md)"
        )
    path = PRESET_DIR / f"{robot}.toml" if path is None else Path(path)
    data = read_toml(path, "walking preset")
    missing = [s for s in SECTIONS if s not in data]
    extra = sorted(set(data) - set(ALL_SECTIONS) - {SCENARIO_TABLE})
    if missing or extra:
        raise ParameterError(f"walking preset {str(path)!r}: sections must be {list(SECTIONS)} and optionally "
                             f"{list(OPTIONAL_SECTIONS)} and [{SCENARIO_TABLE}.<name>] (missing {missing}, "
                             f"unknown {extra})")
    by_scenario = scenario_override_tables(data.get(SCENARIO_TABLE, {}), path)
    applied = tuple(by_scenario.get(scenario, {}).items()) if scenario is not None else ()
    if applied:  # the file's own overrides alone first, so that an error in them says where it is
        try:
            _preset_from_tables(robot, path, data, applied)
        except ParameterError as err:
            raise ParameterError(f"walking preset {str(path)!r} [{SCENARIO_TABLE}.{scenario}]: {err}") from None
    preset = _preset_from_tables(robot, path, data, (*applied, *(overrides or {}).items()))
    return dataclasses.replace(preset, scenario=scenario or "", scenario_overrides=applied)


def _preset_from_tables(robot: str, path: Path, data: Mapping[str, Any], overrides) -> WalkingPreset:
    """The preset of the file's ``data`` with the ``(key, value)`` pairs of ``overrides`` applied in order."""
    tables = {section: _as_table(data[section]) for section in SECTIONS}
    tables["footstep_planner"] = {"alip": {}, **_as_table(data.get("footstep_planner", {}))}
    tables["perception"] = _as_table(data.get("perception", {}))
    has_perception = "perception" in data
    for key, value in overrides:
        _apply_override(tables, key, value)
        has_perception = has_perception or key.split(".", 1)[0] == "perception"
    sections = {section: _BUILDERS[section](tables[section]) for section in SECTIONS}
    footstep_planner = _footstep_planner_from_table(tables["footstep_planner"], robot, sections["planner"])
    perception = _perception_from_table(tables["perception"]) if has_perception else None
    return WalkingPreset(robot=robot, source=str(path), footstep_planner=footstep_planner, perception=perception,
                         **sections)


def scenario_override_tables(table: Any, source: str | Path = "") -> dict[str, dict[str, Any]]:
    """A preset file's ``[scenarios]`` table as {scenario: {"section.field": value}} (nested tables flattened to
    dotted keys, in file order).

    Raises:
        ParameterError: the table is not a table of tables, or a key addresses nothing a preset override can
            (a section, ``section.field`` or a controller field).
    """
    where = f"walking preset {str(source)!r}: " if source else ""
    if not isinstance(table, Mapping) or not all(isinstance(v, Mapping) for v in table.values()):
        raise ParameterError(f"{where}[{SCENARIO_TABLE}] must hold one table of overrides per scenario, "
                             f"[{SCENARIO_TABLE}.<name>], got {table!r}")

    def flat(values: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key, value in values.items():
            if isinstance(value, Mapping):
                out.update(flat(value, f"{prefix}{key}."))
            else:
                out[f"{prefix}{key}"] = value
        return out

    tables = {name: flat(values) for name, values in table.items()}
    for name, values in tables.items():
        for key in values:
            if "." not in key or key.split(".", 1)[0] not in ALL_SECTIONS:
                raise ParameterError(f"{where}[{SCENARIO_TABLE}.{name}] key {key!r} must be 'section.field' "
                                     f"(sections {list(ALL_SECTIONS)})")
    return tables


def _perception_from_table(table: Mapping[str, Any]) -> PerceptionConfig:
    table = {key: _tuples(value) for key, value in table.items()}
    return _build(PerceptionConfig, table, "perception")


def preset_override_keys() -> set[str]:
    """Names accepted as overrides besides dotted ``section.field`` keys: the sections and the
    controller's fields."""
    return set(ALL_SECTIONS) | {f.name for f in dataclasses.fields(WalkingControllerConfig)}


def is_preset_override(key: str) -> bool:
    """True when ``key`` addresses the walking preset (a section, ``section.field`` or a controller field)."""
    return key in preset_override_keys() or key.split(".", 1)[0] in ALL_SECTIONS
