"""A growing table of planes that stores each plane once: a body's planes, then the inverted and
bounding planes its part groups add.
"""

from __future__ import annotations

import numpy as np


class PlaneTable:
    """The planes of a body's groups: the polygonization's, then new ones (inverted, bounding).

    :meth:`add` returns an index, reusing an identical plane; indices below
    ``base`` are the input planes. Storage grows geometrically.
    """

    def __init__(self, omega: np.ndarray, h: np.ndarray) -> None:
        self.base = len(h)
        self._count = self.base
        self._omega = np.array(omega, dtype=np.float64).reshape(-1, 3)
        self._h = np.array(h, dtype=np.float64).reshape(-1)
        self._new: dict[tuple[float, ...], int] = {}

    def add(self, omega: np.ndarray, h: float) -> int:
        key = (float(omega[0]), float(omega[1]), float(omega[2]), float(h))
        idx = self._new.get(key)
        if idx is None:
            idx = self._new[key] = self._count
            self._reserve(self._count + 1)
            self._omega[idx] = omega
            self._h[idx] = h
            self._count += 1
        return idx

    def _reserve(self, need: int) -> None:
        """Room for ``need`` planes, growing the storage geometrically."""
        if need > len(self._h):
            grow = max(16, len(self._h), need - len(self._h))
            self._omega = np.concatenate([self._omega, np.zeros((grow, 3))])
            self._h = np.concatenate([self._h, np.zeros(grow)])

    def extend(self, omega: np.ndarray, h: np.ndarray) -> np.ndarray:
        """:meth:`add` of each row of ``omega`` (k, 3), ``h`` (k,), in one pass: their indices."""
        rows = np.column_stack([np.asarray(omega, dtype=np.float64).reshape(-1, 3),
                                np.asarray(h, dtype=np.float64).reshape(-1)])
        old = np.column_stack([self._omega[self.base:self._count], self._h[self.base:self._count]])
        # "+ 0.0" turns -0.0 into 0.0: np.unique compares rows by their bytes, add()'s dictionary by value.
        _, first, inverse = np.unique(np.vstack([old, rows]) + 0.0, axis=0, return_index=True,
                                      return_inverse=True)
        index = np.empty(len(first), dtype=np.int64)
        known = first < len(old)
        index[known] = self.base + first[known]
        new = np.flatnonzero(~known)
        new = new[np.argsort(first[new])]
        index[new] = self._count + np.arange(len(new))
        added = rows[first[new] - len(old)]
        need = self._count + len(added)
        self._reserve(need)
        self._omega[self._count:need] = added[:, :3]
        self._h[self._count:need] = added[:, 3]
        self._new.update(zip(map(tuple, added.tolist()), index[new].tolist()))
        self._count = need
        return index[inverse.reshape(-1)[len(old):]]

    def inverted(self, j: int) -> int:
        """The index of plane ``j`` turned over, ``(-omega, -h)``."""
        return self.add(-self._omega[j], -float(self._h[j]))

    def plane(self, j: int) -> tuple[np.ndarray, float]:
        return self._omega[j], float(self._h[j])

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """All planes so far: views, valid until the next :meth:`add`."""
        return self._omega[:self._count], self._h[:self._count]
