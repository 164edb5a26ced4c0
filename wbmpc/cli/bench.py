"""``wbmpc bench TARGET``: run one benchmark and print its figures (``--json`` for a dict).

Each target module (listed in ``BENCH_MODULES``) provides ``add_arguments(parser)`` and
``run(args) -> dict``, and a ``format_report(result) -> str`` for the human-readable table.
"""

from __future__ import annotations

import argparse
import importlib

from wbmpc.cli.arguments import (
    COUNT,
    DURATION,
    NON_NEGATIVE_INT,
    POSITIVE,
    SEED,
    NumberType,
    parse_assignment,
    restrict_numbers,
)
from wbmpc.cli.output import add_output_arguments, print_json

# target name -> module path (each module: add_arguments, run, format_report)
BENCH_MODULES: dict[str, str] = {
    "sequencer": "bench.sequencer",
    "loop": "bench.loop",
    "ddp": "bench.ddp",
    "campaign": "bench.campaign",
    "planner": "bench.planner",
}

# The checked type of every numeric option of each target (the targets declare them with plain int/float).
BENCH_NUMBERS: dict[str, dict[str, NumberType]] = {
    "sequencer": {"repeats": COUNT, "seed": SEED},
    "loop": {"duration": DURATION, "seed": SEED, "max_iterations": COUNT},
    "ddp": {"nodes": COUNT, "ticks": COUNT, "repeats": COUNT, "g1_nodes": NON_NEGATIVE_INT, "seed": SEED,
            "time_budget": POSITIVE},
    "campaign": {"trials": COUNT, "duration": DURATION, "rounds": COUNT},
    "planner": {"repeats": COUNT, "seed": SEED},
}

# The targets that take ``--set NAME=VALUE`` walking-preset overrides (``args.overrides``, (name, value) pairs).
BENCH_PRESET_OVERRIDES = {"loop"}


def register(subparsers) -> None:
    parser = subparsers.add_parser("bench", help="run a benchmark (ratios against an in-run baseline)")
    targets = parser.add_subparsers(dest="target", metavar="TARGET", required=True)
    for name, module_path in BENCH_MODULES.items():
        module = importlib.import_module(module_path)
        sub = targets.add_parser(name, help=(module.__doc__ or "").strip().splitlines()[0])
        module.add_arguments(sub)
        restrict_numbers(sub, BENCH_NUMBERS.get(name, {}))
        if name in BENCH_PRESET_OVERRIDES:
            sub.add_argument(
                "--set", dest="overrides", action="append", type=parse_assignment, default=[], metavar="NAME=VALUE",
                help="a walking-preset override for every run (repeatable), e.g. ocp.rollout_dynamics=compiled",
            )
        add_output_arguments(sub, plot=False)
        sub.set_defaults(func=_runner(module))


def _runner(module):
    def run(args: argparse.Namespace) -> int:
        result = module.run(args)
        if args.json:
            print_json(result)
        else:
            print(module.format_report(result))
        return 0

    return run
