"""Output options shared by the subcommands: ``--json`` and ``--plot FILE``."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from wbmpc.cli.arguments import output_file
from wbmpc.jsonable import to_jsonable


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout (NaN/inf become null)."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def add_output_arguments(parser: argparse.ArgumentParser, plot: bool = True) -> None:
    """Add the common ``--json`` and (optionally) ``--plot FILE`` options to a subcommand."""
    parser.add_argument("--json", action="store_true", help="print a machine-readable result on stdout")
    if plot:
        parser.add_argument("--plot", metavar="FILE", type=output_file, default=None, help="write the figure to FILE (PNG)")
