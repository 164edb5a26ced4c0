"""``ray`` backend: trials as Ray tasks, on this machine or on an existing Ray cluster (optional extra).

- ``RayBackend(workers=2)``: ``ray.init(num_cpus=workers)`` starts a private Ray instance on this
  machine (shut down by ``close()``).
- ``RayBackend(address="auto")`` or ``address="ray://head:10001"``: connects to a running cluster
  (left running by ``close()``). The cluster's workers must be able to import this library (the
  same environment on every node, or a Ray ``runtime_env``); each trial asks for one CPU.

Ray is an optional dependency (``pip install ray``); the file name's trailing underscore keeps
``import ray`` pointing at the real package.
"""

from __future__ import annotations

from typing import Any, Callable, Iterable, Iterator

from sim.campaigns.errors import BackendNotAvailable, CampaignError

LOCAL_OBJECT_STORE_BYTES = 200 * 1024**2  # trial records are small; keep Ray's shared memory modest


class RayBackend:
    """Ray tasks (one CPU each).

    Args:
        workers: CPUs of the private local instance (default 2); with ``address``, the number of
            tasks in flight is twice this (None: twice the cluster's CPUs).
        address: address of an existing cluster (None: start a local instance).

    Raises:
        BackendNotAvailable: ray is not installed.
    """

    name = "ray"

    def __init__(self, workers: int | None = None, address: str | None = None) -> None:
        try:
            import ray
        except ImportError as err:
            raise BackendNotAvailable(
                "backend='ray' needs the ray package, which is not installed: pip install ray "
                "(or use backend='local', the default)"
            ) from err
        self._ray = ray
        self.address = address
        self._owns_instance = False
        if not ray.is_initialized():
            options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            if address is None:
                options.update(num_cpus=workers or 2, object_store_memory=LOCAL_OBJECT_STORE_BYTES)
            else:
                options["address"] = address
            ray.init(**options)
            self._owns_instance = True
        if workers is None:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        self.workers = int(workers)

    def map_unordered(self, function: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[Any]:
        """Yield ``function(item)`` as each Ray task finishes (at most ``2 * workers`` in flight).

        Raises:
            CampaignError: a task failed outside the trial (worker died, node lost).
        """
        ray = self._ray
        remote = ray.remote(num_cpus=1, max_retries=0)(function)
        queue = iter(items)
        pending: list[Any] = []

        def refill() -> None:
            while len(pending) < 2 * self.workers:
                try:
                    item = next(queue)
                except StopIteration:
                    return
                pending.append(remote.remote(item))

        try:
            refill()
            while pending:
                done, _ = ray.wait(pending, num_returns=1)
                for ref in done:
                    pending.remove(ref)
                    try:
                        result = ray.get(ref)
                    except ray.exceptions.RayError as err:
                        raise CampaignError(
                            f"a Ray task failed outside the trial ({type(err).__name__}: {err}); the finished "
                            "trials are saved: rerun with --resume"
                        ) from err
                    yield result
                refill()
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)

    def close(self) -> None:
        """Shut down the local Ray instance this backend started (a cluster is left running)."""
        if self._owns_instance and self._ray.is_initialized():
            self._ray.shutdown()
        self._owns_instance = False

    def __enter__(self) -> "RayBackend":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
