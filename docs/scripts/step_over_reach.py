"""Can a humanoid's legs step over its obstacle campaign's boxes? The highest clearance a crossing swing can reach
over the box's edges, from Pinocchio kinematics and SLSQP (issue 15; docs/robots.md, "Can the H1 step over 40 cm?",
"Can the G1 step over 32 cm?").

    PYTHONPATH=. python docs/scripts/step_over_reach.py [--robot h1|g1] [--heights 0.1 0.2 0.3 0.4 0.5]
        [--margin M] [--hip-extension-cap 0.5] [--table-height 0.4] [--self-collision] [--body-clearance H]
        [--poses H T ...] [--plot docs/figures/<robot>_step_over_reach.png]

Every number is the robot's (``robots.<robot>``: its model, torque limits, sole spheres and sole size) or its
walking preset's (``wbmpc/walking/presets/<robot>.toml``, the [planner], [ocp] and [fall] sections), so the script
follows them; the H1's figures in brackets below.

Geometry (the preset's rules): the box's near edge at x = 0, its far edge at x = depth; the clearance terms act over
the box grown by ocp.obstacle_footprint_margin (x in [-0.03, depth + 0.03] m). Lead swing: the stance sole flat on
the floor, its toe ``--margin`` before the near edge (planner.obstacle_margin, 0.08 m). Trailing swing: the stance
sole flat, its heel ``--margin`` beyond the far edge. The swing foot's leading point is at the grown footprint's
edge: its toe at x = -0.03 ("near": the sole entering it) or its heel at x = depth + 0.03 ("far": leaving it).

Maximised: t, with the toe and heel points of the swing sole (ocp.obstacle_sole_points) and the swing knee frame
(ocp.obstacle_shank_frames, on the knee joint) at least t high; the preset asks t = h + ocp.obstacle_clearance_margin
(0.05 m). Free: the stance leg's hip pitch, knee and ankle (pitch) and the swing leg's hip pitch, knee, ankle (and,
in the "abducted" and "turned" variants, the swing hip's roll, then also its yaw); the stance hip roll and yaw, the
torso or waist and the arms stay at the standing posture, so the pelvis stays level in roll and follows from the
stance leg. Subject to the joint limits, the pelvis pitch within +-15 deg, its height >= fall.min_base_height
(0.60 m), no point of either leg's hip-knee-ankle segments (lines between the joint origins) inside the box (the only
place the box's height enters: each curve is flat in h unless that binds), and the sagittal statics of single
support: the stance sole's 6D wrench balancing gravity (the floating-base rows of g(q) = J_c^T f,
``pinocchio.computeGeneralizedGravity`` and the stance sole's LOCAL Jacobian), every leg joint's torque g - J_c^T f
within ``robot.torque_limit``, and the centre of pressure within the sole along x (between the MuJoCo sole spheres'
centres, ``SOLE_SPHERES_IN_ANKLE``: x in [-0.1075, 0.0725] m of the H1's sole frame, its ankle's 40 N·m bounding it
7.9 cm ahead of the ankle). The H1's lateral balance is not checked: it cannot hold any single-support pose
statically (no ankle roll: with the pelvis rolled up to 30 deg the lateral CoP stays several centimetres outside the
sole's +-3.5 cm, printed), it balances sideways dynamically. A robot with an ankle roll (the G1) takes the sole's
roll moment through that joint, within its torque limit: its stance hip roll and ankle roll are free too, the pelvis
is held level (roll 0, an equality), and the lateral centre of pressure is kept within +-sole_size[1] / 2 (the G1:
+-0.025 m); the swing ankle roll stays at 0. "joint limits only" drops the statics.

``--self-collision`` also keeps the swing leg's links off the rest of the robot (the pelvis, torso, head and the
stance leg; the arms, which the OCP moves, left out) in the simulation's MuJoCo model
(``build_mujoco_spec(link_collisions=True)``: the links' collision meshes as convex hulls, the sole spheres);
``--body-clearance H`` prints the first table's poses re-solved at the box height H with the knee frame's height over
the box's top and each leg link's signed distance to the box [m] in that model; ``--poses H T ...`` the sagittal
cases' poses nearest the standing posture (least squares of the free joints' angles) with the sole points at T and
the knee frame at the preset's shank margin over a box H high, the same numbers.

Each maximisation is multi-started: five standing, folded and stretched leg poses and ``--starts`` random ones at
the first height, the previous height's optimum and two random ones after, then back down from the next height's.
About 30 s on one core for the H1, 2 min for the G1 with ``--self-collision``. Prints the tables of docs/robots.md
and writes the figure.
"""

from __future__ import annotations

import argparse
import importlib
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.walking.preset import load_walking_preset

