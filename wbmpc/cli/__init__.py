"""Command-line entry point ``wbmpc``: a thin layer over the library's Python functions.

Each package that has something to run contributes its subcommands through a module with a
``register(subparsers)`` function (listed in ``SUBCOMMAND_MODULES``). Every subcommand accepts
``--json`` (machine-readable result on stdout); the ones that draw accept ``--plot FILE``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# Modules providing ``register(subparsers)``; the order is the order of ``wbmpc --help``.
SUBCOMMAND_MODULES: list[str] = [
    "wbmpc.cli.plan",
    "wbmpc.cli.sensitivity",
    "wbmpc.cli.demo",
    "wbmpc.cli.bench",
    "wbmpc.cli.walk",
    "wbmpc.cli.robots",
    "wbmpc.cli.ocp",
    "wbmpc.cli.campaign",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wbmpc",
        description="Whole-body MPC walking: footstep sequencer, sensitivity, FDDP, MuJoCo closed loop.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in SUBCOMMAND_MODULES:
        importlib.import_module(module_name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the ``wbmpc`` command line; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError) as err:  # user errors: one clear line, no traceback
        print(f"wbmpc {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0 if code is None else int(code)


if __name__ == "__main__":
    sys.exit(main())
