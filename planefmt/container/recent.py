"""The last few results of a costly step, by key: an encode makes the same segment, walk and body several
times while it sizes, writes and verifies a file (encoding's trials, then the file itself)."""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

T = TypeVar("T")


class Recent(Generic[T]):
    """At most ``count`` values by key, the least recently used dropped first. A value is a pure function
    of its key, so what is dropped only costs time; a lock keeps concurrent encodes (the batch's threads)
    from dropping a key between its lookup and its read."""

    def __init__(self, count: int) -> None:
        self._items: collections.OrderedDict[Hashable, T] = collections.OrderedDict()
        self._count = count
        self._lock = threading.Lock()

    def get(self, key: Hashable, make: Callable[[], T]) -> T:
        """The value kept for ``key``, else ``make()``'s, kept (made outside the lock)."""
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        value = make()
        with self._lock:
            self._items[key] = value
            while len(self._items) > self._count:
                self._items.popitem(last=False)
        return value

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