PITCH_MAX = np.radians(15.0)  # pelvis pitch bound
SWING, STANCE = "left", "right"
# Per robot: each leg joint's role -> the model's joint name after the side prefix ("left_"), in the order of
# VARIABLES ("stance hip_yaw", ..., "swing ankle_roll").
LEG_JOINTS = {
    "h1": {"hip_yaw": "hip_yaw", "hip_roll": "hip_roll", "hip_pitch": "hip_pitch", "knee": "knee", "ankle": "ankle"},
    "g1": {"hip_yaw": "hip_yaw_joint", "hip_roll": "hip_roll_joint", "hip_pitch": "hip_pitch_joint",
           "knee": "knee_joint", "ankle": "ankle_pitch_joint", "ankle_roll": "ankle_roll_joint"},
}
SAGITTAL = tuple((role, joint) for role in ("stance", "swing") for joint in ("hip_pitch", "knee", "ankle"))
# With an ankle roll (the G1) the stance sole's roll moment goes through that joint, within its torque limit: the
# stance hip roll and ankle roll are free too, to bring the centre of mass over the sole with the pelvis level.
BALANCE = (("stance", "hip_roll"), ("stance", "ankle_roll"))
FREEDOMS = {  # the free (role, joint) pairs of VARIABLES besides SAGITTAL (and BALANCE)
    "sagittal": (),
    "abducted": (("swing", "hip_roll"),),   # + the swing hip roll
    "turned": (("swing", "hip_roll"), ("swing", "hip_yaw")),  # + the swing hip roll and yaw
}
# Initial guesses besides the random ones (stance hip pitch, knee, ankle, swing hip pitch, knee, ankle [rad]): the
# standing legs, the swing leg folded forward (the lead's near edge), reaching forward (its far edge), folded back
# under the body (the trailing's far edge), stretched back with the knee bent (the hip at its extension limit).
# The G1's flex further (hip pitch to -2.53 rad, knee to 2.88 rad; the H1's -1.57 and 2.05).
SEEDS = {
    "h1": (
        (-0.177, 0.6, -0.423, -0.177, 0.6, -0.423),
        (-0.3, 0.0, 0.1, -1.57, 2.05, -0.7),
        (0.27, 0.0, 0.0, -1.57, 1.3, 0.5),
        (0.5, 0.0, -0.17, 0.0, 2.05, 0.5),
        (-0.2, 0.0, 0.0, 1.57, 1.5, 0.0),
    ),
    "g1": (
        (-0.312, 0.669, -0.357, -0.312, 0.669, -0.357),
        (-0.3, 0.0, 0.1, -2.0, 2.6, -0.7),
        (0.27, 0.0, 0.0, -1.57, 1.3, 0.5),
        (0.5, 0.0, -0.17, 0.0, 2.6, 0.5),
        (-0.2, 0.0, 0.0, 1.57, 1.5, 0.0),
    ),
}
# Box depths [m] (shallow, deep): the deep one at the edges next to the stance foot, both at the others. The H1's;
# the G1's shallow one is the H1's x 0.80 (its leg length ratio), its deep one the deepest box its crossing step
# crosses (0.52 - 0.337 m, planner.obstacle_step_length_max less the margins and the sole).
DEPTHS = {"h1": (0.15, 0.25), "g1": (0.12, 0.18)}


