"""Where the trials run: one backend per file, all with the same interface.

A backend maps a picklable top-level function over items and yields the results in the order they
finish (``map_unordered``); at most ``2 * workers`` items are in flight, so an interrupted campaign
has little work to throw away and the progress bar's ETA follows the real rate.

- ``local`` (default): a ``concurrent.futures.ProcessPoolExecutor`` on this machine (forkserver
  start method where available, else spawn; no server needed).
- ``ray``: Ray tasks, ``ray.init()`` on this machine or ``address=`` of an existing cluster
  (optional: ``pip install ray``).
- ``inline``: in this process, one item after the other (debugging, profiling, tests).

The same campaign (spec file) runs on any of them and gives the same records (timings aside).
"""

from __future__ import annotations

from typing import Any

from sim.campaigns.errors import BackendNotAvailable

BACKENDS = ("local", "ray", "inline")


def make_backend(name: str, workers: int | None = None, address: str | None = None) -> Any:
    """Create backend ``name`` with ``workers`` parallel workers.

    Args:
        name: "local", "ray" or "inline".
        workers: parallel workers (local and ray-on-this-machine; default 2 for local; ignored by
            inline; for a Ray cluster, None uses every CPU of the cluster).
        address: Ray cluster address (e.g. "ray://head:10001" or "auto"); ray backend only.

    Raises:
        BackendNotAvailable: unknown name, or ray requested but not installed.
        ParameterError: workers < 1, or an address given to another backend than ray.
    """
    from wbmpc.errors import ParameterError

    if name not in BACKENDS:
        raise BackendNotAvailable(f"backend={name!r} is unknown (available: {BACKENDS})")
    if workers is not None and not (isinstance(workers, int) and workers >= 1):
        raise ParameterError(f"workers={workers!r} must be an integer >= 1")
    if address is not None and name != "ray":
        raise ParameterError(f"address={address!r} is for the ray backend only (backend={name!r})")
    if name == "local":
        from sim.campaigns.backends.local import LocalPoolBackend

        return LocalPoolBackend(workers=workers or 2)
    if name == "ray":
        from sim.campaigns.backends.ray_ import RayBackend

        return RayBackend(workers=workers, address=address)
    from sim.campaigns.backends.inline import InlineBackend

    return InlineBackend()


__all__ = ["BACKENDS", "make_backend"]
