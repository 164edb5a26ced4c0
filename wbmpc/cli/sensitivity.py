"""``wbmpc sensitivity``: DCM sensitivity of the footstep QP (eqs. 9-12) by four routes, and Fig. 2
(``--wrt step-qp``, the default); the whole-body OCP's sensitivity to the touchdown times by three
routes (``--wrt contact-timing``); the end-to-end du0/dθ from a DCM disturbance to the first
torques (``--wrt dcm``). ``--planner alip``: the ALIP step-to-step NMPC's (ℓ*, T*, τ*) with respect to
the measured ALIP state, t_curr and the command, by three routes (``sensitivity.alip_crosscheck``)."""

from __future__ import annotations

import argparse

import numpy as np

from sensitivity.crosscheck import crosscheck
from sensitivity.studies.fig2 import plot_fig2, run_monte_carlo
from sequencer.step_qp import CONSTRAINT_NAMES, VARIABLE_NAMES, StepProblem
from wbmpc.cli.arguments import COUNT, FINITE, POSITIVE, SEED
from wbmpc.cli.output import add_output_arguments, print_json
from wbmpc.cli.plan import add_params_arguments, add_state_arguments, alip_params_from_args, params_from_args, state_from_args
from wbmpc.errors import ParameterError


def sensitivity_report(problem: StepProblem, samples: int, sigma: float, seed: int) -> dict:
    """Everything the subcommand prints: x*, dx*/dtheta per route, active set, Monte Carlo check."""
    check = crosscheck(problem)
    study = run_monte_carlo(problem, samples=samples, sigma=sigma, seed=seed)
    return {
        "x": dict(zip(VARIABLE_NAMES, check.x)),
        "touchdown_duration": float(np.log(check.x[2]) / problem.omega),
        "dx_dtheta": check.jacobians["analytic"],
        "dx_dtheta_rows": list(VARIABLE_NAMES),
        "active_set": [name for name, on in zip(CONSTRAINT_NAMES, check.active) if on],
        "jacobians": check.jacobians,
        "max_disagreement": check.max_disagreement,
        "worst_route": check.worst_route,
        "monte_carlo": {
            "samples": samples, "sigma": sigma, "seed": seed,
            "max_linearisation_error_p_T_y": study.max_linearisation_error[0],
            "max_linearisation_error_b_T_y": study.max_linearisation_error[1],
            "samples_with_other_active_set": study.n_active_changed,
        },
        "_study": study,
    }


def format_report(report: dict) -> str:
    x = report["x"]
    J = np.asarray(report["dx_dtheta"])
    lines = ["x* = " + ", ".join(f"{k}={v:+.6g}" for k, v in x.items()) + f"  (T = {report['touchdown_duration']:.4f} s)",
             f"active set: {report['active_set'] or 'none'}",
             "dx*/dtheta (analytic, eq. 10):      d/dtheta_x     d/dtheta_y"]
    for name, row in zip(report["dx_dtheta_rows"], J):
        lines.append(f"  {name:>8} {row[0]:>+14.6g} {row[1]:>+14.6g}")
    lines.append(f"largest disagreement between routes: {report['max_disagreement']:.3g} ({report['worst_route']} "
                 "vs analytic; routes: CasADi/IPOPT, central finite differences, ProxQP compute_backward)")
    mc = report["monte_carlo"]
    lines.append(f"Monte Carlo ({mc['samples']} samples, sigma {mc['sigma']} m): max |re-solve - plane| "
                 f"p_T,y {mc['max_linearisation_error_p_T_y']:.3g} m, b_T,y {mc['max_linearisation_error_b_T_y']:.3g} m, "
                 f"{mc['samples_with_other_active_set']} samples with another active set")
    return "\n".join(lines)


WRT = ("step-qp", "contact-timing", "dcm")


