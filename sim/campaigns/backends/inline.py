"""``inline`` backend: the items run in this process, one after the other (debugging, tests)."""

from __future__ import annotations

from typing import Any, Callable, Iterable, Iterator


class InlineBackend:
    """Runs ``function(item)`` in the calling process (a debugger or profiler sees everything)."""

    name = "inline"
    workers = 1

    def map_unordered(self, function: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[Any]:
        """Yield ``function(item)`` for each item, in order."""
        for item in items:
            yield function(item)

    def close(self) -> None:
        """Nothing to release."""

    def __enter__(self) -> "InlineBackend":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
