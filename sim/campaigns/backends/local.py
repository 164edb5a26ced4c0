"""``local`` backend: a process pool on this machine (``concurrent.futures.ProcessPoolExecutor``).

Workers start with the forkserver method where the platform has it (else spawn): never plain fork,
which would copy the parent's threads and open files (MuJoCo, BLAS and tqdm do not survive a fork
reliably). The forkserver preloads the simulation modules once, so each worker starts in a
fraction of a second instead of importing Pinocchio and MuJoCo again.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Iterable, Iterator

from sim.campaigns.errors import CampaignError

PRELOAD_MODULES = ["sim.campaigns.trial", "sim.runner"]


def start_method() -> str:
    """"forkserver" where available (Linux, macOS), else "spawn" (Windows)."""
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


class LocalPoolBackend:
    """``workers`` worker processes on this machine.

    Args:
        workers: number of worker processes (>= 1). Keep it at most the number of free cores: a
            trial is single-threaded and CPU-bound.
    """

    name = "local"

    def __init__(self, workers: int = 2) -> None:
        self.workers = int(workers)
        self._context = multiprocessing.get_context(start_method())
        if self._context.get_start_method() == "forkserver":
            self._context.set_forkserver_preload(PRELOAD_MODULES)
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self._context)
        return self._pool

    def map_unordered(self, function: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[Any]:
        """Yield ``function(item)`` as each finishes (at most ``2 * workers`` items in flight).

        Raises:
            CampaignError: a worker process died (crash, out of memory, killed); the results
                already yielded stand, the others are cancelled.
        """
        pool = self._executor()
        queue = iter(items)
        pending: set[Future] = set()

        def refill() -> None:
            while len(pending) < 2 * self.workers:
                try:
                    item = next(queue)
                except StopIteration:
                    return
                pending.add(pool.submit(function, item))

        try:
            refill()
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in done:
                    pending.discard(future)
                    try:
                        result = future.result()
                    except BrokenProcessPool as err:
                        raise CampaignError(
                            f"a worker process of the local pool died ({err}); the finished trials are saved, "
                            "the running ones are lost: rerun with --resume"
                        ) from err
                    yield result
                refill()
        finally:
            for future in pending:
                future.cancel()
            if pending:  # interrupted or failed: do not wait for the running items
                self.close(wait=False)

    def close(self, wait: bool = True) -> None:
        """Shut the pool down (``wait=False``: do not wait for running items)."""
        if self._pool is not None:
            self._pool.shutdown(wait=wait, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> "LocalPoolBackend":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close(wait=exc[0] is None)
