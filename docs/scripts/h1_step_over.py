"""The H1 stepping over a box it is told about (the deterministic scene of docs/ocp.md, "Obstacle clearance (the
H1)": tests/negotiation_scene.py's StepOverBox, 1.0 m ahead, 0.3 m/s, the controller given the true box), with
the H1 preset and ``--set`` overrides; prints every touchdown (foot, x, y, time, measured DCM x and its offset
from the foot), the planned next step at each, the first box contact, the crossing time, the lowest clearance
over the box, the MPC failures and the fall; with ``--trace T0 T1`` every replan between those times (the planned
next foothold and touchdown, the measured DCM, both ankles). Needs the optional extra ``wbmpc[h1]``.

    PYTHONPATH=. python docs/scripts/h1_step_over.py [--height 0.1] [--duration 7] [--set section.name=value ...]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from negotiation_scene import BoxContacts, KnownObstacleController, StepOverBox  # noqa: E402

from sim.runner import run_scenario  # noqa: E402
from wbmpc.cli.arguments import parse_assignment  # noqa: E402
from wbmpc.walking.preset import load_walking_preset  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--height", type=float, default=0.1, help="box height [m]")
    parser.add_argument("--depth", type=float, default=0.1, help="box depth [m]")
    parser.add_argument("--speed", type=float, default=0.3, help="walking speed [m/s]")
    parser.add_argument("--duration", type=float, default=7.0, help="simulated time [s]")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", type=parse_assignment,
                        help="walking-preset override, e.g. planner.obstacle_swing_length_max=0.75")
    parser.add_argument("--plans", action="store_true",
                        help="print the plan at the start of every stance from x = 0.5 m on")
    parser.add_argument("--terms", action="store_true",
                        help="print the OCP's four largest cost terms every 0.1 s once a crossing is in its horizon")
    parser.add_argument("--trace", nargs=2, type=float, metavar=("T0", "T1"),
                        help="print every replan from T0 to T1 [s]: the next foothold and touchdown, the DCM, the ankles")
    parser.add_argument("--cold-restart", action="store_true",
                        help="the MPC update after a failed one starts cold (= --set mpc_restart_after_failures=1)")
    args = parser.parse_args()
    overrides = dict(args.set)
    if args.cold_restart:  # RecedingHorizonMPC(restart_after_failures=1)
        overrides.setdefault("mpc_restart_after_failures", 1)
    warnings.simplefilter("ignore")  # the node-wise evaluation warning (the KKT backend)
    box = StepOverBox(height=args.height, depth=args.depth, distance=1.0, speed=args.speed)
    preset = load_walking_preset("h1", overrides, scenario="obstacle")  # the obstacle runs' preset
    controller = KnownObstacleController(preset, (box.obstacle(),))
    contacts = BoxContacts(box)
    terms = []  # (t, the OCP's largest cost terms after the update) with --terms
    if args.terms:
        replan = controller.replan

        def replan_with_terms(t, measurement):
            record = replan(t, measurement)
            if record.get("crossing_nodes", 0) > 0 and round(t / 0.02) % 5 == 0:
                costs = controller.mpc.problem.term_costs()
                terms.append((t, sorted(costs.items(), key=lambda item: -item[1])[:4]))
            return record

        controller.replan = replan_with_terms
    plans = []  # (t, the plan) at the first replan of every stance: what the planner asked for then
    ankles = []  # (t, left ankle x, right ankle x, left z, right z) [s, m] every 20 ms with --trace

    def on_tick(model, data) -> None:
        contacts(model, data)
        if args.trace and args.trace[0] <= data.time <= args.trace[1] and round(data.time * 1000) % 20 == 0:
            left, right = (data.body(f"{side}_ankle_link").xpos for side in ("left", "right"))
            ankles.append((float(data.time), left[0], right[0], left[2], right[2]))
        plan = controller.plan if controller.planning is not None else None
        if plan is not None and (not plans or plans[-1][1].stance_foot != plan.stance_foot):
            plans.append((float(data.time), plan))

    log = run_scenario("step_over_box", robot="h1", duration=args.duration, controller=controller,
                       on_tick=on_tick, progress=False, height=box.height, depth=box.depth, distance=box.distance,
                       speed=box.speed)
    r = log.replans
    feet = ("left", "right")
    print(f"overrides {overrides}  box {box.height} x {box.depth} m at x = {box.distance} m")
    for i in np.flatnonzero(r["stance_switched"] > 0):
        print(f"  t {r['t'][i]:6.3f}  {feet[int(r['stance_foot'][i])]:5s} landed x {r['stance_x'][i]:6.3f} "
              f"y {r['stance_y'][i]:6.3f}  dcm x {r['dcm_x'][i]:6.3f} (offset {r['dcm_x'][i] - r['stance_x'][i]:+.3f})"
              f"  next: {feet[int(r['next_foot'][i])]} x {r['next_x'][i]:6.3f} y {r['next_y'][i]:6.3f} "
              f"at {r['next_touchdown_time'][i]:.3f}"
              + ("" if np.isnan(r["next_crossing_height"][i]) else "  CROSSING"))
    if args.plans:
        for t, plan in plans:
            if plan.stance_position[0] < 0.5:
                continue
            print(f"  plan at {t:.3f} ({plan.stance_foot} stance x {plan.stance_position[0]:.3f}, "
                  f"DCM x {plan.dcm_measured[0]:.3f}):")
            for step in plan.steps[:3]:
                print(f"      {step.foot:5s} x {step.position[0]:6.3f} y {step.position[1]:6.3f} "
                      f"T {step.duration:.3f} at {step.touchdown_time:.3f} offset x {step.dcm_offset[0]:+.3f}"
                      + (f" lift-off x {step.crossing.liftoff[0]:.3f} CROSSING" if step.crossing is not None else "")
                      + ("" if step.double_support is None else f" settled {step.double_support:.2f} s"))
    if args.trace:
        print("  trace (t, next foot x y at touchdown, DCM x y, ankles x left right, z left right):")
        at = np.array([a[0] for a in ankles]) if ankles else np.zeros(0)
        for i in np.flatnonzero((r["t"] >= args.trace[0]) & (r["t"] <= args.trace[1])):
            k = int(np.argmin(np.abs(at - r["t"][i]))) if at.size else None
            print(f"    {r['t'][i]:6.3f}  {feet[int(r['next_foot'][i])]:5s} {r['next_x'][i]:6.3f} {r['next_y'][i]:+.3f} "
                  f"at {r['next_touchdown_time'][i]:.3f}  DCM {r['dcm_x'][i]:6.3f} {r['dcm_y'][i]:+.3f}"
                  + ("" if k is None else f"  ankles {ankles[k][1]:6.3f} {ankles[k][2]:6.3f}  z {ankles[k][3]:.3f} "
                                          f"{ankles[k][4]:.3f}")
                  + ("" if np.isnan(r["next_crossing_height"][i]) else "  X"))
    crossing = np.flatnonzero(r["crossing_nodes"] > 0)
    if crossing.size:  # the MPC from the first replan whose horizon holds a crossing swing, every 0.1 s
        rows = range(int(crossing[0]), len(r["t"]), 5)
        print("  MPC (t, cost, ok, crossing nodes): " + "  ".join(
            f"{r['t'][i]:.2f} {r['mpc_cost'][i]:.1e} {int(r['mpc_ok'][i])} {int(r['crossing_nodes'][i])}"
            for i in rows))
    for t, top in terms:
        print(f"  terms at {t:.2f}: " + ", ".join(f"{name} {value:.1e}" for name, value in top))
    failed = r["t"][r["mpc_ok"] < 0.5]
    cost = r["mpc_cost"]
    big = r["t"][np.isfinite(cost) & (cost > 1e7)]
    print(f"  first box contact: {contacts.touches[0] if contacts.touches else None}  "
          f"({len(contacts.touches)} ticks)")
    print(f"  crossed (every sole sphere beyond the far edge): {contacts.crossed_time}  "
          f"lowest clearance over the box: {contacts.clearance:.3f} m")
    print(f"  MPC failures: {failed.size}" + (f" from {failed[0]:.3f} s" if failed.size else "")
          + (f"; cost > 1e7 from {big[0]:.3f} s" if big.size else "")
          + (f"; cold restarts at {', '.join(f'{t:.2f}' for t in r['t'][r['mpc_restart'] > 0.5])} s"
             if "mpc_restart" in r and np.any(r["mpc_restart"] > 0.5) else ""))
    print(f"  status {log.status}  fall {log.fall_time} ({log.fall_reason})  error {log.error}")
    iterations = r["mpc_iterations"][1:]  # the first update is the cold start
    if iterations.size:
        print(f"  FDDP iterations per update: mean {np.mean(iterations):.1f}, median {np.median(iterations):.0f}, "
              f"max {np.max(iterations):.0f}  (real-time factor {log.metrics.get('real_time_factor') or float('nan'):.3f})")
    dcm = log.ticks.get("dcm")
    if dcm is not None:
        print(f"  final DCM x {dcm[-1, 0]:.3f}  CoM x {log.ticks['com'][-1, 0]:.3f}")


if __name__ == "__main__":
    main()
