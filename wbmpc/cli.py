"""Command-line entry point ``wbmpc``: a thin layer over the library's Python functions.

Each package that has something to run contributes its subcommands through a module with a
``register(subparsers)`` function (listed in ``SUBCOMMAND_MODULES``). Every subcommand accepts
``--json`` (machine-readable result on stdout); the ones that draw accept ``--plot FILE``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from typing import Any

import numpy as np

# Modules providing ``register(subparsers)``; the order is the order of ``wbmpc --help``.
SUBCOMMAND_MODULES: list[str] = [
    "sequencer.cli",
    "sensitivity.cli",
    "sim.demo",
    "bench.cli",
    "sim.cli",
    "robots.cli",
    "wbmpc.ocp_cli",
    "sim.campaigns.cli",
]


def to_jsonable(obj: Any) -> Any:
    """Convert numpy arrays/scalars, dataclasses and tuples into JSON-serialisable objects."""
    import dataclasses

    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if np.isfinite(value) else None
    return obj


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout (NaN/inf become null)."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def add_output_arguments(parser: argparse.ArgumentParser, plot: bool = True) -> None:
    """Add the common ``--json`` and (optionally) ``--plot FILE`` options to a subcommand."""
    parser.add_argument("--json", action="store_true", help="print a machine-readable result on stdout")
    if plot:
        parser.add_argument("--plot", metavar="FILE", default=None, help="write the figure to FILE (PNG)")


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
