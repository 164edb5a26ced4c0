"""Can the H1's legs step over a 10-50 cm box? The highest clearance a crossing swing can reach over the box's
edges, from Pinocchio kinematics and SLSQP (issue 15; docs/robots.md, "Can the H1 step over 40 cm?").

    PYTHONPATH=. python docs/scripts/step_over_reach.py [--heights 0.1 0.2 0.3 0.4 0.5] [--margin 0.08]
        [--hip-extension-cap 0.5] [--plot docs/figures/h1_step_over_reach.png]

Geometry (the H1 preset's rules): the box's near edge at x = 0, its far edge at x = depth; the clearance terms act
over the box grown by 3 cm (x in [-0.03, depth + 0.03]). Lead swing: the stance sole flat on the floor, its toe
``--margin`` before the near edge (planner.obstacle_margin). Trailing swing: the stance sole flat, its heel
``--margin`` beyond the far edge. The swing foot's leading point is at the grown footprint's edge: its toe at
x = -0.03 ("near": the sole entering it) or its heel at x = depth + 0.03 ("far": the sole leaving it).

Maximised: t, with the toe and heel points of the swing sole (ocp.obstacle_sole_points) and the swing knee frame
(``left_knee``, ocp.obstacle_shank_frames) at least t high; the preset asks t = h + 0.05. Free: the stance leg's
hip pitch, knee and ankle and the swing leg's hip pitch, knee, ankle (and, in the "abducted" and "turned" variants,
the swing hip's roll, then also its yaw); the stance hip roll and yaw, the torso and the arms stay at the standing
posture, so the pelvis stays level in roll and follows from the stance leg. Subject to the joint limits, the pelvis
pitch within +-15 deg, its height >= 0.60 m (the fall threshold), no point of either leg's hip-knee-ankle segments
inside the box (the only place the box's height enters: each curve is flat in h unless that binds), and the
sagittal statics of single support: the stance sole's 6D wrench balancing gravity (the floating-base rows of
g(q) = J_c^T f, ``pinocchio.computeGeneralizedGravity`` and the stance sole's LOCAL Jacobian), every leg joint's
torque g - J_c^T f within ``robot.torque_limit``, and the centre of pressure within the sole along x (the MuJoCo
heel and toe spheres: x in [-0.1075, 0.0725] m of the sole frame; the ankle's 40 N·m bounds it 7.9 cm ahead of
the ankle). Lateral balance is not checked: the H1 cannot hold any single-support pose statically (no ankle
roll: with the pelvis rolled up to 30 deg the lateral CoP stays several centimetres outside the sole's +-3.5 cm,
printed), it balances sideways dynamically. "joint limits only" drops the statics.

Each maximisation is multi-started: five standing, folded and stretched leg poses and ``--starts`` random ones at
the first height, the previous height's optimum and two random ones after, then back down from the next height's.
About 30 s on one core. Prints the tables of docs/robots.md and writes the figure.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field, replace

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

from robots import load_robot
from robots.h1 import HEEL_X, SOLE_CENTER_IN_ANKLE, TOE_HALF_WIDTH, TOE_X
from wbmpc.walking.preset import load_walking_preset

PRESET = load_walking_preset("h1")  # the numbers below are the preset's, so the script follows it
TOE, HEEL = (np.array(point) for point in PRESET.ocp.obstacle_sole_points)  # [m], sole frame
CLEARANCE = PRESET.ocp.obstacle_clearance_margin  # [m] (= obstacle_shank_margin in the preset)
GROWN = PRESET.ocp.obstacle_footprint_margin  # [m]
SOLE_FRONT, SOLE_REAR = PRESET.planner_params.sole_front, PRESET.planner_params.sole_rear  # [m]
MARGIN = PRESET.planner_params.obstacle_margin  # [m] stance sole to the box's edge
PITCH_MAX = np.radians(15.0)  # pelvis pitch bound
PELVIS_MIN = PRESET.fall.min_base_height  # [m]
SUPPORT = (HEEL_X - SOLE_CENTER_IN_ANKLE[0], TOE_X - SOLE_CENTER_IN_ANKLE[0])  # [m] the heel and toe spheres along
#                                                                                the sole frame's x
APEX_CAP = PRESET.ocp.obstacle_apex_height_max  # [m]
SWING, STANCE = "left", "right"
LEG_JOINTS = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle")
VARIABLES = tuple(f"{role} {joint}" for role in ("stance", "swing") for joint in LEG_JOINTS)
FREEDOMS = {  # the free entries of VARIABLES
    "sagittal": (2, 3, 4, 7, 8, 9),
    "abducted": (2, 3, 4, 6, 7, 8, 9),      # + the swing hip roll
    "turned": (2, 3, 4, 5, 6, 7, 8, 9),     # + the swing hip roll and yaw
}
# Initial guesses besides the random ones (stance hip pitch, knee, ankle, swing hip pitch, knee, ankle [rad]): the
# standing legs, the swing leg folded forward (the lead's near edge), reaching forward (its far edge), folded back
# under the body (the trailing's far edge), stretched back with the knee bent (the hip at its extension limit).
SEEDS = (
    (-0.177, 0.6, -0.423, -0.177, 0.6, -0.423),
    (-0.3, 0.0, 0.1, -1.57, 2.05, -0.7),
    (0.27, 0.0, 0.0, -1.57, 1.3, 0.5),
    (0.5, 0.0, -0.17, 0.0, 2.05, 0.5),
    (-0.2, 0.0, 0.0, 1.57, 1.5, 0.0),
)


@dataclass
class Reach:
    """The H1's legs with the stance sole fixed flat on the floor."""

    robot: object = field(default_factory=lambda: load_robot("h1"))

    def __post_init__(self) -> None:
        model = self.model = self.robot.pinocchio_model
        self.data = model.createData()
        joint = lambda side, name: model.joints[model.getJointId(f"{side}_{name}")]
        self.iq = np.array([joint(side, name).idx_q for side in (STANCE, SWING) for name in LEG_JOINTS])
        self.lower = model.lowerPositionLimit[self.iq].copy()
        self.upper = model.upperPositionLimit[self.iq].copy()
        self.stance_sole = model.getFrameId(self.robot.foot_frames[STANCE])
        self.swing_sole = model.getFrameId(self.robot.foot_frames[SWING])
        self.chains = [[model.getJointId(f"{side}_{name}") for name in ("hip_pitch", "knee", "ankle")]
                       for side in (SWING, STANCE)]
        self.leg_v = np.array([joint(side, name).idx_v - 6 for side in (STANCE, SWING) for name in LEG_JOINTS])
        self.q0 = np.array(self.robot.q_reference)
        self.q0[:7] = [0, 0, 0, 0, 0, 0, 1]
        self._last = (None, None)

    def pose(self, x: np.ndarray, stance_x: float) -> dict:
        """World points of leg angles x (VARIABLES order) with the stance sole flat at (stance_x, its y, 0)."""
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
        out = {"q": q, "toe": sole.act(TOE), "heel": sole.act(HEEL), "knee": legs[5], "legs": legs,
               "pitch": float(np.arctan2(-rotation[2, 0], rotation[0, 0])),
               "roll": float(np.arctan2(rotation[2, 1], rotation[2, 2])), "pelvis_z": float(origin[2])}
        self._last = (key, out)
        return out

    def statics(self, q: np.ndarray, lateral: bool = False) -> tuple[np.ndarray, float]:
        """Joint torques [N·m] (nu,) holding the robot's weight on the stance sole alone, and the centre of
        pressure's x in the stance sole frame [m] (its y with ``lateral``)."""
        g = pin.computeGeneralizedGravity(self.model, self.data, q)
        jacobian = pin.computeFrameJacobian(self.model, self.data, q, self.stance_sole, pin.LOCAL)
        wrench = np.linalg.solve(jacobian[:, :6].T, g[:6])
        tau = g[6:] - jacobian[:, 6:].T @ wrench
        return tau, float((wrench[3] if lateral else -wrench[4]) / wrench[2])


