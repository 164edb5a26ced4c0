"""Command-line entry point ``wbmpc``: a thin layer over the library's Python functions.

Each package that has something to run contributes its subcommands through a module with a
``register(subparsers)`` function (listed in ``SUBCOMMAND_MODULES``). Every subcommand accepts
``--json`` (machine-readable result on stdout); the ones that draw accept ``--plot FILE``.

A user error (an option out of range, an unknown robot, a parameter a library function refuses:
:class:`wbmpc.errors.WbmpcError`, ``ValueError``, ``OSError``) ends the command with one line on
stderr naming the parameter, its value and what is allowed, and the exit code 2; no traceback.
"""

from __future__ import annotations

import importlib
import os
import sys

from wbmpc.cli.arguments import CommandParser, fail
from wbmpc.errors import WbmpcError

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


def build_parser() -> CommandParser:
    parser = CommandParser(
        prog="wbmpc",
        description="Whole-body MPC walking: footstep sequencer, sensitivity, FDDP, MuJoCo closed loop.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in SUBCOMMAND_MODULES:
        importlib.import_module(module_name).register(subparsers)
    return parser


def _offscreen_gl_default(argv: list[str]) -> None:
    """Make EGL MuJoCo's GL backend for ``--render`` on a machine without a display.

    MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, and building the parser already
    imports it (the scenario and video-path options), so this is decided from the raw arguments
    before anything else. A non-empty ``MUJOCO_GL`` is kept; ``--viewer`` needs the windowed default.
    """
    rendering = any(arg == "--render" or arg.startswith("--render=") for arg in argv)
    headless = not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if rendering and headless and "--viewer" not in argv and not os.environ.get("MUJOCO_GL"):
        os.environ["MUJOCO_GL"] = "egl"


def main(argv: list[str] | None = None) -> int:
    """Run the ``wbmpc`` command line; returns the process exit code."""
    _offscreen_gl_default(sys.argv[1:] if argv is None else list(argv))
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as end:  # --help, or an option refused while parsing (its one line is printed)
        return end.code if isinstance(end.code, int) else 0
    try:
        code = args.func(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except (WbmpcError, ValueError, OSError) as err:  # user errors: one clear line, no traceback
        return fail(f"wbmpc {args.command}", " ".join(str(err).split()))
    return 0 if code is None else int(code)


if __name__ == "__main__":
    sys.exit(main())
