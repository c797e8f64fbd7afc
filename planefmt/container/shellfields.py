"""The fields of shell groups (kind 6, spec §9.10) and shell trees (kind 7, §9.11): corner codes in
first-use order, the bodies as written and read, and every check the spec asks of a shell."""

from __future__ import annotations

import math
import secrets

import numpy as np

from ..errors import FormatError
from ..model import FREE, MAX_GRID, GroupKind, Shell
from . import schema, varint
from .budget import Charge

try:
    from ._chains import (average as _average, parallelograms as _parallelograms, reflect as _reflect,
                          resolve as _resolve_forward, tree_terms as _tree_terms)
except ImportError:  # built without a C compiler: pointer jumping in numpy does the same, more slowly
    _average = _parallelograms = _reflect = _resolve_forward = _tree_terms = None

#: A kind 10 corner's parallelograms (spec §9.14): at most this many, the first in triangle order.
MAX_PARALLELOGRAMS = 4
#: A kind 12 chain turns only where every component of its two steps is within this (spec §9.16):
#: every product of the prediction then fits a signed 64-bit integer.
MAX_TURN = 1 << 18


def corner_codes(triangles: np.ndarray) -> np.ndarray:
    """The corner codes of spec §9.10 of ``triangles`` (T, 3) whose corners are numbered by first
    use: 0 for a corner's first use, ``k`` for a later one of the k-th newest corner."""
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1)
    if not len(tri):
        return tri
    new = np.r_[True, tri[1:] > np.maximum.accumulate(tri)[:-1]]
    return np.where(new, 0, np.cumsum(new) - tri)


def first_use_order(triangles: np.ndarray, count: int) -> np.ndarray:
    """New number of each of ``count`` corners when numbered in order of first use by ``triangles``
    (read row by row); -1 for corners no triangle uses."""
    flat = np.asarray(triangles, dtype=np.int64).reshape(-1)
    # Where each corner is first used, without sorting the corners (a sort was most of this function's time).
    first = np.full(count, len(flat), dtype=np.int64)
    np.minimum.at(first, flat, np.arange(len(flat)))
    opens = np.zeros(len(flat) + 1, dtype=bool)
    opens[first] = True
    return np.where(first < len(flat), (np.cumsum(opens) - 1)[first], -1)


def check_shell(shell: Shell, bounding: np.ndarray) -> None:
    """``FormatError`` (``BAD_GROUP_STRUCTURE``) naming the first rule of spec §9.10 ``shell``
    breaks for a group whose references have roles ``bounding``."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"shell group: {reason}", code="BAD_GROUP_STRUCTURE")
    explicit = np.asarray(shell.explicit, dtype=bool)
    vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)
    grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    fc = np.asarray(shell.facets, dtype=np.int64)
    v = len(explicit)
    if v < 3 or fc.ndim != 2 or fc.shape[1] != 4 or not len(fc):
        raise bad("needs at least 3 corners and 1 triangle")
    if len(vp) != int((~explicit).sum()) or len(grid) != int(explicit.sum()):
        raise bad("one triple per named corner and one coordinate row per explicit corner")
    count = len(bounding)
    if len(vp) and (vp.min() < 0 or vp.max() >= count):
        raise bad("a corner refers past the group's references")
    if ((vp[:, 0] == vp[:, 1]) | (vp[:, 1] == vp[:, 2]) | (vp[:, 0] == vp[:, 2])).any():
        raise bad("a corner names one plane twice")
    if np.abs(grid).max(initial=0) > MAX_GRID:
        raise bad("a grid coordinate is beyond 2^52")
    if explicit.any() and not (np.isfinite(shell.origin).all() and math.isfinite(shell.step) and shell.step > 0):
        raise bad("the grid's origin and step must be finite, the step positive")
    face, tri = fc[:, 0], fc[:, 1:]
    planar = face != FREE
    if planar.any() and ((~planar[:np.flatnonzero(planar)[-1]]).any()):
        raise bad("a free triangle comes before a planar one")
    f = face[planar]
    if len(f) and (f.min() < 0 or f.max() >= count or bounding[f].any()):
        raise bad("a triangle lies on a reference that is not a face plane")
    if (np.diff(f) < 0).any():
        raise bad("triangles are not in order of their face references")
    if tri.min() < 0 or tri.max() >= v:
        raise bad("a triangle refers past the group's corners")
    if ((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])).any():
        raise bad("a triangle names one corner twice")
    if not np.array_equal(first_use_order(tri, v), np.arange(v)):
        raise bad("corners are not numbered in order of first use, or one is unused")


def grid_bytes(shell: Shell, major: int) -> bytes:
    """A shell's grid as a version ``major`` file stores it (spec §9.10): float64, or float32 from
    version 5 on, where origin and step must be float32 values (``groups.shells`` makes them so)."""
    struct, _ = schema.shell_grid(major)
    values = [*(float(x) for x in shell.origin), float(shell.step)]
    if major >= 5 and np.any(np.asarray(values, dtype=np.float32).astype(np.float64) != values):
        raise FormatError("a version 5 shell grid's origin and step must be float32 values",
                          code="BAD_GROUP_STRUCTURE")
    return struct.build(dict(origin=values[:3], step=values[3]))


def _shell_body(shell: Shell, major: int = 4) -> bytes:
    """The kind data of a SHELL group (spec §9.10)."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    face = fc[:, 0]
    planar = face[face != FREE]
    codes = corner_codes(fc[:, 1:])
    out = [varint.encode([len(explicit), len(fc), len(fc) - len(planar)]),
           np.packbits(explicit, bitorder="little").tobytes(),
           varint.encode(np.asarray(shell.vertex_planes, dtype=np.uint64).reshape(-1))]
    if explicit.any():
        grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
        out += [grid_bytes(shell, major),
                varint.encode(varint.zigzag(np.diff(grid, axis=0, prepend=np.zeros((1, 3), dtype=np.int64))))]
    out += [varint.encode(np.diff(planar, prepend=0)), varint.encode(codes)]
    return b"".join(out)


