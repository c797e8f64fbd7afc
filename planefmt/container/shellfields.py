"""The fields of shell groups (kind 6, spec §9.10): corner codes in first-use order, the body as
written and read, and every check the spec asks of a shell."""

from __future__ import annotations

import math

import numpy as np

from ..errors import FormatError
from ..model import FREE, MAX_GRID, Shell
from . import schema, varint


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
    seen, first = np.unique(flat, return_index=True)
    rank = np.full(count, -1, dtype=np.int64)
    rank[seen[np.argsort(first, kind="stable")]] = np.arange(len(seen))
    return rank


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


def _shell_body(shell: Shell) -> bytes:
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
        out += [schema.ShellGrid.build(dict(origin=[float(x) for x in shell.origin], step=float(shell.step))),
                varint.encode(varint.zigzag(np.diff(grid, axis=0, prepend=np.zeros((1, 3), dtype=np.int64))))]
    out += [varint.encode(np.diff(planar, prepend=0)), varint.encode(codes)]
    return b"".join(out)


def _decode_shell(raw: np.ndarray, bounding: np.ndarray) -> Shell:
    """The corners and triangles of a SHELL body (spec §9.10), checked."""
    (v, t, u), pos = varint.decode(raw, 3, "shell counts")
    v, t, u = int(v), int(t), int(u)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 3 and u <= t):
        raise FormatError(f"shell group: {v} corners, {t} triangles, {u} free: outside the ranges the body "
                          f"allows", code="BAD_GROUP_STRUCTURE")
    explicit, pos = varint.bit_field(raw, pos, v, "shell group: the body", "corner flags")
    e = int(explicit.sum())
    # Every field is read before any value is checked (spec/pln.md §9.10): a body that ends inside one
    # is BAD_PAYLOAD whatever else is wrong. The counts' checks above bound what is decoded.
    triples, used = varint.decode(raw[pos:], 3 * (v - e), "shell corner planes")
    pos += used
    origin, step, grid = np.zeros(3), 0.0, np.zeros((0, 3), dtype=np.int64)
    if e:
        if len(raw) < pos + schema.SHELL_GRID_BYTES:
            raise FormatError("shell group: the body ends inside its grid", code="BAD_PAYLOAD")
        g = schema.ShellGrid.parse(raw[pos:pos + schema.SHELL_GRID_BYTES].tobytes())
        pos += schema.SHELL_GRID_BYTES
        origin, step = np.array(g.origin, dtype=np.float64), float(g.step)
        deltas, used = varint.decode(raw[pos:], 3 * e, "shell corner coordinates")
        pos += used
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
