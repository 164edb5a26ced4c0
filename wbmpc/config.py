"""Reading the library's TOML files (parameter presets, campaign files) into validated
dataclasses, with clear errors."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Any

from wbmpc.errors import ParameterError


def read_toml(path: str | Path, kind: str) -> dict[str, Any]:
    """Parse the TOML file ``path``; ``kind`` names it in errors ("parameter file", "campaign file").

    Raises:
        ParameterError: the file does not exist or is not valid TOML (the message names the path).
    """
    path = Path(path)
    try:
        with path.open("rb") as stream:
            return tomllib.load(stream)
    except FileNotFoundError as err:
        raise ParameterError(f"{kind} {str(path)!r} does not exist") from err
    except tomllib.TOMLDecodeError as err:
        raise ParameterError(f"{kind} {str(path)!r} is not valid TOML: {err}") from err


def dataclass_from_table(cls, data: dict[str, Any], kind: str, source: str):
    """``cls(**data)`` for a dataclass ``cls``, refusing unknown keys with a one-line error
    (``unknown {kind}(s) [...] in {source}; allowed: [...]``); the dataclass validates the values."""
    allowed = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(data) - set(allowed))
    if unknown:
        raise ParameterError(f"unknown {kind}(s) {unknown} in {source}; allowed: {allowed}")
    return cls(**data)


def named_preset(cls, directory: Path, name: str, kind: str):
    """``cls.from_toml(directory / f"{name}.toml")``, refusing an unknown name with the available ones."""
    available = sorted(p.stem for p in directory.glob("*.toml"))
    if name not in available:
        raise ParameterError(f"{kind}={name!r} is not known (available: {available})")
    return cls.from_toml(directory / f"{name}.toml")
