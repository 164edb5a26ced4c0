"""Keep the BLAS libraries single-threaded: the MPC's matrices are small and, on a shared
machine, OpenBLAS worker threads spin and wait far longer than the products take (measured
3x slower solves on 2 busy cores). Nothing here changes results, only threading.
"""

from __future__ import annotations

import ctypes
import os

_SETTERS = (
    "scipy_openblas_set_num_threads64_",
    "scipy_openblas_set_num_threads",
    "openblas_set_num_threads64_",
    "openblas_set_num_threads",
)


def limit_blas_threads(n_threads: int = 1) -> list[str]:
    """Set the thread count of every OpenBLAS library loaded in this process (Linux).

    Honours an explicit ``OPENBLAS_NUM_THREADS`` in the environment (then does nothing).

    Returns:
        paths of the libraries that were limited (empty where this is not supported).
    """
    if "OPENBLAS_NUM_THREADS" in os.environ:
        return []
    import numpy  # noqa: F401 - make sure numpy's BLAS is loaded
    import scipy.linalg  # noqa: F401 - and scipy's (used by numba's np.dot)

    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
    except OSError:
        return []
    limited = []
    for path in paths:
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for name in _SETTERS:
            setter = getattr(library, name, None)
            if setter is not None:
                setter(ctypes.c_int(int(n_threads)))
                limited.append(path)
                break
    return limited