class Reach:
    """A robot's legs with the stance sole fixed flat on the floor, and the numbers of its walking preset.

    Attributes (lengths [m] in the sole frame or the world, angles [rad]): toe, heel (the swing sole's clearance
    points), clearance (t - h asked), shank_margin, grown (the box's footprint margin), sole_front, sole_rear,
    margin (stance sole to the box), pelvis_min, apex_cap, apex_margin, support (the CoP's x range in the sole frame),
    half_width (the sole spheres' largest |y|), lateral (an ankle roll: the lateral statics checked),
    lateral_support (the CoP's |y| bound), variables ("stance hip_pitch", ...), freedoms (their free indices per
    variant), seeds, depths, bodies (the ``Bodies`` of ``self_collision``, or None).
    """

    def __init__(self, name: str = "h1", self_collision: bool = False) -> None:
        self.name = name
        self.robot = load_robot(name)
        module = importlib.import_module(f"robots.{name}")
        preset = self.preset = load_walking_preset(name)
        self.toe, self.heel = (np.array(point) for point in preset.ocp.obstacle_sole_points)
        self.clearance = preset.ocp.obstacle_clearance_margin
        self.shank_margin = preset.ocp.obstacle_shank_margin
        self.grown = preset.ocp.obstacle_footprint_margin
        self.sole_front, self.sole_rear = preset.planner.sole_front, preset.planner.sole_rear
        self.margin = preset.planner.obstacle_margin
        self.pelvis_min = preset.fall.min_base_height
        self.apex_cap = preset.ocp.obstacle_apex_height_max
        self.apex_margin = preset.ocp.obstacle_apex_margin
        spheres = np.array(module.SOLE_SPHERES_IN_ANKLE)  # the MuJoCo sole spheres' centres, ankle link frame
        center = module.SOLE_CENTER_IN_ANKLE
        # the heel and toe spheres along the sole frame's x, and their largest |y|
        self.support = (spheres[:, 0].min() - center[0], spheres[:, 0].max() - center[0])
        self.half_width = float(np.abs(spheres[:, 1]).max())
        joints = LEG_JOINTS[name]
        self.variables = tuple(f"{role} {joint}" for role in ("stance", "swing") for joint in joints)
        self.lateral = "ankle_roll" in joints  # the lateral statics checked (with BALANCE free)
        self.lateral_support = 0.5 * self.robot.sole_size[1]  # [m] the CoP's |y| bound in the sole frame
        index = lambda pairs: tuple(sorted(self.variables.index(f"{role} {joint}") for role, joint in pairs))
        self.sagittal = index(SAGITTAL)
        self.freedoms = {freedom: index(SAGITTAL + (BALANCE if self.lateral else ()) + extra)
                         for freedom, extra in FREEDOMS.items()}
        self.seeds, self.depths = SEEDS[name], DEPTHS[name]
        self.hip_pitch = self.variables.index("swing hip_pitch")

        model = self.model = self.robot.pinocchio_model
        self.data = model.createData()
        joint = lambda side, role: model.joints[model.getJointId(f"{side}_{joints[role]}")]
        self.iq = np.array([joint(side, role).idx_q for side in (STANCE, SWING) for role in joints])
        self.lower = model.lowerPositionLimit[self.iq].copy()
        self.upper = model.upperPositionLimit[self.iq].copy()
        self.stance_sole = model.getFrameId(self.robot.foot_frames[STANCE])
        self.swing_sole = model.getFrameId(self.robot.foot_frames[SWING])
        self.chains = [[model.getJointId(f"{side}_{joints[role]}") for role in ("hip_pitch", "knee", "ankle")]
                       for side in (SWING, STANCE)]
        shank = dict((side, frame) for side, frame in preset.ocp.obstacle_shank_frames)[SWING]
        frame = model.frames[model.getFrameId(shank)]
        if frame.parentJoint != self.chains[0][1] or not frame.placement.isIdentity():
            raise ParameterError(f"ocp.obstacle_shank_frames: {shank!r} is not on the {SWING} knee joint")
        self.leg_v = np.array([joint(side, role).idx_v - 6 for side in (STANCE, SWING) for role in joints])
        self.q0 = np.array(self.robot.q_reference)
        self.q0[:7] = [0, 0, 0, 0, 0, 0, 1]
        self._last = (None, None)
        self.bodies = Bodies(self) if self_collision else None

    def full(self, seed) -> np.ndarray:
        """All VARIABLES [rad] from a seed (the sagittal ones), the others 0."""
        x = np.zeros(len(self.variables))
        x[list(self.sagittal)] = seed
        return x

    def pose(self, x: np.ndarray, stance_x: float) -> dict:
        """World points [m] of leg angles x (VARIABLES order) with the stance sole flat at (stance_x, its y, 0)."""
        key = (x.tobytes(), stance_x)
        if self._last[0] == key:
            return self._last[1]
        model, data = self.model, self.data
        q = self.q0.copy()
        q[self.iq] = x
        pin.forwardKinematics(model, data, q)
        base_sole = pin.updateFramePlacement(model, data, self.stance_sole)
        world_base = pin.SE3(np.eye(3), np.array([stance_x, base_sole.translation[1], 0.0])) * base_sole.inverse()
        q[:7] = pin.SE3ToXYZQUAT(world_base)
        rotation, origin = world_base.rotation, world_base.translation
        sole = world_base * pin.updateFramePlacement(model, data, self.swing_sole)
        s = np.linspace(0.0, 1.0, 6)[:, None]
        segments = []
        for chain in self.chains:
            hip, knee, ankle = (data.oMi[j].translation for j in chain)
            segments += [hip + s * (knee - hip), knee + s * (ankle - knee)]
        legs = np.vstack(segments) @ rotation.T + origin
        out = {"q": q, "toe": sole.act(self.toe), "heel": sole.act(self.heel), "knee": legs[5], "legs": legs,
               "pitch": float(np.arctan2(-rotation[2, 0], rotation[0, 0])),
               "roll": float(np.arctan2(rotation[2, 1], rotation[2, 2])), "pelvis_z": float(origin[2])}
        self._last = (key, out)
        return out

    def statics(self, q: np.ndarray, lateral: bool = False) -> tuple[np.ndarray, float]:
        """Joint torques [N·m] (nu,) holding the robot's weight on the stance sole alone, and the centre of
        pressure's x in the stance sole frame [m] (its y with ``lateral``)."""
        tau, cop = self.statics_xy(q)
        return tau, cop[1] if lateral else cop[0]

    def statics_xy(self, q: np.ndarray) -> tuple[np.ndarray, tuple[float, float]]:
        """Joint torques [N·m] (nu,) holding the robot's weight on the stance sole alone, and the centre of
        pressure (x, y) in the stance sole frame [m]."""
        g = pin.computeGeneralizedGravity(self.model, self.data, q)
        jacobian = pin.computeFrameJacobian(self.model, self.data, q, self.stance_sole, pin.LOCAL)
        wrench = np.linalg.solve(jacobian[:, :6].T, g[:6])
        tau = g[6:] - jacobian[:, 6:].T @ wrench
        return tau, (float(-wrench[4] / wrench[2]), float(wrench[3] / wrench[2]))