@dataclass(frozen=True)
class Case:
    swing: str            # "lead" | "trailing"
    edge: str             # "near" | "far"
    depth: float          # [m]
    freedom: str = "sagittal"
    static: bool = True   # False: the joint limits only
    knee: bool = True     # the swing knee at least t high too
    gating: bool = False  # only the sole points over the grown box held at t (the OCP's rule), else the whole sole
    hip_extension: float | None = None  # swing hip pitch upper bound [rad] (None: its joint limit, 1.57)
    margin: float = MARGIN

    def stance_x(self) -> float:
        return -self.margin - SOLE_FRONT if self.swing == "lead" else self.depth + self.margin + SOLE_REAR


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


def _outside(a: np.ndarray, tau: float = 0.005) -> np.ndarray:
    """Smooth max over the last axis (log-sum-exp minus its largest excess): >= 0 only where the true max is."""
    top = a.max(axis=-1, keepdims=True)
    return (top + tau * np.log(np.exp((a - top) / tau).sum(axis=-1, keepdims=True)))[..., 0] - tau * np.log(a.shape[-1])


def solve(reach: Reach, case: Case, height: float, inits: list[np.ndarray]) -> Result | None:
    """max t for a box ``height`` high from each initial guess (all VARIABLES, or the six of SEEDS); None if no
    start ends feasible."""
    stance_x, depth = case.stance_x(), case.depth
    free = np.array(FREEDOMS[case.freedom])
    n = free.size
    lower, upper = reach.lower[free], reach.upper[free].copy()
    if case.hip_extension is not None:
        upper[list(free).index(7)] = min(reach.upper[7], case.hip_extension)
    limit = reach.robot.torque_limit[reach.leg_v]

    def full(z: np.ndarray) -> np.ndarray:
        x = np.zeros(len(VARIABLES))
        x[free] = z[:n]
        return x

    def inequalities(z: np.ndarray) -> np.ndarray:
        p, t = reach.pose(full(z), stance_x), z[n]
        lead_point, other = ("toe", "heel") if case.edge == "near" else ("heel", "toe")
        rows = [PITCH_MAX - abs(p["pitch"]), p["pelvis_z"] - PELVIS_MIN, p[lead_point][2] - t]
        if case.gating:  # the other point above t, or outside the grown footprint
            x_other = p[other][0]
            rows.append(_outside(np.array([-GROWN - x_other, x_other - depth - GROWN, p[other][2] - t])))
        else:
            rows.append(p[other][2] - t)
        if case.knee:
            rows.append(p["knee"][2] - t)
        legs = p["legs"]
        rows += list(_outside(np.stack([-legs[:, 0], legs[:, 0] - depth, legs[:, 2] - height], axis=1)))
        if case.static:
            tau, cop = reach.statics(p["q"])
            rows += list(1.0 - np.abs(tau[reach.leg_v]) / limit) + [cop - SUPPORT[0], SUPPORT[1] - cop]
        return np.array(rows)

    def at_edge(z: np.ndarray) -> np.ndarray:
        p = reach.pose(full(z), stance_x)
        return np.array([p["toe"][0] + GROWN if case.edge == "near" else p["heel"][0] - depth - GROWN])

    bounds = list(zip(lower, upper)) + [(-1.0, 2.0)]
    best = None
    for init in inits:
        x0 = np.asarray(init, dtype=float)
        if x0.size == len(SEEDS[0]):  # a seed: the sagittal joints
            x0 = np.zeros(len(VARIABLES))
            x0[list(FREEDOMS["sagittal"])] = init
        z0 = np.clip(x0[free], lower, upper)
        p = reach.pose(full(z0), stance_x)
        z0 = np.r_[z0, min(p["toe"][2], p["heel"][2], p["knee"][2] if case.knee else np.inf)]  # a feasible t
        r = minimize(lambda z: -z[n], z0, method="SLSQP", bounds=bounds, options={"maxiter": 200, "ftol": 1e-8},
                     constraints=[{"type": "ineq", "fun": inequalities}, {"type": "eq", "fun": at_edge}])
        if inequalities(r.x).min() > -1e-4 and abs(at_edge(r.x)).max() < 1e-4 and (best is None or r.x[n] > best[n]):
            best = r.x
    if best is None:
        return None
    x = full(best)
    p = reach.pose(x, stance_x)
    tau, cop = reach.statics(p["q"])
    active = [VARIABLES[i] + (" min" if v - lo < 1e-3 else " max") for i, v, lo, hi in
              zip(free, best[:n], lower, upper) if v - lo < 1e-3 or hi - v < 1e-3]
    if abs(abs(p["pitch"]) - PITCH_MAX) < 1e-3:
        active.append(f"pelvis pitch {np.degrees(p['pitch']):+.0f} deg")
    if case.static:
        if cop - SUPPORT[0] < 1e-3:
            active.append("CoP at the heel")
        if SUPPORT[1] - cop < 1e-3:
            active.append("CoP at the toe")
        names = reach.robot.actuated_joint_names
        active += [f"{names[i]} torque" for i in reach.leg_v if abs(tau[i]) / reach.robot.torque_limit[i] > 0.999]
    if case.knee and p["knee"][2] - best[n] < 1e-3:
        active.append("knee height")
    return Result(case, height, float(best[n]), x, p, tau, cop, active)


