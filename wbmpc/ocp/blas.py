"""Run a block of code with the BLAS libraries single-threaded: the MPC's matrices are small and,
on a shared machine, OpenBLAS worker threads spin and wait far longer than the products take
(measured 3x slower solves on 2 busy cores). Nothing here changes results, only threading.

Nothing in the library changes the thread count behind the caller's back: a solver's
constructor leaves it alone; :class:`~wbmpc.ocp.mpc.RecedingHorizonMPC` runs each update and
preparation inside :func:`limit_blas_threads` (its ``blas_threads`` option) and the benchmarks
wrap their timed runs in it.

    with limit_blas_threads(1):
        solver.solve(xs, us)
"""

from __future__ import annotations

import ctypes
import os
from contextlib import contextmanager
from typing import Iterator

from wbmpc.errors import ParameterError

_NAMES = (  # (setter, getter) of the OpenBLAS builds numpy and scipy ship
    ("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
    ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
    ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
    ("openblas_set_num_threads", "openblas_get_num_threads"),
)
_libraries: list[tuple[str, object, object]] | None = None  # (path, setter, getter), found once


def _openblas_libraries() -> list[tuple[str, object, object]]:
    """The OpenBLAS libraries loaded in this process (Linux /proc/self/maps), looked up once."""
    global _libraries
    if _libraries is not None:
        return _libraries
    import numpy  # noqa: F401 - make sure numpy's BLAS is loaded
    import scipy.linalg  # noqa: F401 - and scipy's (used by numba's np.dot)

    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
    except OSError:
        paths = []
    found = []
    for path in paths:
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in _NAMES:
            setter, getter = getattr(library, set_name, None), getattr(library, get_name, None)
            if setter is not None and getter is not None:
                getter.restype = ctypes.c_int
                found.append((path, setter, getter))
                break
    _libraries = found
    return found


@contextmanager
def limit_blas_threads(n_threads: int = 1) -> Iterator[list[str]]:
    """Within the block, every OpenBLAS library loaded in this process uses ``n_threads``; the
    previous counts are restored on exit (also on an exception). The count is per process, so
    other threads see it during the block.

    Honours an explicit ``OPENBLAS_NUM_THREADS`` in the environment (then does nothing).

    Yields:
        paths of the libraries that were limited (empty where this is not supported).
    """
    if isinstance(n_threads, bool) or not isinstance(n_threads, int) or n_threads < 1:
        raise ParameterError(f"n_threads={n_threads!r} must be an integer >= 1")
    if "OPENBLAS_NUM_THREADS" in os.environ:
        yield []
        return
    libraries = _openblas_libraries()
    previous = [int(getter()) for _, _, getter in libraries]
    for _, setter, _ in libraries:
        setter(ctypes.c_int(n_threads))
    try:
        yield [path for path, _, _ in libraries]
    finally:
        for (_, setter, _), count in zip(libraries, previous):
            setter(ctypes.c_int(count))
