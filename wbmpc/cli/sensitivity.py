"""``wbmpc sensitivity``: DCM sensitivity of the footstep QP (eqs. 9-12) by four routes, and Fig. 2."""

from __future__ import annotations

import argparse

import numpy as np

from sensitivity.crosscheck import crosscheck
from sensitivity.studies.fig2 import plot_fig2, run_monte_carlo
from sequencer.step_qp import CONSTRAINT_NAMES, VARIABLE_NAMES, StepProblem
from wbmpc.cli.arguments import COUNT, POSITIVE, SEED
from wbmpc.cli.output import add_output_arguments, print_json
from wbmpc.cli.plan import add_params_arguments, add_state_arguments, params_from_args, state_from_args


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


def run_sensitivity(args: argparse.Namespace) -> int:
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
    add_output_arguments(parser, plot=True)
    parser.set_defaults(func=run_sensitivity)
