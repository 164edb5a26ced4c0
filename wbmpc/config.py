"""Reading the library's TOML files (parameter presets, campaign files) with clear errors."""

from __future__ import annotations

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
