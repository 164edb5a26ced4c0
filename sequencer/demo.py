"""``wbmpc demo``: the interim main job — plan the Table I sequence, print it, draw Fig. 3 and Fig. 2.

Kept as one small module so that the closed-loop walking run can replace it by swapping the
module path in ``wbmpc.cli.SUBCOMMAND_MODULES``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from sensitivity.cli import format_report, sensitivity_report
from sensitivity.studies.fig2 import plot_fig2
from sequencer.cli import TABLE_I_DCM, TABLE_I_ELAPSED, TABLE_I_STANCE_FOOT, TABLE_I_STANCE_POSITION, plan_table
from sequencer.horizon import FootstepSequencer
from sequencer.params import SequencerParams
from sequencer.plots import plot_plan
from sequencer.step_qp import StepProblem
from wbmpc.cli import add_output_arguments, print_json


def run_demo(out: str | Path, as_json: bool = False) -> dict:
    """Plan Table I's sequence (H_u = 3 s) and its sensitivity; write plan.png and sensitivity.png in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    params = SequencerParams.table_i()
    plan = FootstepSequencer(params).plan(
        t=TABLE_I_ELAPSED, stance_foot=TABLE_I_STANCE_FOOT, stance_position=TABLE_I_STANCE_POSITION,
        dcm_measured=TABLE_I_DCM, t_stance_start=0.0,
    )
    plot_plan(plan, params, str(out / "plan.png"))
    problem = StepProblem.from_params(params, TABLE_I_STANCE_FOOT, TABLE_I_STANCE_POSITION, TABLE_I_DCM, TABLE_I_ELAPSED)
    report = sensitivity_report(problem, samples=1000, sigma=0.005, seed=0)
    plot_fig2(report.pop("_study"), str(out / "sensitivity.png"))
    if not as_json:
        print(plan_table(plan))
        print()
        print(format_report(report))
        print(f"\nwrote {out / 'plan.png'} (Fig. 3) and {out / 'sensitivity.png'} (Fig. 2)")
    return {"plan": plan, "mean_velocity": plan.mean_velocity(), "sensitivity": report,
            "figures": [str(out / "plan.png"), str(out / "sensitivity.png")]}


def register(subparsers) -> None:
    parser = subparsers.add_parser("demo", help="main job (interim): Table I footstep plan, Fig. 3 and Fig. 2")
    parser.add_argument("--out", default="runs/demo", help="output directory (default runs/demo)")
    add_output_arguments(parser, plot=False)

    def run(args: argparse.Namespace) -> int:
        result = run_demo(args.out, as_json=args.json)
        if args.json:
            print_json(result)
        return 0

    parser.set_defaults(func=run)
