"""Exact side tests for points given as the meeting point of three planes.

A point ``X(i, j, k)`` is where planes ``i, j, k`` meet (plane-based
geometry: the point is never rounded, only its planes are stored). Its side
of plane ``q`` is

    sign(omega_q . X - h_q) = sign(det4(r_i, r_j, r_k, r_q)) * sign(det3(omega_i, omega_j, omega_k))

with rows ``r = (omega, -h)``: adding ``X`` times the first three columns to
the last leaves the determinant unchanged and makes that column
``(0, 0, 0, omega_q . X - h_q)``. Both determinants are evaluated in float64
with a forward error bound; the signs the bound cannot decide (a point on or
within rounding of the plane) are computed exactly from the floats' integer
ratios. So every decision agrees with exact arithmetic on the stored planes,
whoever asks it and in whatever order.

Conventions: planes ``(omega, h)``, inside where ``omega . x <= h``; a triple
``(i, j, k)`` must be independent (``det3 != 0``).
"""

from __future__ import annotations

import numpy as np

from ..errors import GeometryError

_EPS = float(np.finfo(np.float64).eps)
#: Forward error bounds of the float64 evaluations below, in units of eps times the permanent
#: (the same products with absolute values): above the few roundings each term takes.
DET3_BOUND = 8.0 * _EPS
DET4_BOUND = 32.0 * _EPS


def _det3(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``det(a; b; c)`` of rows (n, 3) and its permanent."""
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    aa, ab, ac = np.abs(a), np.abs(b), np.abs(c)
    perm = (aa[:, 0] * (ab[:, 1] * ac[:, 2] + ab[:, 2] * ac[:, 1])
            + aa[:, 1] * (ab[:, 0] * ac[:, 2] + ab[:, 2] * ac[:, 0])
            + aa[:, 2] * (ab[:, 0] * ac[:, 1] + ab[:, 1] * ac[:, 0]))
    return det, perm


def _det4(r: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``det`` of four rows (n, 4) by 2x2 minors of the first two and last two columns, and its permanent."""
    det = np.zeros(len(r[0]))
    perm = np.zeros(len(r[0]))
    for (a, b, c, d), sign in (((0, 1, 2, 3), 1.0), ((0, 2, 1, 3), -1.0), ((0, 3, 1, 2), 1.0),
                               ((1, 2, 0, 3), 1.0), ((1, 3, 0, 2), -1.0), ((2, 3, 0, 1), 1.0)):
        s = r[a][:, 0] * r[b][:, 1] - r[b][:, 0] * r[a][:, 1]
        t = r[c][:, 2] * r[d][:, 3] - r[d][:, 2] * r[c][:, 3]
        det += sign * s * t
        perm += ((np.abs(r[a][:, 0] * r[b][:, 1]) + np.abs(r[b][:, 0] * r[a][:, 1]))
                 * (np.abs(r[c][:, 2] * r[d][:, 3]) + np.abs(r[d][:, 2] * r[c][:, 3])))
    return det, perm


def _int_rows(rows: list[list[float]]) -> list[list[int]]:
    """Rows of floats scaled by positive powers of two to integers (a determinant keeps its sign)."""
    out = []
    for row in rows:
        ratios = [float(x).as_integer_ratio() for x in row]
        den = max(d for _, d in ratios)
        out.append([n * (den // d) for n, d in ratios])
    return out


def _idet(m: list[list[int]]) -> int:
    if len(m) == 1:
        return m[0][0]
    total = 0
    for col in range(len(m)):
        if m[0][col]:
            minor = [row[:col] + row[col + 1:] for row in m[1:]]
            total += (-1) ** col * m[0][col] * _idet(minor)
    return total


def _exact_side(omega: np.ndarray, h: np.ndarray, t: np.ndarray, q: int) -> int:
    rows = [[*omega[p].tolist(), -float(h[p])] for p in (*t.tolist(), q)]
    d4 = _idet(_int_rows(rows))
    d3 = _idet(_int_rows([r[:3] for r in rows[:3]]))
    return int(np.sign(d4) * np.sign(d3))


class ExactBudget:
    """A cap on the exact (integer) evaluations a computation may spend: a file whose every plane
    passes through one point cannot make a decoder run them without end."""

    def __init__(self, limit: int) -> None:
        self.left = int(limit)

    def spend(self, count: int) -> None:
        self.left -= count
        if self.left < 0:
            raise GeometryError("too many exact side tests (planes nearly concurrent everywhere)",
                                code="LIMIT_EXCEEDED")


class ExactPlanes:
    """Planes ``omega`` (n, 3), ``h`` (n,) for exact tests, spending from one :class:`ExactBudget`."""

    def __init__(self, omega: np.ndarray, h: np.ndarray, limit: int) -> None:
        self.omega = np.asarray(omega, dtype=np.float64)
        self.h = np.asarray(h, dtype=np.float64)
        self.budget = ExactBudget(limit)

    def sides(self, triples: np.ndarray, q: np.ndarray | int) -> np.ndarray:
        """:func:`sides` on these planes."""
        return sides(self.omega, self.h, triples, q, self.budget)

    def points(self, triples: np.ndarray) -> np.ndarray:
        """:func:`points` on these planes."""
        return points(self.omega, self.h, triples)


def sides(omega: np.ndarray, h: np.ndarray, triples: np.ndarray, q: np.ndarray | int,
          budget: ExactBudget | None = None) -> np.ndarray:
    """Exact ``sign(omega_q . X(t) - h_q)`` (int8, -1 inside) of points ``triples`` (n, 3) for planes ``q`` (n,).

    0 where ``q`` is one of the point's planes, or the point lies on ``q`` exactly. Signs the
    float64 bound cannot decide are charged to ``budget`` (``LIMIT_EXCEEDED`` when spent).
    """
    triples = np.asarray(triples, dtype=np.int64).reshape(-1, 3)
    q = np.broadcast_to(np.asarray(q, dtype=np.int64), (len(triples),))
    out = np.zeros(len(triples), dtype=np.int8)
    free = np.flatnonzero((triples != q[:, None]).all(axis=1))
    if len(free) == 0:
        return out
    t, qq = triples[free], q[free]
    rows = tuple(np.column_stack([omega[p], -h[p]]) for p in (t[:, 0], t[:, 1], t[:, 2], qq))
    d4, p4 = _det4(rows)
    d3, p3 = _det3(omega[t[:, 0]], omega[t[:, 1]], omega[t[:, 2]])
    sure = (np.abs(d4) > DET4_BOUND * p4) & (np.abs(d3) > DET3_BOUND * p3)
    out[free[sure]] = (np.sign(d4[sure]) * np.sign(d3[sure])).astype(np.int8)
    undecided = np.flatnonzero(~sure)
    if budget is not None:
        budget.spend(len(undecided))
    for k in undecided:
        out[free[k]] = _exact_side(omega, h, t[k], int(qq[k]))
    return out


def points(omega: np.ndarray, h: np.ndarray, triples: np.ndarray) -> np.ndarray:
    """Float64 coordinates (n, 3) of the points ``triples`` (n, 3), each solved from its three planes."""
    triples = np.asarray(triples, dtype=np.int64).reshape(-1, 3)
    if len(triples) == 0:
        return np.zeros((0, 3))
    return np.linalg.solve(omega[triples], h[triples][:, :, None])[:, :, 0]
