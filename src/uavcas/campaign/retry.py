"""The campaign's retry rule, shared by the local pool and the Dask executor."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol


class _Outcome(Protocol):
    index: int
    ok: bool


class Retries:
    """Counts tries per run index; `again(outcome)` says whether a failed run is tried once more."""

    def __init__(self, retries: int, on_retry: Callable[[_Outcome, int], None] | None = None) -> None:
        self.retries = retries
        self.on_retry = on_retry
        self.tries: dict[int, int] = {}

    def started(self, index: int) -> int:
        """Record one more try of run `index`; returns its number (1 = first)."""
        self.tries[index] = self.tries.get(index, 0) + 1
        return self.tries[index]

    def again(self, out: _Outcome) -> bool:
        """A failed run, or a finished one asking for a retry (`retry`: its fidelity failed)."""
        if (out.ok and not getattr(out, "retry", False)) or self.tries.get(out.index, 0) > self.retries:
            return False
        if self.on_retry:
            self.on_retry(out, self.tries[out.index])
        return True