class Bodies:
    """The swing leg's collision geoms against the rest of the robot, the arms left out (the OCP moves them), in the
    simulation's MuJoCo model (``build_mujoco_spec(link_collisions=True)``: meshes as convex hulls, the sole
    spheres); the pairs less than 1 cm apart standing (the hip's own housings) are not checked."""

    def __init__(self, reach: Reach, distance_max: float = 0.05) -> None:
        import mujoco

        from robots.mujoco_model import build_mujoco_spec

        self.mujoco, self.distance_max = mujoco, distance_max
        model = self.model = build_mujoco_spec(reach.robot, link_collisions=True).compile()
        self.data = mujoco.MjData(model)

        def below(joint_names) -> set[int]:  # the bodies of these joints and their descendants
            roots = {model.jnt_bodyid[model.joint(name).id] for name in joint_names}
            out = set()
            for body in range(1, model.nbody):
                ancestor = body
                while ancestor and ancestor not in roots:
                    ancestor = model.body_parentid[ancestor]
                if ancestor:
                    out.add(body)
            return out

        leg = below([f"{SWING}_{name}" for name in LEG_JOINTS[reach.name].values()])
        arms = below([name for name in reach.robot.actuated_joint_names
                      if any(part in name for part in ("shoulder", "elbow", "wrist"))])
        geoms = [g for g in range(model.ngeom) if model.geom_contype[g] and model.geom_bodyid[g] != 0]
        swing = [g for g in geoms if model.geom_bodyid[g] in leg]
        others = [g for g in geoms if model.geom_bodyid[g] not in leg | arms]
        self.pairs = []
        self.set(reach.robot.q_reference)
        for a in swing:
            for b in others:
                if mujoco.mj_geomDistance(model, self.data, a, b, 0.01, None) >= 0.01:
                    self.pairs.append((a, b))

    def set(self, q: np.ndarray) -> None:
        """The Pinocchio configuration q (free flyer's quaternion x, y, z, w) to MuJoCo's kinematics."""
        self.data.qpos[:] = np.r_[q[:3], q[6], q[3:6], q[7:]]
        self.mujoco.mj_kinematics(self.model, self.data)

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Signed distances [m] of the checked pairs (capped at distance_max; negative: penetrating)."""
        self.set(q)
        distance = self.mujoco.mj_geomDistance
        return np.array([distance(self.model, self.data, a, b, self.distance_max, None) for a, b in self.pairs])

    def nearest(self, q: np.ndarray) -> tuple[str, str, float]:
        """The nearest pair's bodies and signed distance [m]."""
        d = self.distances(q)
        a, b = self.pairs[int(np.argmin(d))]
        name = lambda g: self.model.body(self.model.geom_bodyid[g]).name
        return name(a), name(b), float(d.min())


@dataclass(frozen=True)
class Case:
    swing: str            # "lead" | "trailing"
    edge: str             # "near" | "far"
    depth: float          # [m]
    freedom: str = "sagittal"
    static: bool = True   # False: the joint limits only
    knee: bool = True     # the swing knee at least t high too
    gating: bool = False  # only the sole points over the grown box held at t (the OCP's rule), else the whole sole
    hip_extension: float | None = None  # swing hip pitch upper bound [rad] (None: its joint limit)
    margin: float | None = None         # stance sole to the box [m] (None: the preset's planner.obstacle_margin)

    def stance_x(self, reach: Reach) -> float:
        """The stance sole frame's x [m] (the box's near edge at 0)."""
        margin = reach.margin if self.margin is None else self.margin
        return -margin - reach.sole_front if self.swing == "lead" else self.depth + margin + reach.sole_rear


@dataclass
class Result:
    case: Case
    height: float
    t: float
    x: np.ndarray         # all VARIABLES
    pose: dict
    tau: np.ndarray
    cop: float
    active: list[str]


def _cm(length: float) -> str:
    """A length [m] to the centimetre, or to the millimetre where that is not exact (the G1's scaled margins)."""
    return f"{length:.2f}" if abs(length - round(length, 2)) < 1e-9 else f"{length:.3f}"


def _outside(a: np.ndarray, tau: float = 0.005) -> np.ndarray:
    """Smooth max over the last axis (log-sum-exp minus its largest excess): >= 0 only where the true max is."""
    top = a.max(axis=-1, keepdims=True)
    return (top + tau * np.log(np.exp((a - top) / tau).sum(axis=-1, keepdims=True)))[..., 0] - tau * np.log(a.shape[-1])