def timing_report(robot: str, n_nodes: int | None, fd_step: float | None) -> dict:
    """``--wrt contact-timing``: a standing robot's walking OCP (the preset's node spacing, N default the
    preset's) and its du0/dτ, dK0/dτ, dforces0/dτ, dCoM_N/dτ by route."""
    from wbmpc.walking.preset import load_walking_preset
    from wbmpc.walking.timing import (
        contact_timing_sensitivity,
        gain_reaction_by_joint,
        standing_start_timing_ocp,
        state_tangent_names,
    )

    controller = load_walking_preset(robot).controller
    n_nodes = controller.n_nodes if n_nodes is None else n_nodes
    timed = standing_start_timing_ocp(robot, n_nodes=n_nodes, dt=controller.node_dt)
    solver = timed.solve(th_stop=1e-17)
    kwargs = {} if fd_step is None else {"fd_step": fd_step}
    result = contact_timing_sensitivity(timed, solver, **kwargs)
    model = timed.ocp.state.pinocchio
    names = {"u0": "du0_dtau", "K0": "dK0_dtau", "forces0": "dforces0_dtau", "com_terminal": "dcom_terminal_dtau"}
    routes = {route: {names[key]: out[key] for key in names if key in out} for route, out in result.routes.items()}
    joints, tangent = list(model.names[2:]), state_tangent_names(model)
    return {
        "robot": robot, "n_nodes": n_nodes, "dt_s": timed.ocp.dt, "parameters": result.parameter_names,
        "touchdown_times_s": result.touchdown_times, "double_support_s": float(timed.plan.double_support),
        "joints": joints, "state_tangent": tangent,
        "stance_feet_node0": list(timed.problem.running_models[0].differential.active_contacts),
        "units": {"du0_dtau": "N·m/s", "dK0_dtau": "(N·m per unit of the state_tangent component)/s",
                  "dforces0_dtau": "N/s (6D contacts: force N/s, then moment N·m/s)", "dcom_terminal_dtau": "m/s"},
        "routes": routes, "disagreement": result.disagreement,
        "max_relative_disagreement": result.max_relative_disagreement,
        "gains": {"K0": result.gains["K0"], "sign": "SolverFDDP.K: u = u* + K (x ⊖ x*)",
                  "regularization": result.gains["regularization"], "block_steps_s": result.gains["block_steps"],
                  "solver_K0_gap": result.gains["solver_K0_gap"],
                  "by_joint": gain_reaction_by_joint(result.gains["K0"], result.dK_dtouchdown, joints, tangent)},
        "gauss_newton": {"du0_dtau": result.gauss_newton["outputs"]["u0"],
                         "relative_gap": result.gauss_newton["gap_to_finite_differences"]},
        "cost": result.cost, "settings": result.settings,
    }


def dcm_report(n_nodes: int, fd_step: float | None) -> dict:
    """``--wrt dcm``: the end-to-end du0/dθ and its check against the whole chain."""
    from wbmpc.walking.timing import dcm_sensitivity

    result = dcm_sensitivity("bolt", n_nodes=n_nodes, **({} if fd_step is None else {"fd_step": fd_step}))
    return {"robot": "bolt", "n_nodes": n_nodes, "units": {"du0_dtheta": "N·m/m", "dtau_dtheta": "s/m"}, **result}


def format_timing(report: dict) -> str:
    lines = [f"{report['robot']} walking OCP, N={report['n_nodes']}, dt={report['dt_s']} s, double support "
             f"{report['double_support_s']} s: touchdowns "
             + ", ".join(f"{n} {t:.4f} s" for n, t in zip(report["parameters"], report["touchdown_times_s"])),
             "du0/dtau [N·m/s] (Riccati sweep, exact Hessian):"]
    J = np.asarray(report["routes"]["riccati"]["du0_dtau"])
    for name, row in zip(report["joints"], J):
        lines.append(f"  {name:>14} " + " ".join(f"{v:>+10.4g}" for v in row))
    for pair, gaps in report["disagreement"].items():
        lines.append(f"  {pair}: " + ", ".join(f"{k} {v:.2e}" for k, v in gaps.items()))
    lines.append(f"largest relative disagreement between routes: {report['max_relative_disagreement']:.2e}")
    lines.append("first gains K0: the joints whose gains move most, ||dK0_i/dtau|| [N·m/(state unit)/s] and relative "
                 "to ||K0_i|| [1/s], per touchdown:")
    by_joint = report["gains"]["by_joint"]
    for row in by_joint[:5]:
        lines.append(f"  {row['joint']:>26} " + " ".join(f"{a:>9.3g} ({b:.3g}/s)" for a, b in
                                                        zip(row["dK_norm_per_s"], row["relative_per_s"]))
                     + f"  largest on {row['largest_column']}")
    lines.append("Gauss-Newton sweep (FDDP's factorisation) vs finite differences: "
                 + ", ".join(f"{k} {v:.2e}" for k, v in report["gauss_newton"]["relative_gap"].items()))
    c = report["cost"]
    lines.append(f"cost: sweep {c['sensitivity_sweep_s'] * 1e3:.3f} ms = {c['sweep_over_riccati']:.2f} Riccati pass "
                 f"({c['riccati_pass_s'] * 1e3:.3f} ms); exact Hessian {c['exact_hessian_s']:.3f} s; "
                 f"re-solves {c.get('finite_differences_s', float('nan')):.3f} s; gains: block differences "
                 f"{c['gain_block_derivatives_s']:.3f} s, recursion {c['gain_recursion_s'] * 1e3:.3f} ms = "
                 f"{c['gain_recursion_over_riccati']:.2f} Riccati pass")
    return "\n".join(lines)