def series(reach: Reach, case: Case, heights, starts: int, rng: np.random.Generator) -> list[Result | None]:
    """The case over ascending heights, each warm-started from the previous optimum; then back down, each from the
    next height's (feasible there: a lower box only loosens the collision rows)."""
    out, previous = [], None
    for k, height in enumerate(heights):
        if k == 0 or previous is None:
            inits = list(SEEDS) + [rng.uniform(reach.lower, reach.upper) for _ in range(starts)]
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
    [rad], the sagittal CoP within the sole): whether the H1 can stand on one foot statically."""
    def cop(x, lateral=True):
        return reach.statics(reach.pose(x, 0.0)["q"], lateral)[1]

    def rows(x):
        p = reach.pose(x, 0.0)
        return np.array([PITCH_MAX - abs(p["pitch"]), roll_max - abs(p["roll"]), cop(x, False) - SUPPORT[0],
                         SUPPORT[1] - cop(x, False)])

    best = np.inf
    inits = [np.bincount(list(FREEDOMS["sagittal"]), seed, len(VARIABLES)) for seed in SEEDS[:1]]
    for x0 in inits + [rng.uniform(reach.lower, reach.upper) for _ in range(starts)]:
        r = minimize(lambda x: cop(x) ** 2, x0, method="SLSQP", bounds=list(zip(reach.lower, reach.upper)),
                     constraints=[{"type": "ineq", "fun": rows}], options={"maxiter": 300})
        if rows(r.x).min() > -1e-4:
            best = min(best, abs(cop(r.x)))
    return best


def knee_height_on_floor(reach: Reach) -> float:
    """The highest the knee frame can be with its sole flat on the floor: the shank vertical (ankle angle 0 in this
    model), knee-ankle distance + the ankle's height above the sole plane [m]."""
    shank = reach.model.jointPlacements[reach.model.getJointId(f"{SWING}_ankle")].translation  # in the knee's frame
    sole = reach.model.frames[reach.swing_sole].placement.translation  # in the ankle's frame
    return float(np.linalg.norm(shank) - sole[2])