def solve(reach: Reach, case: Case, height: float, inits: list[np.ndarray], fixed_t: float | None = None
          ) -> Result | None:
    """max t for a box ``height`` high [m] from each initial guess (all VARIABLES, or the six of a seed); None if no
    start ends feasible. With ``fixed_t`` [m]: the pose nearest the standing posture (least squares of the free
    joints' angles) with the sole points at fixed_t and the knee at the preset's shank margin over the box."""
    stance_x, depth, grown = case.stance_x(reach), case.depth, reach.grown
    free = np.array(reach.freedoms[case.freedom])
    n = free.size
    lower, upper = reach.lower[free], reach.upper[free].copy()
    if case.hip_extension is not None:
        upper[list(free).index(reach.hip_pitch)] = min(reach.upper[reach.hip_pitch], case.hip_extension)
    limit = reach.robot.torque_limit[reach.leg_v]
    support = reach.support

    def full(z: np.ndarray) -> np.ndarray:
        x = np.zeros(len(reach.variables))
        x[free] = z[:n]
        return x

    def inequalities(z: np.ndarray) -> np.ndarray:
        p, t = reach.pose(full(z), stance_x), z[n]
        lead_point, other = ("toe", "heel") if case.edge == "near" else ("heel", "toe")
        rows = [PITCH_MAX - abs(p["pitch"]), p["pelvis_z"] - reach.pelvis_min, p[lead_point][2] - t]
        if case.gating:  # the other point above t, or outside the grown footprint
            x_other = p[other][0]
            rows.append(_outside(np.array([-grown - x_other, x_other - depth - grown, p[other][2] - t])))
        else:
            rows.append(p[other][2] - t)
        if case.knee:
            rows.append(p["knee"][2] - (t if fixed_t is None else height + reach.shank_margin))
        legs = p["legs"]
        rows += list(_outside(np.stack([-legs[:, 0], legs[:, 0] - depth, legs[:, 2] - height], axis=1)))
        if case.static:
            tau, (cop, cop_y) = reach.statics_xy(p["q"])
            rows += list(1.0 - np.abs(tau[reach.leg_v]) / limit) + [cop - support[0], support[1] - cop]
            if reach.lateral:
                rows.append(reach.lateral_support - abs(cop_y))
        if reach.bodies is not None:
            rows += list(reach.bodies.distances(p["q"]))
        return np.array(rows)

    def at_edge(z: np.ndarray) -> np.ndarray:
        """The swing foot's leading point at the grown box's edge [m] (and, with BALANCE free, the pelvis level
        [rad])."""
        p = reach.pose(full(z), stance_x)
        edge = [p["toe"][0] + grown if case.edge == "near" else p["heel"][0] - depth - grown]
        return np.array(edge + ([p["roll"]] if reach.lateral else []))

    bounds = list(zip(lower, upper)) + [(-1.0, 2.0) if fixed_t is None else (fixed_t, fixed_t)]
    if fixed_t is None:
        objective = lambda z: -z[n]
    else:
        standing = reach.q0[reach.iq][free]
        objective = lambda z: float(np.sum((z[:n] - standing) ** 2))
    best = None
    for init in inits:
        x0 = np.asarray(init, dtype=float)
        if x0.size == len(reach.seeds[0]):  # a seed: the sagittal joints
            x0 = reach.full(init)
        z0 = np.clip(x0[free], lower, upper)
        p = reach.pose(full(z0), stance_x)
        z0 = np.r_[z0, min(p["toe"][2], p["heel"][2], p["knee"][2] if case.knee else np.inf)]  # a feasible t
        if fixed_t is not None:
            z0[n] = fixed_t
        r = minimize(objective, z0, method="SLSQP", bounds=bounds, options={"maxiter": 200, "ftol": 1e-8},
                     constraints=[{"type": "ineq", "fun": inequalities}, {"type": "eq", "fun": at_edge}])
        if inequalities(r.x).min() > -1e-4 and abs(at_edge(r.x)).max() < 1e-4 and (
                best is None or objective(r.x) < objective(best)):
            best = r.x
    if best is None:
        return None
    x = full(best)
    p = reach.pose(x, stance_x)
    tau, (cop, cop_y) = reach.statics_xy(p["q"])
    active = [reach.variables[i] + (" min" if v - lo < 1e-3 else " max") for i, v, lo, hi in
              zip(free, best[:n], lower, upper) if v - lo < 1e-3 or hi - v < 1e-3]
    if abs(abs(p["pitch"]) - PITCH_MAX) < 1e-3:
        active.append(f"pelvis pitch {np.degrees(p['pitch']):+.0f} deg")
    if case.static:
        if cop - support[0] < 1e-3:
            active.append("CoP at the heel")
        if support[1] - cop < 1e-3:
            active.append("CoP at the toe")
        if reach.lateral and reach.lateral_support - abs(cop_y) < 1e-3:
            active.append("CoP at the side")
        names = reach.robot.actuated_joint_names
        active += [f"{names[i]} torque" for i in reach.leg_v if abs(tau[i]) / reach.robot.torque_limit[i] > 0.999]
    if case.knee and fixed_t is None and p["knee"][2] - best[n] < 1e-3:
        active.append("knee height")
    if reach.bodies is not None and (nearest := reach.bodies.nearest(p["q"]))[2] < 1e-3:
        active.append(f"{nearest[0]} on {nearest[1]}")
    return Result(case, height, float(best[n]), x, p, tau, cop, active)


def series(reach: Reach, case: Case, heights, starts: int, rng: np.random.Generator) -> list[Result | None]:
    """The case over ascending heights [m], each warm-started from the previous optimum; then back down, each from
    the next height's (feasible there: a lower box only loosens the collision rows)."""
    out, previous = [], None
    for k, height in enumerate(heights):
        if k == 0 or previous is None:
            inits = list(reach.seeds) + [rng.uniform(reach.lower, reach.upper) for _ in range(starts)]
        else:
            inits = [previous.x] + [rng.uniform(reach.lower, reach.upper) for _ in range(2)]
        result = solve(reach, case, height, inits)
        out.append(result)
        previous = result or previous
    for k in range(len(heights) - 2, -1, -1):
        if out[k + 1] is not None and (out[k] is None or out[k + 1].t > out[k].t + 1e-4):
            result = solve(reach, case, heights[k], [out[k + 1].x])
            if result is not None and (out[k] is None or result.t > out[k].t):
                out[k] = result
    return out


def lateral_cop(reach: Reach, roll_max: float, rng: np.random.Generator, starts: int) -> float:
    """The smallest lateral offset [m] of the centre of pressure from the stance sole's centre line found over
    single-support poses (every leg joint free, the pelvis pitch within +-15 deg and its roll within ``roll_max``
    [rad], the sagittal CoP within the sole): whether the robot can stand on one foot statically."""
    support = reach.support

    def cop(x, lateral=True):
        return reach.statics(reach.pose(x, 0.0)["q"], lateral)[1]

    def rows(x):
        p = reach.pose(x, 0.0)
        return np.array([PITCH_MAX - abs(p["pitch"]), roll_max - abs(p["roll"]), cop(x, False) - support[0],
                         support[1] - cop(x, False)])

    best = np.inf
    inits = [reach.full(seed) for seed in reach.seeds[:1]]
    for x0 in inits + [rng.uniform(reach.lower, reach.upper) for _ in range(starts)]:
        r = minimize(lambda x: cop(x) ** 2, x0, method="SLSQP", bounds=list(zip(reach.lower, reach.upper)),
                     constraints=[{"type": "ineq", "fun": rows}], options={"maxiter": 300})
        if rows(r.x).min() > -1e-4:
            best = min(best, abs(cop(r.x)))
    return best