def format_dcm(report: dict) -> str:
    J = np.asarray(report["du0_dtheta"])
    lines = ["du0/dtheta [N·m/m] (columns theta_x, theta_y):"]
    for i, row in enumerate(J):
        lines.append(f"  u{i} {row[0]:>+11.5g} {row[1]:>+11.5g}")
    for pair, gap in report["disagreement"].items():
        lines.append(f"  {pair}: {gap:.2e}")
    return "\n".join(lines)


def plot_timing(report: dict, path: str) -> None:
    """Bars per joint, one group per touchdown: du0/dτ (top) and the relative change of the joint's
    first gains, ‖dK0_i/dτ‖ / ‖K0_i‖ per 10 ms (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    J = np.asarray(report["routes"]["riccati"]["du0_dtau"])
    joints = report["joints"]
    relative = {row["joint"]: np.asarray(row["relative_per_s"]) for row in report["gains"]["by_joint"]}
    R = 100.0 * 0.01 * np.array([relative[name] for name in joints])  # % of the row per 10 ms
    fig, axes = plt.subplots(2, 1, figsize=(max(8.0, 0.45 * len(joints)), 6.5), sharex=True)
    width = 0.8 / J.shape[1]
    for values, ax in ((J, axes[0]), (R, axes[1])):
        for j, name in enumerate(report["parameters"]):
            ax.bar(np.arange(len(joints)) + (j - (J.shape[1] - 1) / 2) * width, values[:, j], width,
                   label=f"{name} ({report['touchdown_times_s'][j]:.3f} s)")
        ax.axhline(0.0, color="k", lw=0.6)
    axes[1].set_xticks(np.arange(len(joints)), [name.removesuffix("_joint") for name in joints], rotation=60, ha="right")
    axes[0].set_ylabel("du0/dτ [N·m/s]")
    axes[1].set_ylabel("‖dK0_i‖ / ‖K0_i‖ [% per 10 ms]")
    axes[0].legend()
    axes[0].set_title(f"{report['robot']}: first torques and first gains of the whole-body MPC vs the touchdown times")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


ALIP_UNITS = {"T": "s", "tau": "N·m", "l": "m", "p_x": "m", "L_y": "kg·m²/s", "p_y": "m", "L_x": "kg·m²/s", "t_curr": "s",
              "v_x": "m/s", "v_y": "m/s", "yaw_rate": "rad/s"}


def alip_instance_from_args(args: argparse.Namespace, params):
    """The ALIP NMPC instance of ``--planner alip``: ``--alip-state`` or the orbit of the command (--vx, --vy) at
    ``--t`` (default 0.1 s) into a ``--stance-foot`` (default left) stance, plus the ``--push`` impulse."""
    from sequencer.alip.instances import orbit_state
    from sequencer.alip.nlp import AlipInstance

    foot = args.stance_foot or "left"
    t_curr = 0.1 if args.elapsed is None else float(args.elapsed)
    v_x, v_y = args.param_v_x or 0.0, args.param_v_y or 0.0
    params.check_velocity(v_x, v_y)
    x0 = np.array(args.alip_state, dtype=float) if args.alip_state is not None else orbit_state(params, v_x, v_y, foot, t_curr)
    if args.push is not None:
        x0 = x0 + params.model.impulse_state_change(args.push, (x0[0], x0[2]))
    return AlipInstance(x0, t_curr, foot, v_x, v_y, args.yaw_rate)


def alip_report(params, instance, fd_step: float) -> dict:
    """``--planner alip``: d(T, τ, ℓ)/dθ by route, disagreement, active bounds, active-set changes, cost."""
    from sensitivity.alip_crosscheck import AlipSensitivityAnalysis

    analysis = AlipSensitivityAnalysis(params, fd_step=fd_step)
    check = analysis.crosscheck(instance)
    K = analysis.nlp.K
    names = analysis.nlp.names[:5 * K]
    solution = check.solution
    return {
        "planner": "alip", "params": params.to_dict(),
        "instance": {"x0": instance.x0, "t_curr": instance.t_curr, "stance_foot": instance.stance_foot,
                     "v_x": instance.v_x, "v_y": instance.v_y, "yaw_rate": instance.yaw_rate},
        "solution": {"periods": solution.periods, "torques": solution.torques, "steps": solution.steps,
                     "cost": solution.cost},
        "parameters": list(check.parameters), "outputs": list(names),
        "units": {"rows": "T_k [s], tau_k [N·m], l_k [m] (heading frame of step k)",
                  "columns": {name: ALIP_UNITS[name] for name in check.parameters}},
        "routes": {name: sens.decision_jacobian for name, sens in check.routes.items()},
        "disagreement": {name: dict(zip(check.parameters, d)) for name, d in check.disagreement.items()},
        "max_relative_disagreement": check.max_relative_disagreement,
        "active_bounds": list(check.active.names), "weakly_active": list(check.active.weakly_active),
        "differentiable": check.active.differentiable,
        "fd_step": fd_step, "fd_steps": dict(zip(check.parameters, check.fd_steps)),
        "fd_active_set_changes": [
            {"parameter": c.parameter, "step": c.step, "plus_entered": c.plus_entered, "plus_left": c.plus_left,
             "minus_entered": c.minus_entered, "minus_left": c.minus_left, "forward": c.forward[:5 * K],
             "backward": c.backward[:5 * K]} for c in check.fd_changes],
        "cost_ms": {key.removesuffix("_s"): value * 1e3 for key, value in check.cost.items()},
    }


def format_alip(report: dict) -> str:
    inst, sol = report["instance"], report["solution"]
    params = report["parameters"]
    lines = [f"ALIP NMPC ({report['params']['name']}): {inst['stance_foot']} stance, t_curr = {inst['t_curr']:.3f} s, "
             f"x0 = " + ", ".join(f"{v:+.4g}" for v in inst["x0"]) + f", command ({inst['v_x']:+.3g}, {inst['v_y']:+.3g}, "
             f"{inst['yaw_rate']:+.3g})",
             "T* = " + ", ".join(f"{v:.4f}" for v in sol["periods"]) + " s; l*_0 = "
             + ", ".join(f"{v:+.4f}" for v in sol["steps"][0]) + " m",
             f"active bounds: {', '.join(report['active_bounds']) or 'none'}"
             + (f"; weakly active (one-sided derivatives): {', '.join(report['weakly_active'])}"
                if report["weakly_active"] else ""),
             "d(first step)/dθ (route kkt):" + "".join(f"{p:>11}" for p in params)]
    J = np.asarray(report["routes"]["kkt"])
    outputs = report["outputs"]
    for name in ("T_0", "tau_y_0", "tau_x_0", "l_x_0", "l_y_0"):
        lines.append(f"  {name:>26} " + "".join(f"{v:>+11.4g}" for v in J[outputs.index(name)]))
    lines.append(f"largest relative disagreement between routes: {report['max_relative_disagreement']:.2e} "
                 "(CasADi's solver derivative, re-solved central differences, vs the KKT route)")
    for change in report["fd_active_set_changes"]:
        lines.append(f"  active set changes within the FD step of {change['parameter']} (+: entered "
                     f"{change['plus_entered'] or '-'}, left {change['plus_left'] or '-'}; -: entered "
                     f"{change['minus_entered'] or '-'}, left {change['minus_left'] or '-'}): no central difference")
    lines.append("cost: " + ", ".join(f"{k} {v:.2f} ms" for k, v in report["cost_ms"].items()))
    return "\n".join(lines)


def run_alip_sensitivity(args: argparse.Namespace) -> int:
    from sensitivity.alip_finite_differences import DEFAULT_FD_STEP

    given = [flag for flag, value in (("--stance-position", args.stance_position), ("--dcm", args.dcm),
                                      ("--plot", args.plot)) if value is not None]
    if args.wrt != "step-qp":
        given.append("--wrt")
    if given:
        raise ParameterError(f"{given} are options of --planner dcm; --planner alip takes the ALIP state (--alip-state, "
                             "--push, --t, --stance-foot), the command (--vx, --vy, --yaw-rate), --fd-step, --params, --robot")
    params = alip_params_from_args(args)
    report = alip_report(params, alip_instance_from_args(args, params),
                         DEFAULT_FD_STEP if args.fd_step is None else args.fd_step)
    if args.json:
        print_json(report)
    else:
        print(format_alip(report))
    return 0


def run_sensitivity(args: argparse.Namespace) -> int:
    if args.planner == "alip":
        return run_alip_sensitivity(args)
    alip_only = [flag for flag, value in (("--alip-state", args.alip_state), ("--push", args.push)) if value is not None]
    if alip_only or args.yaw_rate != 0.0:
        raise ParameterError(f"{alip_only or ['--yaw-rate']} are options of --planner alip")
    if args.wrt != "step-qp":
        if args.wrt == "dcm" and args.robot not in (None, "bolt"):
            raise ParameterError(f"--robot {args.robot}: --wrt dcm (the end-to-end chain) is built for bolt only")
        if args.wrt == "contact-timing":
            report = timing_report(args.robot or "bolt", args.nodes, args.fd_step)
        else:
            report = dcm_report(100 if args.nodes is None else args.nodes, args.fd_step)
        if args.plot and args.wrt == "contact-timing":
            plot_timing(report, args.plot)
        if args.json:
            print_json(report)
        else:
            print(format_timing(report) if args.wrt == "contact-timing" else format_dcm(report))
        return 0
    params = params_from_args(args)
    problem = StepProblem.from_params(params, *state_from_args(args))
    report = sensitivity_report(problem, args.samples, args.sigma, args.seed)
    study = report.pop("_study")
    if args.plot:
        plot_fig2(study, args.plot)
    if args.json:
        print_json(report)
    else:
        print(format_report(report))
        if args.plot:
            print(f"wrote {args.plot}")
    return 0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "sensitivity", help="DCM sensitivity of the footstep QP (analytic, CasADi, FD, ProxQP) and Fig. 2",
        description="Sensitivity of the one-step footstep QP to a disturbance theta on the measured DCM "
        "(default: the Table I example).",
    )
    add_params_arguments(parser)
    add_state_arguments(parser)
    parser.add_argument("--samples", type=COUNT, default=1000, help="Monte Carlo samples for Fig. 2 (default 1000)")
    parser.add_argument("--sigma", type=POSITIVE, default=0.005, help="std of each theta component [m] (default 0.005)")
    parser.add_argument("--seed", type=SEED, default=0, help="seed of the Monte Carlo samples")
    parser.add_argument("--wrt", choices=WRT, default="step-qp",
                        help="step-qp: the footstep QP to the DCM (default); contact-timing: the whole-body OCP's u0, "
                        "first gains K0, node-0 forces and terminal CoM to the touchdown times (--robot, default "
                        "bolt); dcm: the end-to-end du0/dtheta (bolt)")
    parser.add_argument("--fd-step", type=POSITIVE, default=None,
                        help="central-difference step of the re-solved route: [s] for contact-timing (default 2e-5), "
                        "[m] for dcm (default 1e-4); for --planner alip relative to each parameter's unit (default 1e-6)")
    parser.add_argument("--planner", choices=("dcm", "alip"), default="dcm",
                        help="dcm: the footstep QP / whole-body OCP (--wrt, default); alip: the ALIP S2S NMPC's steps, "
                        "periods and ankle torques to the measured ALIP state, t_curr and the command (preset "
                        "sequencer/presets/alip/ROBOT.toml, --robot default g1)")
    alip = parser.add_argument_group("--planner alip (default state: the command's orbit at --t, default 0.1 s)")
    alip.add_argument("--alip-state", nargs=4, type=FINITE, metavar=("PX", "LY", "PY", "LX"), default=None,
                      help="measured ALIP state about the stance contact, heading frame [m, kg·m²/s, m, kg·m²/s]")
    alip.add_argument("--push", nargs=2, type=FINITE, metavar=("DPX", "DPY"), default=None,
                      help="horizontal impulse on the CoM added to the state [N·s] (L_y += z DPX, L_x -= z DPY)")
    alip.add_argument("--yaw-rate", type=FINITE, default=0.0, help="commanded turning rate [rad/s]")
    parser.add_argument("--nodes", type=COUNT, default=None,
                        help="OCP horizon N for contact-timing (default the --robot's preset, bolt 100, g1 50) and dcm "
                        "(default 100)")
    add_output_arguments(parser, plot=True)
    parser.set_defaults(func=run_sensitivity)
