"""Exception hierarchy shared by every package of the library.

Each error names the parameter, its value and what is allowed, so that a user reading a
traceback knows what to change without opening the source.
"""


class WbmpcError(Exception):
    """Base class of every error raised on purpose by this library."""


class ParameterError(WbmpcError, ValueError):
    """A user-supplied parameter is out of its allowed range or of the wrong shape."""


class MissingExtraError(WbmpcError, ImportError):
    """A feature needs an optional extra that is not installed (the message gives the
    ``pip install 'wbmpc[NAME]'`` line)."""


class SolverError(WbmpcError):
    """A numerical solver failed (infeasible problem, divergence, maximum iterations)."""


class NoSolutionError(SolverError):
    """A control loop has no solution to follow: its first solve failed (later failures keep the
    last good solution and are only reported)."""


def check_finite(name: str, value) -> None:
    """Raise ParameterError if ``value`` (scalar or array) contains NaN or inf."""
    import numpy as np

    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name}={value!r} must be finite (no NaN or inf)")
