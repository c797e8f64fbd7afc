"""Test streams: non-seekable readers and writers that move one byte at a time."""

from __future__ import annotations

import io


class TrickleReader(io.RawIOBase):
    """A non-seekable stream that returns at most one byte per read, like a slow pipe."""

    def __init__(self, data: bytes) -> None:
        self._data = data
        self._pos = 0

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return False

    def read(self, n: int = -1) -> bytes:
        if n == 0 or self._pos >= len(self._data):
            return b""
        b = self._data[self._pos:self._pos + 1]
        self._pos += 1
        return b

    def readinto(self, buf) -> int:
        b = self.read(1)
        buf[:len(b)] = b
        return len(b)


class TrickleWriter(io.RawIOBase):
    """A non-seekable sink that accepts one byte per write call."""

    def __init__(self) -> None:
        self.data = bytearray()

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return False

    def write(self, b) -> int:
        if not b:
            return 0
        self.data += bytes(b[:1])
        return 1
