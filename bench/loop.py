"""Closed-loop real-time factor and where the time goes (simulation, sequencer, MPC, feedback).

Runs the ``walk`` scenario of ``--robot``'s walking preset (Bolt: sequencer + MPC at 100 Hz; G1:
at 50 Hz; 1 kHz Riccati feedback) for ``--duration`` simulated seconds and reports:

- the real-time factor (simulated time / wall time; the issues' targets: Bolt >= 1.5 on one core,
  G1 >= 1.0);
- the share of the wall time spent in MuJoCo stepping, the sequencer, the MPC update, the 1 kHz
  feedback and the runner's own bookkeeping (state conversion, kinematics, logging);
- as the in-run baseline, the cost of bare ``mj_step`` on the same model measured in the same
  process, and the loop's cost per tick as a multiple of it (machine-independent ratio);
- with ``--baseline crocoddyl`` (the default when Crocoddyl is installed), the same scenario run
  with Crocoddyl's FDDP as the MPC solver (:mod:`bench.crocoddyl_loop`): its real-time factor,
  ours over it, and the largest difference between the two runs' torques. The runs go ours,
  Crocoddyl, Crocoddyl, ours, and the ratio uses both of each, so that a drift of the shared
  machine's speed during the benchmark (25 % within minutes was seen) cancels to first order;
  likewise our MPC cycle (update + its preparation) over Crocoddyl's MPC tick, medians of both
  runs of each. A preset whose walking OCP has no Crocoddyl twin (the H1's) is compared on its
  twin-able variant (:func:`bench.crocoddyl_loop.crocoddyl_twinnable_variant`, the fields it
  replaces are reported): the four runs are then all on the variant, after the headline run of
  ours on the preset.

``--set NAME=VALUE`` (repeatable) overrides the walking preset for every run of the benchmark, in the
form of :func:`wbmpc.walking.preset.load_walking_preset`'s overrides (``--set ocp.rollout_dynamics=compiled``:
the H1's rollouts compiled; ``--set n_nodes=80``); the report names them. Alternate runs with and without
an override to compare them on a shared machine.
"""

from __future__ import annotations

import argparse
import time

#: the issues' real-time targets: Bolt 1.5 on one core, the G1 (MPC at 50 Hz) 1.0
TARGET_REAL_TIME_FACTOR = {"bolt": 1.5, "g1": 1.0}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--duration", type=float, default=5.0, help="simulated time [s]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scenario", default="walk", help="scenario to run (default: walk)")
    parser.add_argument("--robot", default="bolt", metavar="NAME", help="robot (default: bolt)")
    parser.add_argument(
        "--max-iterations", type=int, default=None, help="FDDP iterations per MPC update (default: the controller's, 1)"
    )
    parser.add_argument(
        "--baseline", choices=("crocoddyl", "none"), default="crocoddyl",
        help="also run the loop with Crocoddyl's FDDP as the MPC solver (default; skipped if Crocoddyl is absent)",
    )
    # --set NAME=VALUE (args.overrides, a list of (name, value)): wbmpc.cli.bench adds it, with the CLI's parser


def preset_overrides(args: argparse.Namespace) -> dict:
    """The walking-preset overrides of ``--set`` (``{}`` without; a Namespace built without the option too)."""
    return dict(getattr(args, "overrides", None) or ())