def _decode_shell(raw: np.ndarray, bounding: np.ndarray, major: int = 4, charge: Charge | None = None) -> Shell:
    """The corners and triangles of a SHELL body (spec §9.10), checked; ``charge`` takes the declared
    counts before anything of their size is allocated (spec §12.4)."""
    (v, t, u), pos = varint.decode(raw, 3, "shell counts")
    v, t, u = int(v), int(t), int(u)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 3 and u <= t):
        raise FormatError(f"shell group: {v} corners, {t} triangles, {u} free: outside the ranges the body "
                          f"allows", code="BAD_GROUP_STRUCTURE")
    if charge is not None:
        charge(vertices=v, triangles=t)
    explicit, pos = varint.bit_field(raw, pos, v, "shell group: the body", "corner flags")
    e = int(explicit.sum())
    # Every field is read before any value is checked (spec/pln.md §9.10): a body that ends inside one
    # is BAD_PAYLOAD whatever else is wrong. The counts' checks above bound what is decoded.
    triples, used = varint.decode(raw[pos:], 3 * (v - e), "shell corner planes")
    pos += used
    origin, step, grid = np.zeros(3), 0.0, np.zeros((0, 3), dtype=np.int64)
    if e:
        origin, step, deltas, pos = _read_grid(raw, pos, e, "shell group", "shell corner coordinates", major)
        steps = varint.unzigzag(deltas).reshape(-1, 3)
    gaps, used = varint.decode(raw[pos:], t - u, "shell face references")
    pos += used
    codes, used = varint.decode(raw[pos:], 3 * t, "shell triangle corners")
    if pos + used != len(raw):
        raise FormatError("shell group: the triangles do not fill the body", code="BAD_GROUP_STRUCTURE")
    if e:
        # Checked before the cumulative sum, which steps near 2^63 would overflow (and compared on both
        # sides: abs(-2^63) is still negative in int64).
        if ((steps > MAX_GRID) | (steps < -MAX_GRID)).any():
            raise FormatError("shell group: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        grid = np.cumsum(steps, axis=0)
    if len(gaps) and gaps.max() >= len(bounding):
        raise FormatError("shell group: a face reference is past the group's references",
                          code="BAD_GROUP_STRUCTURE")
    if codes.max() > np.uint64(3 * t):
        raise FormatError("shell group: a triangle corner refers back past the first corner",
                          code="BAD_GROUP_STRUCTURE")
    codes = codes.astype(np.int64)
    new = codes == 0
    seen = np.cumsum(new)
    tri = np.where(new, seen - 1, seen - codes)
    if tri.min() < 0:
        raise FormatError("shell group: a triangle corner refers back past the first corner",
                          code="BAD_GROUP_STRUCTURE")
    face = np.r_[np.cumsum(gaps.astype(np.int64)), np.full(u, FREE, dtype=np.int64)]
    shell = Shell(explicit=explicit, vertex_planes=triples.astype(np.int64).reshape(-1, 3), grid=grid,
                  origin=origin, step=step, facets=np.column_stack([face, tri.reshape(-1, 3)]))
    check_shell(shell, bounding)
    return shell


# spec 3.3 §8.10 Shell trees ----------------------------------------------------------------------

def _read_grid(raw: np.ndarray, pos: int, explicit: int, label: str,
               field: str, major: int = 4) -> tuple[np.ndarray, float, np.ndarray, int]:
    """A shell body's grid (spec §9.10) at ``pos`` and the ``3 * explicit`` coordinate varints after it
    (``field`` in messages): ``(origin, step, raw coordinate varints, position after them)``."""
    origin, step, pos = read_grid(raw, pos, label, major)
    deltas, used = varint.decode(raw[pos:], 3 * explicit, field)
    return origin, step, deltas, pos + used


def read_grid(raw: np.ndarray, pos: int, label: str, major: int) -> tuple[np.ndarray, float, int]:
    """The grid of a version ``major`` shell body at ``pos`` (spec §9.10): origin, step, position after it."""
    _, size = schema.shell_grid(major)
    if len(raw) < pos + size:
        raise FormatError(f"{label}: the body ends inside its grid", code="BAD_PAYLOAD")
    # Four little-endian floats of the struct's width, viewed rather than parsed field by field.
    g = np.frombuffer(raw[pos:pos + size].tobytes(), dtype="<f4" if size == 16 else "<f8").astype(np.float64)
    return g[:3], float(g[3]), pos + size


def resolve_chains(value: np.ndarray, pointer: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``value[k]`` where ``pointer[k] < 0``, else ``offset[k]`` plus the resolved value at
    ``pointer[k]``, which is always an earlier entry. One forward pass in C (``_chains.c``) where the
    extension was built; otherwise pointer jumping: each round halves every chain, so a tree of depth
    817 (CAD/box.STL) takes 11 rounds of numpy work over the arrays."""
    value = np.array(value, dtype=np.int64)
    if _resolve_forward is not None:
        try:
            _resolve_forward(value, np.ascontiguousarray(pointer, dtype=np.int64),
                             np.ascontiguousarray(offset, dtype=np.int64))
        except ValueError as exc:
            raise FormatError(f"shell tree: {exc}", code="BAD_GROUP_STRUCTURE") from None
        return value
    return _jump(value, np.array(pointer, dtype=np.int64), np.array(offset, dtype=np.int64))


def resolve_sums(value: np.ndarray, pointer: np.ndarray, plus: np.ndarray, minus: np.ndarray,
                 offset: np.ndarray) -> np.ndarray:
    """:func:`resolve_chains` with a second earlier entry added and a third subtracted where ``plus``
    and ``minus`` are not -1 (a parallelogram's a + b - c, spec §9.12), every ``value`` and ``offset``
    within :data:`MAX_GRID`; ``BAD_GROUP_STRUCTURE`` where a resolved value is not (checked as each
    is made: a chain of parallelograms can double at every step). One forward pass in C; without it,
    the lower-triangular system (I - P) x = value solved by scipy (exact while every value is within
    2^53; a value beyond that is beyond MAX_GRID, however rounded)."""
    value = np.array(value, dtype=np.int64)
    pointer, plus, minus = (np.ascontiguousarray(a, dtype=np.int64) for a in (pointer, plus, minus))
    if _resolve_forward is not None:
        try:
            _resolve_forward(value, pointer, np.ascontiguousarray(offset, dtype=np.int64), plus, minus, MAX_GRID)
        except ValueError as exc:
            raise FormatError(f"shell tree: {exc}", code="BAD_GROUP_STRUCTURE") from None
        except OverflowError:
            raise FormatError("shell tree: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE") from None
        return value
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve_triangular

    n = len(value)
    row = np.arange(n)
    live = pointer >= 0
    parts = [(row[live], pointer[live], -1.0), (row[live & (plus >= 0)], plus[live & (plus >= 0)], -1.0),
             (row[live & (minus >= 0)], minus[live & (minus >= 0)], 1.0), (row, row, 1.0)]
    if any((c >= r).any() for r, c, _ in parts[:3]):
        raise FormatError("shell tree: a predictor is not an earlier entry", code="BAD_GROUP_STRUCTURE")
    matrix = coo_matrix((np.concatenate([np.full(len(r), w) for r, _, w in parts]),
                         (np.concatenate([r for r, _, _ in parts]), np.concatenate([c for _, c, _ in parts]))),
                        shape=(n, n)).tocsr()
    rhs = np.where(live, np.asarray(offset, dtype=np.int64), value).astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        solved = spsolve_triangular(matrix, rhs, lower=True)
    if not (np.abs(solved) <= MAX_GRID).all():
        raise FormatError("shell tree: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE")
    return np.rint(solved).astype(np.int64)


def _jump(value: np.ndarray, pointer: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """:func:`resolve_chains` in numpy alone, in place on its (copied) arguments."""
    pending = np.flatnonzero(pointer >= 0)
    while len(pending):
        target = pointer[pending]
        ready = pointer[target] < 0
        done, wait, via = pending[ready], pending[~ready], target[~ready]
        # Jump from what the targets were at the start of the round, not what this round made them.
        offset[wait], pointer[wait] = offset[wait] + offset[via], pointer[via]
        value[done] = offset[done] + value[target[ready]]
        pointer[done] = -1
        pending = wait
    return value


def _read_tables(raw: np.ndarray, pos: int, explicit: int) -> tuple[list[np.ndarray], int]:
    """A shell walk's three value tables (spec §9.13) at ``pos``, each checked as it is read (its
    count decides how much follows), and the position after them."""
    tables = []
    for axis in "xyz":
        (count,), used = varint.decode(raw[pos:], 1, f"shell walk {axis} table count")
        pos += used
        if not 1 <= int(count) <= explicit:
            raise FormatError(f"shell walk: a {axis} table of {int(count)} values for {explicit} explicit corners",
                              code="BAD_GROUP_STRUCTURE")
        values, used = varint.decode(raw[pos:], int(count), f"shell walk {axis} table")
        pos += used
        first, gaps = varint.unzigzag(values[:1])[0], values[1:]
        # Every value within 2^52 keeps the last minus the first within 2^53, the gaps' sum with it:
        # checked in floating point before the integer sum could wrap.
        if abs(int(first)) > MAX_GRID or float(gaps.astype(np.float64).sum()) + len(gaps) > 2.0 * MAX_GRID + 1:
            raise FormatError(f"shell walk: a {axis} table value is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        table = int(first) + np.cumsum(np.r_[0, gaps.astype(np.int64) + 1])
        if np.abs(table).max() > MAX_GRID:
            raise FormatError(f"shell walk: a {axis} table value is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        tables.append(table)
    return tables, pos


def incident_planes(triangles: np.ndarray, face: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct face references of the planar triangles at each of ``count`` corners, ascending:
    (references, start and count of each corner's run in them)."""
    live = face != FREE
    m = int(face.max(initial=0)) + 1
    key = np.unique(triangles[live].reshape(-1) * m + np.repeat(face[live], 3))
    corner = key // m
    runs = np.bincount(corner, minlength=count)
    return key % m, np.cumsum(runs) - runs, runs


def _tree_parents(links: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    root = links == 0
    d = (links - 1) // 3 + 1
    return root, np.where(root, -1, np.arange(len(links)) - d), np.where(root, 0, (links - 1) % 3)


def _tree_predictors(links: np.ndarray, triangles: np.ndarray, explicit: np.ndarray, per: np.ndarray,
                     new: np.ndarray, parallelogram: bool = False, later: bool = False) -> np.ndarray:
    """For each corner, the corners its grid coordinates are coded from, ``(V, 3)``: ``(p, a, b)``
    for the prediction p + a - b, -1 where a term is absent (spec §9.11, §9.12). Kind 7 (§9.11): p the
    first corner of the attached triangle that names the corner anew, where that corner is explicit;
    otherwise the previous explicit corner; -1 for none (coded from 0); with ``later`` (kind 13, §9.17)
    the later-named of that triangle's first two corners instead of its first. Kind 8
    (``parallelogram``, §9.12): where that triangle's first two corners and its parent's corner
    opposite them are all explicit, those three. ``per``: each triangle's corner codes (3 or 1);
    ``new``: which codes name a corner anew. In C (``_chains.tree_terms``, one pass for the fifteen of
    numpy below) where the extension was built."""
    v = len(explicit)
    if _tree_terms is not None:
        out = np.empty((v, 3), dtype=np.int64)
        try:
            _tree_terms(np.ascontiguousarray(links, dtype=np.int64), np.ascontiguousarray(triangles, dtype=np.int64),
                        np.ascontiguousarray(explicit, dtype=bool), np.ascontiguousarray(new, dtype=bool),
                        parallelogram, later, out)
            return out
        except ValueError:
            pass  # a tree its caller did not check: numpy's indexing says what is wrong
    creator = np.repeat(np.arange(len(triangles)), per)[new]
    gate, second = triangles[creator, 0], triangles[creator, 1]
    if later:
        gate, second = np.maximum(gate, second), np.minimum(gate, second)
    attached = links[creator] != 0
    previous = np.r_[-1, np.maximum.accumulate(np.where(explicit, np.arange(v), -1))[:-1]]
    out = np.full((v, 3), -1, dtype=np.int64)
    out[:, 0] = np.where(attached & explicit[gate], gate, previous)
    if parallelogram:
        link = links[creator]
        parent, edge = creator - (link - 1) // 3 - 1, (link - 1) % 3
        opposite = triangles[np.maximum(parent, 0), (edge + 2) % 3]
        use = attached & explicit[gate] & explicit[second] & explicit[opposite]
        out[use, 1], out[use, 2] = second[use], opposite[use]
    return out


def parallelograms(triangles: np.ndarray, explicit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each corner's parallelograms of spec §9.14, as ``start`` (V + 1: corner k's are rows
    ``start[k]:start[k + 1]``) and ``terms`` (rows ``(a, b, c)``, predicting a + b - c): for each
    triangle in order and each place of k in it, the edge (a, b) opposite k and the far corner c of
    that edge (the third corner of the first triangle that has (b, a)), where a, b and c are
    explicit and numbered below k; the first :data:`MAX_PARALLELOGRAMS` of each corner. In C (a hash
    map of directed edges keyed per call, two passes over the triangles) where the extension was built; else sorts."""
    tri = np.asarray(triangles, dtype=np.int64)
    v = len(explicit)
    if _parallelograms is not None and MAX_PARALLELOGRAMS == 4:
        start = np.zeros(v + 1, dtype=np.int64)
        terms = np.zeros(12 * v, dtype=np.int64)
        rows = _parallelograms(np.ascontiguousarray(tri.reshape(-1)), np.asarray(explicit, dtype=np.int64), start,
                               terms, secrets.randbits(64))
        return start, terms[:3 * rows].reshape(-1, 3)
    k, a, b = (np.roll(tri, -s, axis=1).reshape(-1) for s in range(3))
    # Far corners: the edges sorted by (start, end), stable, so the first of a run is the first triangle's.
    key = k * v + a
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    first = np.r_[True, sorted_key[1:] != sorted_key[:-1]]
    edge_key, edge_far = sorted_key[first], b[order][first]
    want = b * v + a
    at = np.minimum(np.searchsorted(edge_key, want), max(len(edge_key) - 1, 0))
    found = edge_key[at] == want if len(edge_key) else np.zeros(len(want), dtype=bool)
    c = np.where(found, edge_far[at], 0)
    live = found & (a < k) & (b < k) & (c < k) & explicit[k] & explicit[a] & explicit[b] & explicit[c]
    k, terms = k[live], np.column_stack([a[live], b[live], c[live]])
    order = np.argsort(k, kind="stable")
    k, terms = k[order], terms[order]
    counts = np.bincount(k, minlength=v)
    rank = np.arange(len(k)) - (np.cumsum(counts) - counts)[k]
    keep = rank < MAX_PARALLELOGRAMS
    counts = np.bincount(k[keep], minlength=v)
    return np.r_[0, np.cumsum(counts)], terms[keep]


def predict_averaged(values: np.ndarray, start: np.ndarray, terms: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """The predictions ``(V, 3)`` of spec §9.14 from every corner's known ``values``: the floor
    average of a corner's parallelograms (:func:`parallelograms`), or ``fallback`` where it has none."""
    counts = np.diff(start)
    owner = np.repeat(np.arange(len(counts)), counts)
    sums = np.zeros_like(values)
    np.add.at(sums, owner, values[terms[:, 0]] + values[terms[:, 1]] - values[terms[:, 2]])
    averaged = np.floor_divide(sums + (counts // 2)[:, None], np.maximum(counts, 1)[:, None])
    return np.where((counts > 0)[:, None], averaged, fallback)


def _resolve_averaged(value: np.ndarray, pointer: np.ndarray, plus: np.ndarray, minus: np.ndarray,
                      start: np.ndarray, terms: np.ndarray) -> np.ndarray:
    """One axis of a kind 10 walk's corners resolved in corner order (spec §9.14): ``value`` the
    residuals (a corner's value where it has no predictor), each resolved value checked against
    :data:`MAX_GRID` as it is made. In C (``_chains.average``); without it, the same loop in Python."""
    out = np.array(value, dtype=np.int64)
    columns = [np.ascontiguousarray(terms[:, i], dtype=np.int64) for i in range(3)]
    if _average is not None:
        try:
            _average(out, *(np.ascontiguousarray(x, dtype=np.int64) for x in (pointer, plus, minus, value, start)),
                     *columns, MAX_GRID)
        except ValueError as exc:
            raise FormatError(f"shell walk: {exc}", code="BAD_GROUP_STRUCTURE") from None
        except OverflowError:
            raise FormatError("shell walk: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE") from None
        return out
    res = [int(x) for x in value]
    got = [int(x) for x in value]
    ca, cb, cc = (col.tolist() for col in columns)
    for k, (lo, hi) in enumerate(zip(start[:-1].tolist(), start[1:].tolist())):
        if hi > lo:
            total = sum(got[ca[q]] + got[cb[q]] - got[cc[q]] for q in range(lo, hi))
            x = res[k] + (total + (hi - lo) // 2) // (hi - lo)
        elif pointer[k] >= 0:
            x = res[k] + got[pointer[k]] + (got[plus[k]] if plus[k] >= 0 else 0) - (got[minus[k]] if minus[k] >= 0 else 0)
        else:
            continue
        if abs(x) > MAX_GRID:
            raise FormatError("shell walk: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        got[k] = x
    return np.array(got, dtype=np.int64)


def _chains_of(step: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each corner's step sources a = step[k], b = step[a], c = step[b] (spec §9.16), -1 where absent."""
    b = np.where(step >= 0, step[np.maximum(step, 0)], -1)
    return step, b, np.where(b >= 0, step[np.maximum(b, 0)], -1)


def predict_reflected(values: np.ndarray, step: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """The predictions ``(V, 3)`` of spec §9.16 from every corner's known ``values``: the last step of a
    corner's turning chain of ``step`` sources (§9.11's predictors) turned on by the angle between its
    last two steps, in exact integers; ``fallback`` (§9.13's prediction) where the chain does not turn."""
    a, b, c = _chains_of(step)
    ga, gb, gc = (values[np.maximum(x, 0)] for x in (a, b, c))
    d1, d2 = gb - gc, ga - gb
    d = (d2 * d2).sum(axis=1)
    turns = (c >= 0) & (d > 0) & (np.abs(d1).max(axis=1) <= MAX_TURN) & (np.abs(d2).max(axis=1) <= MAX_TURN)
    # Steps that do not turn are zeroed first: their products could pass 2^63.
    d1, d2 = d1 * turns[:, None], d2 * turns[:, None]
    den = np.where(turns, d, 1)[:, None]
    num = 2 * (d1 * d2).sum(axis=1)[:, None] * d2 - den * d1
    return np.where(turns[:, None], ga + np.floor_divide(2 * num + den, 2 * den), fallback)


def _resolve_reflected(residual: np.ndarray, terms: np.ndarray, explicit: np.ndarray) -> np.ndarray:
    """A kind 12 walk's corners ``(V, 3)`` resolved in corner order (spec §9.16) from their
    ``residual`` ``(V, 3)`` and :func:`_tree_predictors`' ``terms`` (step source, plus, minus), each
    resolved value checked against :data:`MAX_GRID` as it is made; named corners stay 0. In C
    (``_chains.reflect``); without it, the same loop in Python."""
    out = np.ascontiguousarray(residual, dtype=np.int64).copy()
    pointer, plus, minus = (np.ascontiguousarray(np.where(explicit, t, -1), dtype=np.int64) for t in terms.T)
    if _reflect is not None:
        try:
            _reflect(out, pointer, plus, minus, MAX_GRID, MAX_TURN)
        except ValueError as exc:
            raise FormatError(f"shell walk: {exc}", code="BAD_GROUP_STRUCTURE") from None
        except OverflowError:
            raise FormatError("shell walk: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE") from None
        return out
    got = [[int(x) for x in row] for row in out]
    ps, qs, ms = pointer.tolist(), plus.tolist(), minus.tolist()
    for k, a in enumerate(ps):
        if a < 0:
            continue
        b = ps[a]
        c = ps[b] if b >= 0 else -1
        d = 0
        if c >= 0:
            d1 = [got[b][i] - got[c][i] for i in range(3)]
            d2 = [got[a][i] - got[b][i] for i in range(3)]
            d = sum(x * x for x in d2) if max(map(abs, d1 + d2)) <= MAX_TURN else 0
        if d:
            dot = sum(x * y for x, y in zip(d1, d2))
            x = [got[k][i] + got[a][i] + (2 * (2 * dot * d2[i] - d * d1[i]) + d) // (2 * d) for i in range(3)]
        else:
            x = [got[k][i] + got[a][i] + (got[qs[k]][i] if qs[k] >= 0 else 0) - (got[ms[k]][i] if ms[k] >= 0 else 0)
                 for i in range(3)]
        if max(map(abs, x)) > MAX_GRID:
            raise FormatError("shell walk: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        got[k] = x
    return np.array(got, dtype=np.int64).reshape(-1, 3)


def _predict(grid: np.ndarray, terms: np.ndarray) -> np.ndarray:
    """The predictions ``(V, 3)`` of :func:`_tree_predictors`' ``terms`` from every corner's ``grid``."""
    def at(j: np.ndarray) -> np.ndarray:
        return np.where(j[:, None] >= 0, grid[np.maximum(j, 0)], 0)
    return at(terms[:, 0]) + at(terms[:, 1]) - at(terms[:, 2])


def same_tree(back: Shell, shell: Shell) -> bool:
    """Whether ``back``, a tree's body as decoded, is ``shell``: corners, triangles, links and grid."""
    fields = ("explicit", "vertex_planes", "grid", "facets", "links")
    return all(np.array_equal(np.asarray(getattr(back, f)).reshape(-1), np.asarray(getattr(shell, f)).reshape(-1))
               for f in fields) and not (back.grid.size and (not np.array_equal(back.origin, shell.origin)
                                                             or back.step != shell.step))


def check_shell_tree(shell: Shell, bounding: np.ndarray, parallelogram: bool = False) -> None:
    """``FormatError`` (``BAD_GROUP_STRUCTURE``) unless ``shell`` is a shell tree of spec §9.11 (§9.12
    with ``parallelogram``) for a group whose references have roles ``bounding``: what its body decodes
    to, it is."""
    if shell.links is None or len(shell.links) != len(shell.facets):
        raise FormatError("shell tree: one link per triangle", code="BAD_GROUP_STRUCTURE")
    back = _decode_shell_tree(np.frombuffer(_shell_tree_body(shell, parallelogram), dtype=np.uint8),
                              np.asarray(bounding, bool), parallelogram)
    if not same_tree(back, shell):
        raise FormatError("shell tree: its body does not decode to it (triangles not attached at their first "
                          "edge, corners not numbered by first use, or named corners not three of their face "
                          "planes in ascending order)", code="BAD_GROUP_STRUCTURE")


def _shell_tree_body(shell: Shell, parallelogram: bool = False, major: int = 4) -> bytes:
    """The kind data of a SHELL_TREE group (spec §9.11), or with ``parallelogram`` of a
    SHELL_TREE_PARALLELOGRAM group (§9.12)."""
    return b"".join(shell_tree_fields(shell, parallelogram, major).values())


def shell_tree_fields(shell: Shell, parallelogram: bool = False, major: int = 4) -> dict[str, bytes]:
    """The fields of a SHELL_TREE body (spec §9.11), or a SHELL_TREE_PARALLELOGRAM one (§9.12), by
    name, in body order."""
    common, coordinates = _tree_fields(shell, major)
    return {**common, **coordinates(parallelogram)}


def shell_tree_bodies(shell: Shell) -> dict[GroupKind, bytes]:
    """The kind data of ``shell`` as a SHELL_TREE and as a SHELL_TREE_PARALLELOGRAM group, which
    differ in their coordinates only: the rest is made once."""
    common, coordinates = _tree_fields(shell)
    head = b"".join(common.values())
    return {kind: head + b"".join(coordinates(kind == GroupKind.SHELL_TREE_PARALLELOGRAM).values())
            for kind in (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM)}


def code_stream(tri: np.ndarray, root: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stream of corners a shell tree codes (a root's three, an attached triangle's third; spec
    §9.11), which of them name a corner anew, and how many corners were named before each."""
    slots = np.where(root[:, None], tri, np.column_stack([np.full((len(tri), 2), -1), tri[:, 2]]))
    stream = slots.reshape(-1)
    stream = stream[stream >= 0]
    new = np.r_[True, stream[1:] > np.maximum.accumulate(stream)[:-1]]
    return stream, new, np.cumsum(new) - new


def surface_fields(shell: Shell) -> dict[str, bytes]:
    """A shell tree's faces, corner flags and picks (spec §9.11; §9.13 the same), by name."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    root, parent, _ = _tree_parents(np.asarray(shell.links, dtype=np.int64))
    face, tri, v = fc[:, 0], fc[:, 1:], len(explicit)
    same = np.where(root, np.r_[FREE, face[:-1]], face[np.maximum(parent, 0)]) == face
    out = {"faces": varint.encode(np.where(same, 0, np.where(face == FREE, 1, face + 2))),
           "flags": np.packbits(explicit, bitorder="little").tobytes(), "picks": b""}
    named = np.flatnonzero(~explicit)
    if len(named):
        refs, start, runs = incident_planes(tri, face, v)
        vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)
        wide = runs[named] > 3
        # Each plane's place in its corner's run: one search over (corner, reference) keys.
        span = max(int(refs.max(initial=0)), int(vp.max(initial=0))) + 1
        key = np.repeat(np.arange(v), runs) * span + refs
        out["picks"] = varint.encode(np.searchsorted(key, named[wide, None] * span + vp[wide])
                                     - start[named[wide], None])
    return out


def _tree_fields(shell: Shell, major: int = 4):
    """The fields of a shell tree's body up to the picks, and a function of ``parallelogram`` giving
    the grid and the coordinates (none without explicit corners)."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    links = np.asarray(shell.links, dtype=np.int64)
    root, parent, edge = _tree_parents(links)
    face, tri = fc[:, 0], fc[:, 1:]
    t, v = len(fc), len(explicit)
    stream, new, before = code_stream(tri, root)
    is_root = np.repeat(root, np.where(root, 3, 1))
    c1 = np.repeat(tri[:, 1], np.where(root, 3, 1))
    codes = np.where(new, 0, np.where(is_root, before - stream,
                                      varint.zigzag(stream - c1).astype(np.int64) + 1))
    out = {"counts": varint.encode([v, t]), "links": varint.encode(links), "codes": varint.encode(codes),
           **surface_fields(shell)}

    def coordinates(parallelogram: bool) -> dict[str, bytes]:
        if not explicit.any():
            return {}
        g_all = np.zeros((v, 3), dtype=np.int64)
        g_all[explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
        base = _predict(g_all, _tree_predictors(links, tri, explicit, np.where(root, 3, 1), new, parallelogram))
        # Axis by axis: each axis's residuals deflate as one run (CAD/box.STL: 7.5 kB against 8.8 kB
        # interleaved).
        return {"grid": grid_bytes(shell, major),
                "coordinates": varint.encode(varint.zigzag((g_all - base)[explicit].T))}
    return out, coordinates


def _decode_shell_tree(raw: np.ndarray, bounding: np.ndarray, parallelogram: bool = False, major: int = 4,
                       charge: Charge | None = None) -> Shell:
    """The corners and triangles of a SHELL_TREE body (spec §9.11), or with ``parallelogram`` of a
    SHELL_TREE_PARALLELOGRAM body (§9.12), checked; ``charge`` as :func:`_decode_shell`'s."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"shell tree: {reason}", code="BAD_GROUP_STRUCTURE")
    (v, t), pos = varint.decode(raw, 2, "shell tree counts")
    v, t = int(v), int(t)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 3):
        raise bad(f"{v} corners, {t} triangles: outside the ranges the body allows")
    if charge is not None:
        charge(vertices=v, triangles=t)
    links, used = varint.decode(raw[pos:], t, "shell tree links")
    pos += used
    codes, used = varint.decode(raw[pos:], t + 2 * int((links == 0).sum()), "shell tree corner codes")
    pos += used
    faces, used = varint.decode(raw[pos:], t, "shell tree faces")
    pos += used
    explicit, pos = varint.bit_field(raw, pos, v, "shell tree: the body", "corner flags")
    if links.max() > np.uint64(3 * t):
        raise bad("a triangle is attached to one before the first")
    links = links.astype(np.int64)
    root, parent, edge = _tree_parents(links)
    if (parent[~root] < 0).any():
        raise bad("a triangle is attached to one before the first")
    if codes.max() > np.uint64(2 * v + 1):
        raise bad("a corner code is past the group's corners")
    codes = codes.astype(np.int64)
    per = np.where(root, 3, 1)
    end = np.cumsum(per)
    first = end - per
    new = codes == 0
    before = np.cumsum(new) - new
    is_root = np.repeat(root, per)
    # Each triangle slot (3 per triangle) is a corner, or a pointer to an earlier slot plus an offset.
    value = np.zeros(3 * t, dtype=np.int64)
    pointer = np.full(3 * t, -1, dtype=np.int64)
    offset = np.zeros(3 * t, dtype=np.int64)
    direct = np.where(new, before, before - codes)
    rows = np.flatnonzero(root)
    value[(3 * rows[:, None] + np.arange(3)).reshape(-1)] = direct[(first[rows, None] + np.arange(3)).reshape(-1)]
    att = np.flatnonzero(~root)
    pointer[3 * att] = 3 * parent[att] + (edge[att] + 1) % 3
    pointer[3 * att + 1] = 3 * parent[att] + edge[att]
    third = first[att]
    fresh = new[third]
    value[3 * att[fresh] + 2] = before[third[fresh]]
    old = att[~fresh]
    pointer[3 * old + 2] = 3 * old + 1
    offset[3 * old + 2] = varint.unzigzag((codes[third[~fresh]] - 1).astype(np.uint64))
    if (~new & is_root & (codes > before)).any():
        raise bad("a triangle corner refers back past the first corner")
    tri = resolve_chains(value, pointer, offset).reshape(-1, 3)
    named_again = tri[old, 2]
    if ((named_again < 0) | (named_again >= before[third[~fresh]])).any():
        raise bad("a triangle's third corner is not one named before it")
    if int(new.sum()) != v:
        raise bad(f"{int(new.sum())} corners are named anew, not {v}")
    if ((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])).any():
        raise bad("a triangle names one corner twice")
    return tree_rest(raw, pos, bounding, tri, links, faces, explicit, new, parallelogram, major=major)


def tree_rest(raw: np.ndarray, pos: int, bounding: np.ndarray, tri: np.ndarray, links: np.ndarray,
              faces: np.ndarray, explicit: np.ndarray, new: np.ndarray, parallelogram: bool | None,
              averaged: bool = False, major: int = 4, reflected: bool = False, later: bool = False) -> Shell:
    """A shell tree's body from its faces' checks on (spec §9.11 and §9.12; §9.13 with
    ``parallelogram`` None, whose mode byte and tables come before the coordinates; §9.14 with
    ``averaged`` too, whose corners parallelograms average where they can; §9.16 with ``reflected``,
    whose corners a turning chain of steps predicts; §9.17 with ``later``, whose corners step from the
    later-named gate corner): ``tri`` and
    ``links`` as decoded, ``faces`` the face codes and ``explicit`` the flags as read, ``new`` which of
    the corner code stream's entries (3 per root, 1 per attached triangle) name a corner anew."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"shell tree: {reason}", code="BAD_GROUP_STRUCTURE")
    t, v = len(tri), len(explicit)
    root, parent, _ = _tree_parents(links)
    per = np.where(root, 3, 1)
    m = len(bounding)
    if faces.max() > np.uint64(m + 1):
        raise bad("a face reference is past the group's references")
    faces = faces.astype(np.int64)
    fvalue = np.where(faces == 1, FREE, faces - 2)
    fpointer = np.where(faces == 0, np.where(root, np.arange(t) - 1, parent), -1)
    fvalue[(faces == 0) & (fpointer < 0)] = FREE
    fpointer[fpointer < 0] = -1
    face = resolve_chains(fvalue, fpointer, np.zeros(t, dtype=np.int64))
    planar = face != FREE
    if bounding[face[planar]].any():
        raise bad("a triangle lies on a reference that is not a face plane")
    named = np.flatnonzero(~explicit)
    vertex_planes = np.zeros((0, 3), dtype=np.int64)
    if len(named):
        refs, start, runs = incident_planes(tri, face, v)
        wide = named[runs[named] > 3]
        picks, used = varint.decode(raw[pos:], 3 * len(wide), "shell tree corner planes")
        pos += used
        picks = picks.reshape(-1, 3)
    e = int(explicit.sum())
    origin, step, grid = np.zeros(3), 0.0, np.zeros((0, 3), dtype=np.int64)
    if e:
        mode = 0
        if parallelogram is None:
            if pos >= len(raw):
                raise FormatError("shell walk: the body ends inside its mode", code="BAD_PAYLOAD")
            mode = int(raw[pos])
            pos += 1
            parallelogram = bool(mode & 1)
        origin, step, pos = read_grid(raw, pos, "shell tree", major)
        tables = None
        if mode & 2:
            tables, pos = _read_tables(raw, pos, e)
        deltas, used = varint.decode(raw[pos:], 3 * e, "shell tree corner coordinates")
        pos += used
        if mode & ~schema.SHELL_WALK_MODES:
            raise bad(f"coordinate mode {mode} has a bit above 1 set")
    # §9.11, §9.13: the named corners' planes and picks are values of "the rest", checked once every
    # field is read, so that a body cut short is BAD_PAYLOAD whatever they hold.
    if len(named):
        if (runs[named] < 3).any():
            raise bad("a named corner is on fewer than three face planes")
        if len(wide) and ((picks[:, 0] >= picks[:, 1]) | (picks[:, 1] >= picks[:, 2])
                          | (picks[:, 2] >= runs[wide].astype(np.uint64))).any():
            raise bad("a corner's planes are not three of its face planes in ascending order")
        pick = np.tile(np.arange(3, dtype=np.int64), (len(named), 1))
        pick[runs[named] > 3] = picks.astype(np.int64)
        vertex_planes = refs[start[named, None] + pick]
    if e:
        steps = varint.unzigzag(deltas).reshape(3, -1).T
        if np.abs(steps).max(initial=0) > MAX_GRID:
            raise bad("a grid residual is beyond 2^52")
        terms = _tree_predictors(links, tri, explicit, per, new, parallelogram, later)
        ex = np.flatnonzero(explicit)
        residual = np.zeros((3, v), dtype=np.int64)
        residual[:, ex] = steps.T
        if reflected:
            grid = _resolve_reflected(residual.T, terms, explicit)[ex]
        elif averaged:
            start, quads = parallelograms(tri, explicit)
            grid = np.column_stack([_resolve_averaged(residual[axis], *terms.T, start, quads)
                                    for axis in range(3)])[ex]
        elif _reflect is not None:
            # The three axes in one pass over the corners: reflect() without turns (turn 0) is resolve()'s
            # rule on rows. A value beyond 2^52 anywhere is refused in either order, and no term is a
            # later corner (a corner's terms were named before it), so nothing else can differ.
            rows = np.ascontiguousarray(residual.T)
            try:
                _reflect(rows, *(np.ascontiguousarray(j) for j in terms.T), MAX_GRID, 0)
            except ValueError as exc:
                raise FormatError(f"shell tree: {exc}", code="BAD_GROUP_STRUCTURE") from None
            except OverflowError:
                raise bad("a grid coordinate is beyond 2^52") from None
            grid = rows[ex]
        else:
            # One chain per axis: axis i's entries are i * V on.
            pointers = [np.where(j >= 0, j + np.arange(3)[:, None] * v, -1).reshape(-1) for j in terms.T]
            flat = residual.reshape(-1)
            chained = resolve_sums(flat, *pointers, flat)
            grid = chained.reshape(3, v).T[ex]
        if np.abs(grid).max(initial=0) > MAX_GRID:
            raise bad("a grid coordinate is beyond 2^52")
        if tables is not None:
            for axis, table in enumerate(tables):
                if ((grid[:, axis] < 0) | (grid[:, axis] >= len(table))).any():
                    raise bad(f"a corner's index is outside the {'xyz'[axis]} table")
                grid[:, axis] = table[grid[:, axis]]
    if pos != len(raw):
        raise bad("the corners do not fill the body")
    shell = Shell(explicit=explicit, vertex_planes=vertex_planes, grid=grid, origin=origin, step=step,
                  facets=np.column_stack([face, tri]), links=links)
    if e and not (np.isfinite(origin).all() and math.isfinite(step) and step > 0):
        raise bad("the grid's origin and step must be finite, the step positive")
    return shell