def knee_height_on_floor(reach: Reach) -> float:
    """The highest the knee joint can be with its sole flat on the floor [m]: the shank vertical, knee-ankle
    distance + the ankle (pitch) joint's height above the sole plane (the ankle roll, if any, at 0)."""
    model = reach.model
    knee, ankle = reach.chains[0][1:]
    shank = model.jointPlacements[ankle].translation  # in the knee's frame
    frame = model.frames[reach.swing_sole]
    ankle_sole, joint = frame.placement, frame.parentJoint  # the sole frame in the ankle's frame
    while joint != ankle:
        ankle_sole, joint = model.jointPlacements[joint] * ankle_sole, model.parents[joint]
    return float(np.linalg.norm(shank) + ankle_sole.inverse().translation[2])


def body_clearance(reach: Reach, results: list[Result], height: float) -> list[dict[str, float]]:
    """Each leg link's signed distance [m] to the box (``height`` high, 1.2 m wide) in the poses of ``results``, in
    the simulation's MuJoCo model: its collision geoms (meshes as convex hulls) and the sole spheres."""
    import mujoco

    from robots.mujoco_model import add_box_geom, build_mujoco_spec

    out = []
    for result in results:
        spec = build_mujoco_spec(reach.robot, link_collisions=True)
        depth = result.case.depth
        add_box_geom(spec, "box", np.array([0.5 * depth, 0.0, 0.5 * height]), np.array([0.5 * depth, 0.6, 0.5 * height]))
        model = spec.compile()
        data = mujoco.MjData(model)
        q = result.pose["q"]
        data.qpos[:] = np.r_[q[:3], q[6], q[3:6], q[7:]]  # MuJoCo's quaternion is (w, x, y, z)
        mujoco.mj_kinematics(model, data)
        box = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "box")
        floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        distances: dict[str, float] = {}
        for geom in range(model.ngeom):
            if geom in (box, floor) or model.geom_contype[geom] == 0:
                continue
            body = model.body(model.geom_bodyid[geom]).name
            distance = mujoco.mj_geomDistance(model, data, geom, box, 1.0, None)
            distances[body] = min(distances.get(body, np.inf), distance)
        out.append(distances)
    return out


def body_of_joint(reach: Reach, joint: str) -> str:
    """The link (body) a joint moves, by its name in the model."""
    model = reach.model
    jid = model.getJointId(joint)
    return next(f.name for f in model.frames if f.parentJoint == jid and f.type == pin.FrameType.BODY)


