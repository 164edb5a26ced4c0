"""Checked argument types shared by every subcommand: numbers (finite, in a range), output paths and
``--set NAME=VALUE`` assignments.

Every numeric option of every subcommand uses :func:`number` (``tests/test_cli_arguments.py``
walks all parsers to hold that), so a bad value is refused while parsing, with one line naming the
option, the value and what is allowed::

    wbmpc walk: error: argument --seed: invalid value '-1': must be an integer >= 0

:class:`CommandParser` prints that single line (no usage block) and exits with code 2.
"""

from __future__ import annotations

import argparse
import ast
import math
import os
import sys
import tomllib
from typing import NoReturn


class CommandParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr (exit code 2), no usage block."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class NumberType:
    """Argparse ``type=``: parse an int or a float, finite, within [low, high] (ends open or closed).

    Instances compare by their bounds and print as what they allow (``must be a number > 0``).
    """

    def __init__(self, kind: type = float, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False) -> None:
        if kind not in (int, float):
            raise TypeError(f"kind={kind!r} must be int or float")
        self.kind, self.low, self.high, self.low_open, self.high_open = kind, low, high, low_open, high_open
        self.__name__ = "integer" if kind is int else "number"  # argparse names the type in some messages

    @property
    def allowed(self) -> str:
        """What the type accepts, as words: "an integer >= 1", "a finite number in [0, 1)"."""
        what = "an integer" if self.kind is int else "a finite number"
        low, high = (None if v is None else (str(int(v)) if self.kind is int else f"{v:g}") for v in (self.low, self.high))
        if low is not None and high is not None:
            return f"{what} in {'(' if self.low_open else '['}{low}, {high}{')' if self.high_open else ']'}"
        if low is not None:
            return f"{what} {'>' if self.low_open else '>='} {low}"
        if high is not None:
            return f"{what} {'<' if self.high_open else '<='} {high}"
        return what

    def __call__(self, text: str) -> int | float:
        try:
            value = self.kind(text)
        except (TypeError, ValueError):
            value = None
        if value is None or not math.isfinite(value) or not self._in_range(value):
            raise argparse.ArgumentTypeError(f"invalid value {text!r}: must be {self.allowed}")
        return value

    def _in_range(self, value: float) -> bool:
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        if self.high is not None and (value >= self.high if self.high_open else value > self.high):
            return False
        return True

    def __repr__(self) -> str:
        return f"number({self.allowed})"


def number(kind: type = float, low: float | None = None, high: float | None = None,
           low_open: bool = False, high_open: bool = False) -> NumberType:
    """An argparse type for a finite int or float in a range (see :class:`NumberType`)."""
    return NumberType(kind, low, high, low_open, high_open)


# The kinds of numbers the subcommands take (one definition each).
FINITE = number(float)
NON_NEGATIVE = number(float, low=0.0)
POSITIVE = number(float, low=0.0, low_open=True)
COUNT = number(int, low=1)
NON_NEGATIVE_INT = number(int, low=0)
SEED = number(int, low=0, high=2**32 - 1)  # any seed numpy, random and the campaign records take
DURATION = POSITIVE  # simulated time [s]
PHASE = number(float, low=0.0, high=1.0, high_open=True)


def parse_assignment(text: str) -> tuple[str, object]:
    """``NAME=VALUE`` -> (NAME, value): VALUE read as a TOML value (the presets' syntax: ``true``, ``[0.1, 0.2]``,
    ``"alip"``), else as a Python literal (``True``, ``(0.1, 0.2)``), else kept as the string."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected NAME=VALUE")
    name, raw = text.split("=", 1)
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        try:
            value = ast.literal_eval(raw)
        except (ValueError, SyntaxError):
            value = raw
    return name.strip(), value


def output_directory(text: str) -> str:
    """Argparse type of ``--out DIR``: a directory that exists or can be made (not an existing file)."""
    if os.path.exists(text) and not os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: it is an existing file; give a directory (existing or new)")
    return text


def output_file(text: str) -> str:
    """Argparse type of ``--plot FILE``: a file path, not an existing directory."""
    if os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: it is a directory; give a file path")
    return text


def restrict_numbers(parser: argparse.ArgumentParser, types: dict[str, NumberType]) -> None:
    """Give the options of ``parser`` named in ``types`` (by dest) those checked types.

    For options another package declares (the benchmarks) with plain ``int``/``float``.

    Raises:
        KeyError: a name of ``types`` is not an option of ``parser`` (the table is out of date).
    """
    actions = {action.dest: action for action in parser._actions}
    for dest, kind in types.items():
        actions[dest].type = kind


def plain_numeric_options(parser: argparse.ArgumentParser, prefix: str = "") -> list[str]:
    """Options of ``parser`` and its subcommands still parsed by plain ``int``/``float`` (unchecked)."""
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += plain_numeric_options(sub, f"{prefix}{name} ")
        elif action.type in (int, float) and action.choices is None:  # choices check themselves
            found.append(f"{prefix}{'/'.join(action.option_strings) or action.dest}")
    return found


def fail(prog: str, message: str) -> int:
    """Print ``prog: error: message`` on stderr (one line) and return the exit code 2."""
    print(f"{prog}: error: {message}", file=sys.stderr)
    return 2

