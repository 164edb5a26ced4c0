"""Run a block of code with the BLAS libraries single-threaded: the MPC's matrices are small and,
on a shared machine, OpenBLAS worker threads spin and wait far longer than the products take
(measured 3x slower solves on 2 busy cores). The same holds for OpenMP (libgomp, loaded with
Pinocchio): Eigen's matrix products in the C++ libraries (Crocoddyl's backward pass) use its
threads, 22 → 102 ms per G1 backward pass on 2 busy cores. Nothing here changes results, only
threading.

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
_OPENMP_NAMES = (("omp_set_num_threads", "omp_get_max_threads"),)
_OPENMP_LIBRARIES = ("libgomp", "libomp", "libiomp")  # GNU, LLVM, Intel runtimes
_libraries: list[tuple[str, object, object]] | None = None  # (path, setter, getter), found once
_openmp: list[tuple[str, object, object]] | None = None


def _loaded_libraries(matches, names) -> list[tuple[str, object, object]]:
    """(path, setter, getter) of the libraries loaded in this process (Linux /proc/self/maps)
    whose file name ``matches`` and that export one (setter, getter) pair of ``names``."""
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = sorted({line.split()[-1] for line in maps
                            if "/" in line and matches(os.path.basename(line.split()[-1]).lower())})
    except OSError:
        paths = []
    found = []
    for path in paths:
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in names:
            setter, getter = getattr(library, set_name, None), getattr(library, get_name, None)
            if setter is not None and getter is not None:
                getter.restype = ctypes.c_int
                found.append((path, setter, getter))
                break
    return found


def _openblas_libraries() -> list[tuple[str, object, object]]:
    """The OpenBLAS libraries loaded in this process, looked up once."""
    global _libraries
    if _libraries is None:
        import numpy  # noqa: F401 - make sure numpy's BLAS is loaded
        import scipy.linalg  # noqa: F401 - and scipy's (used by numba's np.dot)

        _libraries = _loaded_libraries(lambda name: "openblas" in name, _NAMES)
    return _libraries


def _openmp_libraries() -> list[tuple[str, object, object]]:
    """The OpenMP runtimes loaded in this process (the one Pinocchio loads, which Crocoddyl
    shares), looked up once."""
    global _openmp
    if _openmp is None:
        import pinocchio  # noqa: F401 - make sure its OpenMP runtime is loaded

        _openmp = _loaded_libraries(lambda name: name.startswith(_OPENMP_LIBRARIES), _OPENMP_NAMES)
    return _openmp


@contextmanager
def limit_blas_threads(n_threads: int = 1) -> Iterator[list[str]]:
    """Within the block, every OpenBLAS library loaded in this process uses ``n_threads``, and so
    does every OpenMP runtime for the parallel regions the calling thread starts (Eigen's products
    in Pinocchio and Crocoddyl); the previous counts are restored on exit (also on an exception).
    The OpenBLAS count is per process, so other threads see it during the block.

    Honours an explicit ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` in the environment (then
    leaves that library alone).

    Yields:
        paths of the libraries that were limited (empty where this is not supported).
    """
    if isinstance(n_threads, bool) or not isinstance(n_threads, int) or n_threads < 1:
        raise ParameterError(f"n_threads={n_threads!r} must be an integer >= 1")
    libraries = [] if "OPENBLAS_NUM_THREADS" in os.environ else list(_openblas_libraries())
    if "OMP_NUM_THREADS" not in os.environ:
        libraries += _openmp_libraries()
    previous = [int(getter()) for _, _, getter in libraries]
    for _, setter, _ in libraries:
        setter(ctypes.c_int(n_threads))
    try:
        yield [path for path, _, _ in libraries]
    finally:
        for (_, setter, _), count in zip(libraries, previous):
            setter(ctypes.c_int(count))