def plot(curves: dict, heights, knee_floor: float, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = np.asarray(heights)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5), sharey=True)
    for ax, swing in zip(axes, ("lead", "trailing")):
        ax.plot(h, h + CLEARANCE, "k-", lw=2.5, label=f"required: h + {100 * CLEARANCE:g} cm")
        ax.axhline(APEX_CAP, color="grey", ls=":", label=f"the preset's apex cap, {APEX_CAP:g} m")
        ax.axhline(knee_floor, color="grey", ls="-.", label=f"knee height with the sole flat on the floor, {knee_floor:.2f} m")
        for (sw, _), curve in curves.items():
            if sw != swing:
                continue
            y = np.array([np.nan if r is None else r.t for r in curve["results"]])
            ax.plot(h, y, **curve["style"], ms=5, label=curve["label"])
        stance = "near" if swing == "lead" else "far"
        ax.set(xlabel="box height h [m]", ylim=(0.0, 1.1),
               title=f"{swing} swing (stance foot {'before' if swing == 'lead' else 'beyond'} the box, at its {stance} edge)")
        ax.axvline(0.4, color="k", alpha=0.15, lw=6)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=1)
    axes[0].set_ylabel("highest clearance t of toe, heel and knee [m]")
    fig.suptitle("H1: the highest sole-and-knee clearance over the grown box's edges, statically balanced in the "
                 "sagittal plane, joint and torque limits (docs/scripts/step_over_reach.py)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heights", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.4, 0.5], help="box heights [m]")
    parser.add_argument("--margin", type=float, default=MARGIN, help="stance sole to box edge [m] (planner.obstacle_margin)")
    parser.add_argument("--hip-extension-cap", type=float, default=0.5, help="the trailing swing hip's pitch bound [rad]")
    parser.add_argument("--table-height", type=float, default=0.4, help="the box height of the per-edge table [m]")
    parser.add_argument("--starts", type=int, default=4, help="random starts at the first height (besides SEEDS)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--plot", default="docs/figures/h1_step_over_reach.png")
    args = parser.parse_args()
    reach = Reach()
    rng = np.random.default_rng(args.seed)
    heights = sorted(args.heights)
    cap = args.hip_extension_cap
    knee_floor = knee_height_on_floor(reach)

    # (key, Case, label, plot style). The near edge of a lead swing and the far edge of a trailing one are next to the
    # stance foot: the box's depth does not move them (0.25 m: the deeper box, the larger collision region).
    red, blue, grey = "tab:red", "tab:blue", "0.5"
    specs = [
        ("lead", "near", Case("lead", "near", 0.25), "near edge (next to the stance foot), sagittal",
         dict(color=red, marker="o")),
        ("lead", "near abducted", Case("lead", "near", 0.25, freedom="abducted"), "near edge, swing hip roll free",
         dict(color=red, marker="^", ls="--")),
        ("lead", "near turned", Case("lead", "near", 0.25, freedom="turned"), "near edge, swing hip roll and yaw free",
         dict(color=red, marker="v", ls=":")),
        ("lead", "far 0.15", Case("lead", "far", 0.15), "far edge, 0.15 m deep box, sagittal", dict(color=blue, marker="o")),
        ("lead", "far 0.25", Case("lead", "far", 0.25), "far edge, 0.25 m deep box, sagittal", dict(color=blue, marker="s")),
        ("trailing", "far", Case("trailing", "far", 0.25, hip_extension=cap),
         f"far edge (next to the stance foot), sagittal, hip extension <= {cap:g} rad", dict(color=red, marker="o")),
        ("trailing", "far abducted", Case("trailing", "far", 0.25, freedom="abducted", hip_extension=cap),
         "far edge, swing hip roll free", dict(color=red, marker="^", ls="--")),
        ("trailing", "far turned", Case("trailing", "far", 0.25, freedom="turned", hip_extension=cap),
         "far edge, swing hip roll and yaw free", dict(color=red, marker="v", ls=":")),
        ("trailing", "near 0.15", Case("trailing", "near", 0.15, hip_extension=cap), "near edge, 0.15 m deep box, sagittal",
         dict(color=blue, marker="o")),
        ("trailing", "near 0.25", Case("trailing", "near", 0.25, hip_extension=cap), "near edge, 0.25 m deep box, sagittal",
         dict(color=blue, marker="s")),
        ("trailing", "far full", Case("trailing", "far", 0.25),
         "either edge, the hip extended up to its 1.57 rad limit (thigh behind the body)",
         dict(color=grey, marker="o", ls="--")),
        ("trailing", "near full", Case("trailing", "near", 0.15), "_near edge (0.15 m), hip extension to 1.57 rad",
         dict(color=grey, marker="s", ls="--")),
    ]
    curves = {}
    for swing, key, case, label, style in specs:
        case = replace(case, margin=args.margin)
        curves[swing, key] = {"case": case, "label": label, "style": style,
                              "results": series(reach, case, heights, args.starts, rng)}

    fmt = lambda r: "-" if r is None else f"{r.t:.3f}"
    print("Highest clearance t [m] (toe, heel and swing knee all >= t) over the grown box's edge, statically balanced "
          f"in the sagittal plane; the trailing swing's hip extension <= {cap:g} rad unless 'full'. Required: h + 0.05.")
    keys = list(curves)
    print("| h [m] | required | " + " | ".join(f"{s} {k}" for s, k in keys) + " |")
    print("|---|---|" + "---|" * len(keys))
    for i, height in enumerate(heights):
        print(f"| {height:.2f} | {height + CLEARANCE:.2f} | " + " | ".join(fmt(curves[k]["results"][i]) for k in keys) + " |")

    i = heights.index(args.table_height) if args.table_height in heights else len(heights) - 1
    height = heights[i]
    print(f"\nAt h = {height:.2f} m (required {height + CLEARANCE:.2f} m): t with the whole sole and the knee (the table "
          "above), with the whole sole only, with the OCP's gating (only the sole points over the grown box held at t), "
          "and with the joint limits only (no statics); the limits active at the first; the stance leg's static torques "
          f"|tau| / limit [N·m]; the CoP in the stance sole frame [m] (the support: [{SUPPORT[0]}, {SUPPORT[1]}])")
    print("| swing | edge | t | sole only | OCP gating | joint limits only | knee z | pelvis pitch, z | active at t | "
          "stance torques | CoP |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    names = reach.robot.actuated_joint_names
    limit = reach.robot.torque_limit
    for (swing, key), curve in curves.items():
        result = curve["results"][i]
        if result is None:
            print(f"| {swing} | {key} | infeasible |")
            continue
        inits = [result.x] + list(SEEDS)
        others = [solve(reach, replace(curve["case"], **options), height, inits)
                  for options in (dict(knee=False), dict(gating=True), dict(static=False))]
        p = result.pose
        torques = ", ".join(f"{names[j].removeprefix(STANCE + '_')} {abs(result.tau[j]):.0f}/{limit[j]:.0f}"
                            for j in reach.leg_v[1:5])
        free = others[2]
        if free is not None:  # the stance ankle's torque and the CoP that pose would need
            ankle = reach.leg_v[4]
            free_cell = f"{free.t:.3f} (ankle {abs(free.tau[ankle]):.0f}/{limit[ankle]:.0f}, CoP {free.cop:+.2f})"
        print(f"| {swing} | {key} | {result.t:.3f} | {fmt(others[0])} | {fmt(others[1])} | "
              f"{free_cell if free is not None else '-'} | {p['knee'][2]:.3f} | "
              f"{np.degrees(p['pitch']):+.1f} deg, {p['pelvis_z']:.3f} m | {', '.join(result.active) or '-'} | "
              f"{torques} | {result.cop:+.3f} |")

    print(f"\nThe knee frame with its sole flat on the floor is at most {knee_floor:.3f} m high (the shank vertical): the "
          f"preset's knee barrier (top + 0.05 over the whole crossing swing, lift-off and touchdown included) asks more "
          f"from h = {knee_floor - CLEARANCE:.3f} m on.")
    for roll in (15.0, 30.0):
        offset = lateral_cop(reach, np.radians(roll), rng, 2 * args.starts)
        print(f"Single support, every leg joint free, the pelvis rolled up to {roll:.0f} deg: the lateral CoP stays "
              f"{offset:.3f} m or more off the sole's centre line (the sole spheres: |y| <= {TOE_HALF_WIDTH} m).")
    print(f"\nThe lead swing's near edge (sagittal, the sole and the knee, the OCP's gating) against the stance margin, "
          f"h = {height:.2f} m; the crossing step is then at least depth + margin + 0.32 m:")
    previous = None
    for margin in (0.08, 0.10, 0.12, 0.14, 0.16):
        case = Case("lead", "near", 0.25, gating=True, margin=margin)
        previous = solve(reach, case, height, ([] if previous is None else [previous.x]) + list(SEEDS[1:3])) or previous
        print(f"  margin {margin:.2f} m: t = {previous.t:.3f} m ({', '.join(previous.active)})")
    if args.plot:
        plot(curves, heights, knee_floor, args.plot)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