def print_poses(reach: Reach, rows: list[tuple[str, float, Result | None]]) -> None:
    """A table of poses (label, box height [m], result): the swing leg's angles, the knee frame's height over the
    box's top, the lowest hip-knee-ankle line point over the box, the MuJoCo model's signed distances [m] to the box
    of the swing shank (the knee joint's link) and of the three nearest links, and the swing leg's nearest pair
    with the rest of the body (``--self-collision``)."""
    found = [(box, result) for _, box, result in rows if result is not None]
    distances = iter([body_clearance(reach, [result], box)[0] for box, result in found])
    shank = body_of_joint(reach, f"{SWING}_{LEG_JOINTS[reach.name]['knee']}")
    print("| h [m] | swing, edge | t [m] | swing hip pitch, knee, ankle [rad] | pelvis pitch | knee z - h | lowest leg "
          "line point over the box - h | swing shank to the box | nearest links to the box | nearest body pair |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    swing_joints = [reach.variables.index(f"swing {joint}") for joint in ("hip_pitch", "knee", "ankle")]
    for label, box, result in rows:
        if result is None:
            print(f"| {box:.2f} | {label} | infeasible |")
            continue
        p = result.pose
        legs = p["legs"]
        over = (legs[:, 0] >= 0.0) & (legs[:, 0] <= result.case.depth)
        lowest = f"{legs[over, 2].min() - box:+.3f}" if over.any() else "-"
        distance = next(distances)
        nearest = sorted(distance.items(), key=lambda item: item[1])[:3]
        pair = "-" if reach.bodies is None else "{} / {} {:+.3f}".format(*reach.bodies.nearest(p["q"]))
        print(f"| {box:.2f} | {label} | {result.t:.3f} | {', '.join(f'{result.x[i]:+.2f}' for i in swing_joints)} | "
              f"{np.degrees(p['pitch']):+.1f} deg | {p['knee'][2] - box:+.3f} | {lowest} | "
              f"{distance[shank]:+.3f} | " + ", ".join(f"{body} {d:+.3f}" for body, d in nearest) + f" | {pair} |")


def plot(reach: Reach, curves: dict, heights, knee_floor: float, mark: float, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = np.asarray(heights)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5), sharey=True)
    for ax, swing in zip(axes, ("lead", "trailing")):
        ax.plot(h, h + reach.clearance, "k-", lw=2.5, label=f"required: h + {100 * reach.clearance:g} cm")
        ax.axhline(reach.apex_cap, color="grey", ls=":", label=f"the preset's apex cap, {reach.apex_cap:g} m")
        ax.axhline(knee_floor, color="grey", ls="-.", label=f"knee height with the sole flat on the floor, {knee_floor:.2f} m")
        for (sw, _), curve in curves.items():
            if sw != swing:
                continue
            y = np.array([np.nan if r is None else r.t for r in curve["results"]])
            ax.plot(h, y, **curve["style"], ms=5, label=curve["label"])
        stance = "near" if swing == "lead" else "far"
        ax.set(xlabel="box height h [m]", ylim=(0.0, 1.1),
               title=f"{swing} swing (stance foot {'before' if swing == 'lead' else 'beyond'} the box, at its {stance} edge)")
        ax.axvline(mark, color="k", alpha=0.15, lw=6)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=1)
    axes[0].set_ylabel("highest clearance t of toe, heel and knee [m]")
    balance = "in the sagittal plane" if not reach.lateral else "(the pelvis level)"
    fig.suptitle(f"{reach.name.upper()}: the highest sole-and-knee clearance over the grown box's edges, statically "
                 f"balanced {balance}, joint and torque limits (docs/scripts/step_over_reach.py)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", choices=sorted(LEG_JOINTS), default="h1")
    parser.add_argument("--heights", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.4, 0.5], help="box heights [m]")
    parser.add_argument("--margin", type=float, default=None,
                        help="stance sole to box edge [m] (default: the preset's planner.obstacle_margin)")
    parser.add_argument("--hip-extension-cap", type=float, default=0.5, help="the trailing swing hip's pitch bound [rad]")
    parser.add_argument("--table-height", type=float, default=0.4, help="the box height of the per-edge table [m]")
    parser.add_argument("--body-clearance", type=float, default=None,
                        help="also print the legs' distances to a box this high [m] in the per-edge table's poses")
    parser.add_argument("--poses", type=float, nargs="+", default=[], metavar="H T",
                        help="pairs of a box height and a clearance t [m]: print the sagittal cases' poses nearest the "
                             "standing posture with the sole at t")
    parser.add_argument("--self-collision", action="store_true",
                        help="keep the swing leg off the rest of the body (MuJoCo's collision geoms, the arms left out)")
    parser.add_argument("--starts", type=int, default=4, help="random starts at the first height (besides the seeds)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--plot", default=None, help="figure path (default docs/figures/<robot>_step_over_reach.png; "
                                                     "'' for none)")
    args = parser.parse_args()
    if len(args.poses) % 2:
        parser.error(f"--poses takes pairs of a box height and a clearance [m], got {len(args.poses)} numbers")
    reach = Reach(args.robot, self_collision=args.self_collision)
    margin = reach.margin if args.margin is None else args.margin
    path = f"docs/figures/{args.robot}_step_over_reach.png" if args.plot is None else args.plot
    rng = np.random.default_rng(args.seed)
    heights = sorted(args.heights)
    cap = args.hip_extension_cap
    knee_floor = knee_height_on_floor(reach)
    shallow, deep = reach.depths
    full_extension = reach.upper[reach.hip_pitch]

    # (key, Case, label, plot style). The near edge of a lead swing and the far edge of a trailing one are next to the
    # stance foot: the box's depth does not move them (the deep box: the larger collision region).
    red, blue, grey = "tab:red", "tab:blue", "0.5"
    lead = lambda edge, depth, **options: Case("lead", edge, depth, **options)
    trailing = lambda edge, depth, **options: Case("trailing", edge, depth, hip_extension=cap, **options)
    specs = [
        ("lead", "near", lead("near", deep), "near edge (next to the stance foot), sagittal",
         dict(color=red, marker="o")),
        ("lead", "near abducted", lead("near", deep, freedom="abducted"), "near edge, swing hip roll free",
         dict(color=red, marker="^", ls="--")),
        ("lead", "near turned", lead("near", deep, freedom="turned"), "near edge, swing hip roll and yaw free",
         dict(color=red, marker="v", ls=":")),
        ("lead", f"far {shallow:g}", lead("far", shallow), f"far edge, {shallow:g} m deep box, sagittal",
         dict(color=blue, marker="o")),
        ("lead", f"far {deep:g}", lead("far", deep), f"far edge, {deep:g} m deep box, sagittal",
         dict(color=blue, marker="s")),
        ("trailing", "far", trailing("far", deep),
         f"far edge (next to the stance foot), sagittal, hip extension <= {cap:g} rad", dict(color=red, marker="o")),
        ("trailing", "far abducted", trailing("far", deep, freedom="abducted"),
         "far edge, swing hip roll free", dict(color=red, marker="^", ls="--")),
        ("trailing", "far turned", trailing("far", deep, freedom="turned"),
         "far edge, swing hip roll and yaw free", dict(color=red, marker="v", ls=":")),
        ("trailing", f"near {shallow:g}", trailing("near", shallow),
         f"near edge, {shallow:g} m deep box, sagittal", dict(color=blue, marker="o")),
        ("trailing", f"near {deep:g}", trailing("near", deep),
         f"near edge, {deep:g} m deep box, sagittal", dict(color=blue, marker="s")),
        ("trailing", "far full", Case("trailing", "far", deep),
         f"either edge, the hip extended up to its {full_extension:.2f} rad limit (thigh behind the body)",
         dict(color=grey, marker="o", ls="--")),
        ("trailing", "near full", Case("trailing", "near", shallow),
         f"_near edge ({shallow:g} m), hip extension to {full_extension:.2f} rad", dict(color=grey, marker="s", ls="--")),
    ]
    curves = {}
    for swing, key, case, label, style in specs:
        case = replace(case, margin=margin)
        curves[swing, key] = {"case": case, "label": label, "style": style,
                              "results": series(reach, case, heights, args.starts, rng)}

    fmt = lambda r: "-" if r is None else f"{r.t:.3f}"
    print("Highest clearance t [m] (toe, heel and swing knee all >= t) over the grown box's edge, statically balanced "
          f"in the sagittal plane; the trailing swing's hip extension <= {cap:g} rad unless 'full'. "
          f"Required: h + {reach.clearance:g}.")
    keys = list(curves)
    print("| h [m] | required | " + " | ".join(f"{s} {k}" for s, k in keys) + " |")
    print("|---|---|" + "---|" * len(keys))
    for i, height in enumerate(heights):
        print(f"| {height:.2f} | {height + reach.clearance:.2f} | "
              + " | ".join(fmt(curves[k]["results"][i]) for k in keys) + " |")

    i = heights.index(args.table_height) if args.table_height in heights else len(heights) - 1
    height = heights[i]
    print(f"\nAt h = {height:.2f} m (required {height + reach.clearance:.2f} m): t with the whole sole and the knee (the "
          "table above), with the whole sole only, with the OCP's gating (only the sole points over the grown box held at "
          "t), and with the joint limits only (no statics); the limits active at the first; the stance leg's static "
          "torques |tau| / limit [N·m]; the CoP in the stance sole frame [m] (the support: "
          f"[{reach.support[0]:g}, {reach.support[1]:g}])")
    print("| swing | edge | t | sole only | OCP gating | joint limits only | knee z | pelvis pitch, z | active at t | "
          "stance torques | CoP |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    names = reach.robot.actuated_joint_names
    limit = reach.robot.torque_limit
    ankle = reach.leg_v[reach.variables.index("stance ankle")]
    n_leg = len(reach.variables) // 2
    for (swing, key), curve in curves.items():
        result = curve["results"][i]
        if result is None:
            print(f"| {swing} | {key} | infeasible |")
            continue
        inits = [result.x] + list(reach.seeds)
        others = [solve(reach, replace(curve["case"], **options), height, inits)
                  for options in (dict(knee=False), dict(gating=True), dict(static=False))]
        p = result.pose
        torques = ", ".join(f"{names[j].removeprefix(STANCE + '_').removesuffix('_joint')} {abs(result.tau[j]):.0f}/"
                            f"{limit[j]:.0f}" for j in reach.leg_v[1:n_leg])
        free = others[2]
        if free is not None:  # the stance ankle's torque and the CoP that pose would need
            free_cell = f"{free.t:.3f} (ankle {abs(free.tau[ankle]):.0f}/{limit[ankle]:.0f}, CoP {free.cop:+.2f})"
        print(f"| {swing} | {key} | {result.t:.3f} | {fmt(others[0])} | {fmt(others[1])} | "
              f"{free_cell if free is not None else '-'} | {p['knee'][2]:.3f} | "
              f"{np.degrees(p['pitch']):+.1f} deg, {p['pelvis_z']:.3f} m | {', '.join(result.active) or '-'} | "
              f"{torques} | {result.cop:+.3f} |")

    if args.body_clearance is not None:
        box = args.body_clearance
        print(f"\nA box {box:.2f} m high: the poses of the first table re-solved at that height (the whole sole and the "
              "knee, statics)")
        rows = []
        for (swing, key), curve in curves.items():
            start = curve["results"][heights.index(box)] if box in heights else None
            inits = ([] if start is None else [start.x]) + [r.x for r in curve["results"] if r is not None]
            rows.append((f"{swing} {key}", box, solve(reach, curve["case"], box, inits)))
        print_poses(reach, rows)
    if args.poses:
        print("\nThe poses nearest the standing posture (least squares of the free joints' angles) with the swing sole's "
              "points at t over the grown box's edge, the knee at the preset's shank margin over the box, statics:")
        rows = []
        for box, t in zip(args.poses[::2], args.poses[1::2]):
            for (swing, key), curve in curves.items():
                if curve["case"].freedom != "sagittal" or key.endswith("full") or key.endswith(f" {shallow:g}"):
                    continue
                inits = [r.x for r in curve["results"] if r is not None] + list(reach.seeds)
                rows.append((f"{swing} {key}", box, solve(reach, curve["case"], box, inits, fixed_t=t)))
        print_poses(reach, rows)

    print(f"\nThe knee frame with its sole flat on the floor is at most {knee_floor:.3f} m high (the shank vertical): the "
          f"preset's knee barrier (top + {reach.shank_margin:g} over the whole crossing swing, lift-off and touchdown "
          f"included) asks more from h = {knee_floor - reach.shank_margin:.3f} m on.")
    for roll in (15.0, 30.0):
        offset = lateral_cop(reach, np.radians(roll), rng, 2 * args.starts)
        print(f"Single support, every leg joint free, the pelvis rolled up to {roll:.0f} deg: the lateral CoP stays "
              f"{offset:.3f} m or more off the sole's centre line (the sole spheres: |y| <= {reach.half_width} m).")
    step = margin + reach.margin + reach.sole_front + reach.sole_rear
    print(f"\nThe lead swing's near edge (sagittal, the sole and the knee, the OCP's gating) against the stance margin, "
          f"h = {height:.2f} m; the crossing step is then at least depth + margin + {_cm(step - margin)} m:")
    previous = None
    for k in range(5):
        case = Case("lead", "near", deep, gating=True, margin=round(margin + 0.02 * k, 3))
        previous = solve(reach, case, height, ([] if previous is None else [previous.x]) + list(reach.seeds[1:3])) or previous
        print(f"  margin {_cm(case.margin)} m: t = {previous.t:.3f} m ({', '.join(previous.active)})")
    if path:
        plot(reach, curves, heights, knee_floor, height, path)
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
