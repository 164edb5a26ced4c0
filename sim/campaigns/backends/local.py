"""``local`` backend: a process pool on this machine (``concurrent.futures.ProcessPoolExecutor``).

Workers start with the forkserver method where the platform has it (else spawn): never plain fork,
which would copy the parent's threads and open files (MuJoCo, BLAS and tqdm do not survive a fork
reliably). The forkserver preloads the simulation modules once, so each worker starts in a
fraction of a second instead of importing Pinocchio and MuJoCo again.

Workers end when the campaign process dies, even by ``kill -9`` (which runs no clean-up): each
worker starts with :func:`end_with_campaign`. A forkserver's workers are the forkserver's children,
and the forkserver outlives the campaign as long as a worker runs (each worker holds its "alive"
pipe), so a parent-death signal alone would not fire: a daemon thread of each worker polls the
campaign process and ends the worker once it is gone; on Linux the worker also asks for SIGKILL on
its parent's death (``prctl(PR_SET_PDEATHSIG)``: immediate where the parent is the campaign, as with
the spawn start method). A killed campaign loses only its running trials; ``--resume`` runs them again.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Iterable, Iterator

from sim.campaigns.errors import CampaignError

PRELOAD_MODULES = ["sim.campaigns.trial", "sim.runner"]
CAMPAIGN_POLL_PERIOD = 0.5  # [s] between two checks, in each worker, that the campaign process lives
PR_SET_PDEATHSIG = 1  # linux/prctl.h


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, dead but not yet reaped, does not)."""
    if sys.platform.startswith("linux"):
        try:
            with open(f"/proc/{pid}/stat") as stream:
                stat = stream.read()
        except OSError:
            return False
        return stat[stat.rindex(")") + 2] != "Z"  # "pid (comm) state ..."
    if sys.platform == "win32":
        import ctypes

        handle = ctypes.windll.kernel32.OpenProcess(0x1000, False, pid)  # PROCESS_QUERY_LIMITED_INFORMATION
        if not handle:
            return False
        code = ctypes.c_ulong()
        ctypes.windll.kernel32.GetExitCodeProcess(handle, ctypes.byref(code))
        ctypes.windll.kernel32.CloseHandle(handle)
        return code.value == 259  # STILL_ACTIVE
    try:
        os.kill(pid, 0)  # POSIX: signal 0 checks existence only
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def end_with_campaign(campaign_pid: int, poll_period: float = CAMPAIGN_POLL_PERIOD) -> None:
    """Pool worker initializer: end this worker (``os._exit``) when process ``campaign_pid`` is gone.

    A daemon thread checks every ``poll_period`` seconds; on Linux the worker is also SIGKILLed
    at once when its parent process dies (``prctl(PR_SET_PDEATHSIG)``).
    """
    if sys.platform.startswith("linux"):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)

    def watch() -> None:
        while process_alive(campaign_pid):
            time.sleep(poll_period)
        os._exit(1)

    if not process_alive(campaign_pid):  # died before the watch started
        os._exit(1)
    threading.Thread(target=watch, name="end-with-campaign", daemon=True).start()


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
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self._context,
                                             initializer=end_with_campaign, initargs=(os.getpid(),))
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