def _bare_step_time(robot_name: str = "bolt", n_steps: int = 3000) -> float:
    """Wall time of one bare ``mj_step`` of the robot standing [s] (median of 3 batches)."""
    import mujoco
    import numpy as np

    from robots import load_robot
    from robots.conventions import pinocchio_to_mujoco_state
    from robots.mujoco_model import build_mujoco_spec

    robot = load_robot(robot_name)
    model = build_mujoco_spec(robot, link_collisions=True).compile()
    data = mujoco.MjData(model)
    batches = []
    for _ in range(3):
        data.qpos[:], data.qvel[:] = pinocchio_to_mujoco_state(robot, robot.q_reference, robot.v_reference)
        mujoco.mj_forward(model, data)
        tic = time.perf_counter()
        for _ in range(n_steps // 3):
            mujoco.mj_step(model, data)
        batches.append((time.perf_counter() - tic) / (n_steps // 3))
    return float(np.median(batches))


def pinocchio_floor(mpc, rollouts_per_update: float, repeats: int = 10) -> dict:
    """Pinocchio's own share of one MPC update, timed call by call at the MPC's last solution.

    Each update evaluates, at every node, the contact dynamics (``constraintDynamics``; ABA at a
    flight node) and their derivatives (``computeConstraintDynamicsDerivatives``), and the contact
    dynamics again in each rollout of the line search. Timing these calls alone (on each node's
    own contact set and state, ``repeats`` times, best of 3 rounds) gives the time an update needs
    whatever the code around them: the floor of the MPC's cycle on this machine.

    Returns:
        dynamics_per_node, derivatives_per_node: mean seconds per call over the nodes;
        per_update: N (dynamics (1 + rollouts_per_update) + derivatives) [s];
        per_update_one_rollout: the same with a single rollout (every full step accepted) [s].
    """
    import numpy as np
    import pinocchio as pin

    problem, solution = mpc.problem, mpc.last_good
    model = problem.state.pinocchio
    nq, nv = model.nq, model.nv
    plain = model.createData()
    contact_sets: dict = {}  # one data per contact set, initialised for it (as the batched problem keeps them)
    calls = []
    for k, running in enumerate(problem.running_models):
        dam = running.differential
        q, v = solution.xs[k][:nq].copy(), solution.xs[k][nq:].copy()
        tau = np.zeros(nv)
        tau[nv - problem.nu:] = solution.us[k]
        if dam.nc:
            constraints, settings = dam.active_constraints, dam.proximal_settings
            if dam.active_key not in contact_sets:
                set_data = model.createData()
                constraint_datas = pin.StdVec_RigidConstraintData()
                for constraint in constraints:
                    constraint_datas.append(constraint.createData())
                pin.initConstraintDynamics(model, set_data, constraints, constraint_datas)
                contact_sets[dam.active_key] = (set_data, constraint_datas)
            data, constraint_datas = contact_sets[dam.active_key]
            calls.append((
                lambda q=q, v=v, tau=tau, c=constraints, data=data, d=constraint_datas, s=settings:
                    pin.constraintDynamics(model, data, q, v, tau, c, d, s),
                lambda c=constraints, data=data, d=constraint_datas, s=settings:
                    pin.computeConstraintDynamicsDerivatives(model, data, c, d, s),
            ))
        else:
            calls.append((lambda q=q, v=v, tau=tau: pin.aba(model, plain, q, v, tau),
                          lambda q=q, v=v, tau=tau: pin.computeABADerivatives(model, plain, q, v, tau)))
    dynamics = derivatives = float("inf")
    for _ in range(3):
        dyn = der = 0.0
        for calc, diff in calls:
            tic = time.perf_counter()
            for _ in range(repeats):
                calc()
            dyn += time.perf_counter() - tic
            for _ in range(repeats):  # each derivative call timed alone after its dynamics (not as a difference
                calc()                # of two timings, which a loaded machine can make negative)
                tic = time.perf_counter()
                diff()
                der += time.perf_counter() - tic
        dynamics, derivatives = min(dynamics, dyn / repeats), min(derivatives, der / repeats)
    n = len(calls)
    return {
        "dynamics_per_node": dynamics / n,
        "derivatives_per_node": derivatives / n,
        "rollouts_per_update": rollouts_per_update,
        "per_update": dynamics * (1.0 + rollouts_per_update) + derivatives,
        "per_update_one_rollout": 2.0 * dynamics + derivatives,
    }


def _run_loop(args: argparse.Namespace, controller_class=None, overrides: dict | None = None):
    """One run of the benchmarked closed loop with a walking controller of ``controller_class``
    (default :class:`~wbmpc.walking.controller.WalkingController`) built as ``run_scenario`` builds its own
    (the scenario's velocity command, ``--max-iterations``), on the robot's preset for the scenario (its
    ``[scenarios.<name>]`` table, as ``run_scenario`` loads it) with ``--set``'s overrides, then ``overrides``
    (``{"ocp.<field>": value}``, e.g. the Crocoddyl-twin-able variant's); returns (log, controller)."""
    from sim.runner import run_scenario
    from wbmpc.walking.controller import WalkingController
    from wbmpc.walking.preset import load_walking_preset

    robot = args.robot
    extra = {} if args.max_iterations is None else {"max_iterations": args.max_iterations}
    extra.update(preset_overrides(args))
    extra.update(overrides or {})
    controller = (controller_class or WalkingController)(load_walking_preset(robot, extra, scenario=args.scenario))
    log = run_scenario(args.scenario, robot=robot, duration=args.duration, seed=args.seed, progress=False,
                       controller=controller)
    return log, controller


def run(args: argparse.Namespace) -> dict:
    import numpy as np

    from wbmpc.walking.preset import load_walking_preset

    load_walking_preset(args.robot, preset_overrides(args), scenario=args.scenario)  # a bad --set: refused before any run
    bare = _bare_step_time(args.robot)
    log, controller = _run_loop(args)
    timing = dict(log.timing)
    total = timing["loop"]  # the ticks; the setup (models, cold first solve) is reported apart
    simulated = timing.get("simulated_time", 0.0)
    prepare = timing.get("mpc_prepare", 0.0)
    replan_other = timing["replan"] - timing.get("sequencer", 0.0) - timing.get("mpc", 0.0) - prepare
    shares = {
        "simulation": timing["simulation"] / total,
        "sequencer": timing.get("sequencer", 0.0) / total,
        "mpc update (measurement to solution)": timing.get("mpc", 0.0) / total,
        "mpc prepare (ahead of the next update)": prepare / total,
        "feedback": timing["feedback"] / total,
        "runner (state conversion, kinematics, logging)": (timing["logging"] + max(replan_other, 0.0)) / total,
    }
    shares["other (Python loop)"] = max(0.0, 1.0 - sum(shares.values()))
    n_ticks = len(log.ticks["t"])
    # What the loop would cost if the MPC were Pinocchio's calls and nothing else.
    n_updates = len(log.replans.get("t", ()))
    rollouts = log.replans.get("mpc_rollouts")
    floor = None
    if controller.mpc.last_good is not None and rollouts is not None and n_updates:
        floor = pinocchio_floor(controller.mpc, float(np.nanmean(rollouts[1:])))
        period = controller.replan_period
        outside = (total - timing.get("mpc", 0.0) - prepare) / n_updates  # per period: all but the MPC
        floor["outside_mpc_per_period"] = outside
        floor["mpc_per_update"] = (timing.get("mpc", 0.0) + prepare) / n_updates
        floor["best_real_time_factor"] = period / (floor["per_update"] + outside)
        floor["best_real_time_factor_one_rollout"] = period / (floor["per_update_one_rollout"] + outside)
    baseline = _crocoddyl_baseline(args, log, controller.preset) if args.baseline == "crocoddyl" else None
    return {
        "baseline": baseline,
        "scenario": args.scenario,
        "robot": args.robot,
        "preset_overrides": preset_overrides(args),
        "max_iterations": controller.config.max_iterations,
        "status": log.status,
        "simulated_time": simulated,
        "wall_time": total,
        "setup_time": timing["setup"],
        "real_time_factor": simulated / total if total > 0 else None,
        "target_real_time_factor": TARGET_REAL_TIME_FACTOR.get(args.robot, 1.0),
        "shares": shares,
        "bare_mj_step_time": bare,
        "loop_tick_over_bare_step": (total / n_ticks) / bare if n_ticks else None,
        "mpc_tick_time_median": log.metrics.get("mpc_tick_time_median"),
        "mpc_tick_time_p99": log.metrics.get("mpc_tick_time_p99"),
        "replan_period": controller.replan_period,
        "mpc_tick_over_replan_period": (log.metrics.get("mpc_tick_time_median") or 0.0) / controller.replan_period,
        "mpc_cycle_time_median": log.metrics.get("mpc_cycle_time_median"),
        "mpc_cycle_time_p99": log.metrics.get("mpc_cycle_time_p99"),
        "pinocchio_floor": floor,
    }


def _run_summary(log) -> dict:
    """Status and timing of one run of our loop [s]: what the baseline reports of each of ours."""
    simulated, wall = log.timing.get("simulated_time", 0.0), log.timing["loop"]
    return {"status": log.status, "simulated_time": simulated, "wall_time": wall,
            "real_time_factor": simulated / wall if wall > 0 else None,
            "mpc_tick_time_median": log.metrics.get("mpc_tick_time_median"),
            "mpc_cycle_time_median": log.metrics.get("mpc_cycle_time_median")}


def _crocoddyl_baseline(args: argparse.Namespace, ours_on_preset, preset) -> dict:
    """Our loop against the Crocoddyl-based one, runs ours, Crocoddyl, Crocoddyl, ours (a drift of the
    machine's speed cancels to first order), on one problem: the preset's when it has a Crocoddyl twin (ours
    is then ``ours_on_preset`` and one more run), else its twin-able variant
    (:func:`~bench.crocoddyl_loop.crocoddyl_twinnable_variant`, in ``"variant"``), on which both of ours
    are run anew. Returns the first Crocoddyl run's fields, both runs of each, the ratios and ``"variant"``
    (``{}``: the preset itself), or ``{"skipped": reason}``."""
    first = _crocoddyl_loop(args, ours_on_preset)
    variant: dict = {}
    ours_first = ours_on_preset
    if "no_twin" in first:  # the preset's OCP has no Crocoddyl twin: both loops on its twin-able variant
        from bench.crocoddyl_loop import crocoddyl_twinnable_variant
        from bench.crocoddyl_mirror import NoCrocoddylTwin

        try:
            variant = crocoddyl_twinnable_variant(preset, args.scenario)
        except NoCrocoddylTwin as err:
            return {"skipped": f"{first['skipped']}, and no twin-able variant: {err}"}
        preset_no_twin = first["skipped"]
        ours_first, _ = _run_loop(args, overrides=variant)
        first = {**_crocoddyl_loop(args, ours_first, variant), "preset_no_twin": preset_no_twin}
        if "skipped" in first:
            return {**first, "variant": variant}
    if "skipped" in first:
        return first
    second = _crocoddyl_loop(args, ours_first, variant)
    again, _ = _run_loop(args, overrides=variant)
    ours_rtf = ((ours_first.timing["simulated_time"] + again.timing["simulated_time"])
                / (ours_first.timing["loop"] + again.timing["loop"]))
    theirs_rtf = ((first["simulated_time"] + second["simulated_time"])
                  / (first["wall_time"] + second["wall_time"]))
    ours_cycle = 0.5 * sum(run_log.metrics.get("mpc_cycle_time_median") or run_log.metrics["mpc_tick_time_median"]
                           for run_log in (ours_first, again))
    ours_tick = 0.5 * sum(run_log.metrics["mpc_tick_time_median"] for run_log in (ours_first, again))
    theirs_tick = 0.5 * (first["mpc_tick_time_median"] + second["mpc_tick_time_median"])
    return {**first, "runs": [first, second], "real_time_factor": theirs_rtf,
            "ours_real_time_factor_both_runs": ours_rtf, "ratio": ours_rtf / theirs_rtf,
            "ours_mpc_cycle_both_runs": ours_cycle, "crocoddyl_mpc_tick_both_runs": theirs_tick,
            "mpc_cycle_ratio": ours_cycle / theirs_tick, "variant": variant,
            "ours_runs": [_run_summary(run_log) for run_log in (ours_first, again)],
            "ours_mpc_tick_both_runs": ours_tick}


def _crocoddyl_loop(args: argparse.Namespace, ours, overrides: dict | None = None) -> dict:
    """The same run with Crocoddyl's FDDP solving the MPC, on the robot's preset with ``overrides``; its
    real-time factor without the reference copies into the twin (see :mod:`bench.crocoddyl_loop`), and
    the largest difference of its torques to those of ``ours`` (a run log) over their common ticks.
    Returns ``{"skipped": reason}`` without Crocoddyl, and ``{"skipped": reason, "no_twin": message}``
    when that OCP has no Crocoddyl twin."""
    try:
        import crocoddyl  # noqa: F401
    except ImportError as err:
        return {"skipped": f"crocoddyl is not installed ({err}); pip install -e .[bench]"}
    import numpy as np

    from bench.crocoddyl_loop import CrocoddylWalkingController
    from bench.crocoddyl_mirror import NoCrocoddylTwin

    try:
        log, controller = _run_loop(args, CrocoddylWalkingController, overrides)
    except NoCrocoddylTwin as err:  # e.g. the H1's sole-weighted contact damping and obstacle clearance terms
        which = "its walking OCP" if not overrides else f"its walking OCP with {_overrides_text(overrides)}"
        return {"skipped": f"robot {args.robot!r}: {which} has {err}", "no_twin": str(err)}
    mirror = controller.mirror_seconds
    wall = log.timing["loop"] - mirror
    simulated = log.timing.get("simulated_time", 0.0)
    n = min(len(ours.ticks["tau"]), len(log.ticks["tau"]))
    return {
        "status": log.status,
        "simulated_time": simulated,
        "wall_time": wall,
        "mirror_copy_time_excluded": mirror,
        "real_time_factor": simulated / wall if wall > 0 else None,
        "mpc_tick_time_median": log.metrics.get("mpc_tick_time_median"),
        "max_torque_difference_Nm": float(np.max(np.abs(ours.ticks["tau"][:n] - log.ticks["tau"][:n]))) if n else None,
    }


def _overrides_text(overrides: dict) -> str:
    """``ocp.a='x', ocp.b=0`` (the ``--set`` form of preset overrides)."""
    return ", ".join(f"{name}={value!r}" for name, value in overrides.items())


def _runs_text(runs: list) -> str:
    """``completed 2.00 s, fell 1.22 s``: each run's status and simulated time."""
    return ", ".join(f"{run['status']} {run['simulated_time']:.2f} s" for run in runs)


def format_report(result: dict) -> str:
    overrides = result.get("preset_overrides")
    lines = [
        f"closed loop '{result['scenario']}' on the {result['robot']} preset"
        + (f" with {_overrides_text(overrides)}" if overrides else "") + f" ({result['status']}, "
        f"{result['max_iterations']} FDDP iteration(s) per "
        f"update): {result['simulated_time']:.2f} s simulated "
        f"in {result['wall_time']:.2f} s wall",
        f"  real-time factor        {result['real_time_factor']:.2f} x   (target >= {result['target_real_time_factor']})",
        f"  loop tick / bare mj_step {result['loop_tick_over_bare_step']:.1f} x   "
        f"(bare mj_step {result['bare_mj_step_time'] * 1e6:.1f} us, in-run baseline)",
    ]
    if result.get("mpc_tick_time_median") is not None:
        lines.append(
            f"  MPC tick median / p99   {result['mpc_tick_time_median'] * 1e3:.2f} / "
            f"{result['mpc_tick_time_p99'] * 1e3:.2f} ms  ({result['mpc_tick_over_replan_period']:.2f} of the "
            f"{result['replan_period'] * 1e3:.0f} ms period;"
            " measurement to solution)"
        )
    if result.get("mpc_cycle_time_median") is not None:
        lines.append(
            f"  MPC cycle median / p99  {result['mpc_cycle_time_median'] * 1e3:.2f} / "
            f"{result['mpc_cycle_time_p99'] * 1e3:.2f} ms  (update + the preparation made for it)"
        )
    floor = result.get("pinocchio_floor")
    if floor is not None:
        lines += [
            f"  Pinocchio alone, per MPC update: {floor['per_update'] * 1e3:.2f} ms "
            f"(contact dynamics {floor['dynamics_per_node'] * 1e6:.1f} us x (1 + {floor['rollouts_per_update']:.2f} "
            f"rollouts) + derivatives {floor['derivatives_per_node'] * 1e6:.1f} us, per node); "
            f"the MPC took {floor['mpc_per_update'] * 1e3:.2f} ms",
            f"    with all else per period ({floor['outside_mpc_per_period'] * 1e3:.2f} ms): best real-time factor "
            f"{floor['best_real_time_factor']:.2f} x, {floor['best_real_time_factor_one_rollout']:.2f} x "
            "if every full step were accepted",
        ]
    if result.get("setup_time") is not None:
        lines.append(f"  setup (models, first cold solve; not in the factor) {result['setup_time']:.2f} s")
    base = result.get("baseline")
    if base is not None and "skipped" in base:
        lines.append(f"  Crocoddyl baseline skipped: {base['skipped']}")
    elif base is not None and base.get("variant"):
        ours_runs, theirs_runs = _runs_text(base["ours_runs"]), _runs_text(base["runs"])
        lines += [
            f"  Crocoddyl baseline on the preset's twin-able variant, not on the preset ({base['preset_no_twin']}):",
            f"    the variant is the preset with {_overrides_text(base['variant'])}; both loops run it, "
            "ours, Crocoddyl, Crocoddyl, ours",
            f"    ours on the variant ({ours_runs}): real-time factor "
            f"{base['ours_real_time_factor_both_runs']:.2f} x, MPC tick median {base['ours_mpc_tick_both_runs'] * 1e3:.2f} ms",
            f"    Crocoddyl's FDDP as the solver on the variant ({theirs_runs}): "
            f"real-time factor {base['real_time_factor']:.2f} x, MPC tick median "
            f"{base['crocoddyl_mpc_tick_both_runs'] * 1e3:.2f} ms",
            f"    on the variant: ours / Crocoddyl {base['ratio']:.2f} (real-time factors, both runs of each)",
        ]
    elif base is not None:
        lines.append(
            f"  same loop, Crocoddyl's FDDP as the solver ({base['status']}): real-time factor "
            f"{base['real_time_factor']:.2f} x; ours {base['ours_real_time_factor_both_runs']:.2f} x -> "
            f"ours / Crocoddyl {base['ratio']:.2f}   (runs ours, Crocoddyl, Crocoddyl, ours)"
        )
    if base is not None and "skipped" not in base:
        lines.append(
            f"    MPC: our cycle {base['ours_mpc_cycle_both_runs'] * 1e3:.2f} ms, Crocoddyl's tick "
            f"{base['crocoddyl_mpc_tick_both_runs'] * 1e3:.2f} ms (medians, both runs) -> ours / Crocoddyl "
            f"{base['mpc_cycle_ratio']:.2f}"
        )
        lines.append(
            f"    (its reference copies into the twin, {base['mirror_copy_time_excluded']:.2f} s, excluded; "
            f"largest torque difference to ours {base['max_torque_difference_Nm']:.1e} N·m)"
        )
    lines.append("  share of wall time:")
    for name, share in result["shares"].items():
        lines.append(f"    {name:<48} {100 * share:5.1f} %")
    return "\n".join(lines)
