"""Shell walks (kind 9, spec §9.13): a shell tree whose tree is a depth-first walk (each triangle
names the free edges its children hang on) and whose third corners named before are mostly "left"
or "right", the other end of an open edge at the triangle's first two corners; one symbol per
triangle carries both. Explicit corners may be coded as indices into each axis's sorted values.

The walk is sequential (each answer depends on every triangle before it): ``_chains.c`` runs it in
C, in time linear in the triangles whatever the file holds (its edge map is hashed with a key drawn
per decode, spec §9.13); without the extension :class:`OpenEdges` runs the same rules in Python,
slowly.
"""

from __future__ import annotations

import hashlib
import itertools
import secrets
import zlib

import brotli
import numpy as np

from ..errors import FormatError, LimitError
from ..model import GroupKind, Shell
from . import schema, varint
from .budget import Charge
from .recent import Recent
from .shellfields import (_predict, _shell_body, grid_bytes, _shell_tree_body, _tree_parents, _tree_predictors, code_stream,
                          parallelograms, predict_averaged, predict_reflected, same_tree, surface_fields, tree_rest)

try:
    from ._chains import walk as _walk_c, walk_codes as _walk_codes_c
except ImportError:  # built without a C compiler
    _walk_c = _walk_codes_c = None

#: The ordered lists of a triangle's free edges (places in its free edges), by length then
#: lexicographically: a root's symbol is the index of its list in ROOT_CHILDREN, an attached
#: triangle's symbol // 4 that in ATTACHED_CHILDREN (spec §9.13).
ROOT_CHILDREN = tuple(p for n in range(4) for p in itertools.permutations(range(3), n))
ATTACHED_CHILDREN = tuple(p for n in range(3) for p in itertools.permutations(range(2), n))

#: Coordinate mode bits (spec §9.13).
MODE_PARALLELOGRAM, MODE_TABLES = 1, 2
MODES = (0, MODE_PARALLELOGRAM, MODE_TABLES, MODE_PARALLELOGRAM | MODE_TABLES)

_REASONS = {1: "a symbol is past its range", 2: "the walk needs more escapes than the body holds",
            3: "a corner code names a corner below 0 or not named before",
            4: "a left or right code has no open edge to name", 5: "a triangle names one corner twice",
            6: "the walk promises children after the last triangle", 7: "escapes are left after the walk",
            8: "the walk names a number of corners other than the count"}


class OpenEdges:
    """The open edges of spec §9.13 in Python, as ``_chains.c`` keeps them: each entry on the stack of
    its directed edge (a dict from the edge to its newest entry; Python's int-tuple hashes cannot be
    made to collide by small corner numbers) and on two doubly linked lists, of the entries starting
    and of those ending at its corners, newest first: every operation takes constant time."""

    def __init__(self) -> None:
        self._top: dict[tuple[int, int], int] = {}
        self._start: list[int] = []
        self._end: list[int] = []
        self._below: list[int] = []
        # per entry: next and previous in its start corner's list (out) and its end corner's (in)
        self._links: list[list[int]] = []
        self._out: dict[int, int] = {}
        self._in: dict[int, int] = {}

    def _unlink(self, r: int) -> None:
        on, op, inn, inp = self._links[r]
        if op >= 0:
            self._links[op][0] = on
        else:
            self._out[self._start[r]] = on
        if on >= 0:
            self._links[on][1] = op
        if inp >= 0:
            self._links[inp][2] = inn
        else:
            self._in[self._end[r]] = inn
        if inn >= 0:
            self._links[inn][3] = inp

    def _edge(self, s: int, e: int) -> None:
        r = self._top.get((e, s), -1)
        if r >= 0:
            self._top[e, s] = self._below[r]
            self._unlink(r)
            return
        r = len(self._start)
        self._start.append(s)
        self._end.append(e)
        self._below.append(self._top.get((s, e), -1))
        self._top[s, e] = r
        on, inn = self._out.get(s, -1), self._in.get(e, -1)
        self._links.append([on, -1, inn, -1])
        if on >= 0:
            self._links[on][1] = r
        if inn >= 0:
            self._links[inn][3] = r
        self._out[s] = self._in[e] = r

    def triangle(self, a: int, b: int, c: int) -> None:
        for s, e in ((a, b), (b, c), (c, a)):
            self._edge(s, e)

    def left(self, i1: int, x: int) -> int:
        """The start of the newest open edge ending at ``i1`` (the second newest where that is ``x``)."""
        r = self._in.get(i1, -1)
        if r >= 0 and self._start[r] == x:
            r = self._links[r][2]
        return self._start[r] if r >= 0 else -1

    def right(self, i0: int, x: int) -> int:
        """The end of the newest open edge starting at ``i0`` (the second newest where that is ``x``)."""
        r = self._out.get(i0, -1)
        if r >= 0 and self._end[r] == x:
            r = self._links[r][0]
        return self._end[r] if r >= 0 else -1


def _codes(tri: np.ndarray, links: np.ndarray, v: int) -> np.ndarray:
    """Each attached triangle's corner code (0 new, 1 left, 2 right, 3 + zigzag(i2 - i1)); 0 for roots."""
    codes = np.zeros(len(links), dtype=np.int64)
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    links = np.ascontiguousarray(links, dtype=np.int64)
    if _walk_codes_c is not None:
        _walk_codes_c(tri.reshape(-1), links, v, codes, secrets.randbits(64))
        return codes
    edges, n = OpenEdges(), 0
    for j, (a, b, c) in enumerate(tri.tolist()):
        if links[j] == 0:
            n += sum(1 for x in (a, b, c) if x >= n)
        else:
            p, e = j - (int(links[j]) - 1) // 3 - 1, (int(links[j]) - 1) % 3
            x = int(tri[p, (e + 2) % 3])
            if c == n:
                n += 1
            elif edges.left(b, x) == c:
                codes[j] = 1
            elif edges.right(a, x) == c:
                codes[j] = 2
            else:
                codes[j] = 3 + int(varint.zigzag(np.array([c - b]))[0])
        edges.triangle(a, b, c)
    return codes


def _lut(lists: tuple[tuple[int, ...], ...]) -> np.ndarray:
    """Index of each list of ``lists`` by the key count * 64 + places (3 for none) in base 4."""
    lut = np.full(4 * 64, -1, dtype=np.int64)
    for i, lst in enumerate(lists):
        q = list(lst) + [3] * (3 - len(lst))
        lut[len(lst) * 64 + q[0] * 16 + q[1] * 4 + q[2]] = i
    return lut


_ROOT_LUT, _ATTACHED_LUT = _lut(ROOT_CHILDREN), _lut(ATTACHED_CHILDREN)


def _children(links: np.ndarray) -> np.ndarray:
    """Each triangle's list of children (its index in ROOT_CHILDREN for a root, in ATTACHED_CHILDREN
    otherwise), from the links of a depth-first walk: a parent's children in walk order."""
    t = len(links)
    root, parent, edge = _tree_parents(links)
    att = np.flatnonzero(~root)
    order = att[np.argsort(parent[att], kind="stable")]
    p = parent[order]
    rank = np.arange(len(order)) - np.searchsorted(p, p)
    places = np.full((t, 3), 3, dtype=np.int64)
    places[p, rank] = np.where(root[p], edge[order], edge[order] - 1)
    key = np.bincount(p, minlength=t) * 64 + places[:, 0] * 16 + places[:, 1] * 4 + places[:, 2]
    return np.where(root, _ROOT_LUT[key], _ATTACHED_LUT[key])


def _walk_python(symbols: np.ndarray, escapes: np.ndarray, v: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """:func:`_walk` without the C extension: (triangles, links, reason, triangle) as ``_chains.walk``."""
    t, x = len(symbols), len(escapes)
    tri = np.zeros((t, 3), dtype=np.int64)
    links = np.zeros(t, dtype=np.int64)
    sym, esc = symbols.tolist(), escapes.tolist()
    edges, stack, n, k = OpenEdges(), [], 0, 0
    rows = tri.tolist()
    for j in range(t):
        if not stack:
            if sym[j] >= len(ROOT_CHILDREN):
                return tri, links, 1, j
            if k + 3 > x:
                return tri, links, 2, j
            c = []
            for code in esc[k:k + 3]:
                if code == 0 and n >= v:
                    return tri, links, 8, j
                if code > n:
                    return tri, links, 3, j
                c.append(n if code == 0 else n - code)
                n += code == 0
            k += 3
            lists, first = ROOT_CHILDREN[sym[j]], 0
        else:
            p, e = stack.pop()
            if sym[j] >= 4 * len(ATTACHED_CHILDREN):
                return tri, links, 1, j
            q, code = rows[p], sym[j] % 4
            x_, c = q[(e + 2) % 3], [q[(e + 1) % 3], q[e], -1]
            if code == 3:
                if k >= x:
                    return tri, links, 2, j
                w = c[1] + int(varint.unzigzag(np.array([esc[k]], dtype=np.uint64))[0])
                k += 1
                if not 0 <= w < n:
                    return tri, links, 3, j
                c[2] = w
            elif code == 0:
                if n >= v:
                    return tri, links, 8, j
                c[2], n = n, n + 1
            else:
                c[2] = edges.left(c[1], x_) if code == 1 else edges.right(c[0], x_)
                if c[2] < 0:
                    return tri, links, 4, j
            links[j] = 3 * (j - p - 1) + e + 1
            lists, first = ATTACHED_CHILDREN[sym[j] // 4], 1
        if len(set(c)) < 3:
            return tri, links, 5, j
        rows[j] = c
        tri[j] = c
        edges.triangle(*c)
        stack.extend((j, place + first) for place in reversed(lists))
    reason = 6 if stack else 7 if k != x else 8 if n != v else 0
    return tri, links, reason, t


def _walk(symbols: np.ndarray, escapes: np.ndarray, v: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles (T, 3) and links (T,) of a walk's ``symbols`` and ``escapes`` over ``v`` corners,
    checked (``BAD_GROUP_STRUCTURE``), and :func:`code_stream`'s ``new``: which entries of the corner
    code stream name a corner anew (the C walk knows as it goes)."""
    t = len(symbols)
    if _walk_c is not None:
        tri = np.zeros(3 * t, dtype=np.int64)
        links = np.zeros(t, dtype=np.int64)
        fresh = np.zeros(3 * t, dtype=bool)
        reason, at = _walk_c(np.ascontiguousarray(symbols, dtype=np.uint64),
                             np.ascontiguousarray(escapes, dtype=np.uint64), v, tri, links, secrets.randbits(64),
                             fresh)
        tri = tri.reshape(-1, 3)
    else:
        tri, links, reason, at = _walk_python(symbols, escapes, v)
    if reason == 9:
        raise LimitError(f"shell walk: {t} triangles over {v} corners need more memory than there is",
                         code="MEMORY_LIMIT")
    if reason:
        raise FormatError(f"shell walk: triangle {at}: {_REASONS[reason]}", code="BAD_GROUP_STRUCTURE")
    if _walk_c is None:
        return tri, links, code_stream(tri, links == 0)[1]
    return tri, links, fresh[:t + 2 * int(np.count_nonzero(links == 0))]


def decode_shell_walk(raw: np.ndarray, bounding: np.ndarray, kind: GroupKind = GroupKind.SHELL_WALK,
                      major: int = 4, charge: Charge | None = None) -> Shell:
    """The corners and triangles of a ``kind`` body (a shell walk kind: SHELL_WALK, spec §9.13;
    SHELL_WALK_MULTI, §9.14; SHELL_WALK_REFLECT, §9.16; SHELL_WALK_LATER, §9.17), checked; ``charge``
    takes the declared counts before anything of their size is allocated (spec §12.4)."""
    (v, t, x), pos = varint.decode(raw, 3, "shell walk counts")
    v, t, x = int(v), int(t), int(x)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 2 and x <= left):
        raise FormatError(f"shell walk: {v} corners, {t} triangles, {x} escapes: outside the ranges the body "
                          f"allows", code="BAD_GROUP_STRUCTURE")
    if charge is not None:
        charge(vertices=v, triangles=t)
    symbols, used = varint.decode(raw[pos:], t, "shell walk symbols")
    pos += used
    escapes, used = varint.decode(raw[pos:], x, "shell walk escapes")
    pos += used
    faces, used = varint.decode(raw[pos:], t, "shell walk faces")
    pos += used
    explicit, pos = varint.bit_field(raw, pos, v, "shell walk: the body", "corner flags")
    tri, links, new = _walk(symbols, escapes, v)
    return tree_rest(raw, pos, bounding, tri, links, faces, explicit, new, None,
                     kind == GroupKind.SHELL_WALK_MULTI, major, kind == GroupKind.SHELL_WALK_REFLECT,
                     kind == GroupKind.SHELL_WALK_LATER)


def _coordinates(shell: Shell, tri: np.ndarray, links: np.ndarray, new: np.ndarray,
                 options: tuple[tuple[GroupKind, int], ...], decide: bool = True) -> tuple[GroupKind, dict[str, bytes]]:
    """The kind (a walk kind, :data:`WALK_KINDS`) and the mode, grid, tables and coordinates of a
    walk's explicit corners, in whichever of the ``(kind, mode)`` options compresses smallest
    (:func:`_smallest`)."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    values = np.zeros((len(explicit), 3), dtype=np.int64)
    values[explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    indices, tables = values, b""
    if any(m & MODE_TABLES for _, m in options):
        indices = values.copy()
        parts = []
        for axis in range(3):
            table, indices[explicit, axis] = np.unique(values[explicit, axis], return_inverse=True)
            parts += [varint.encode([len(table)]), varint.encode(varint.zigzag(table[:1])),
                      varint.encode(np.diff(table) - 1)]
        tables = b"".join(parts)
    per = np.where(links == 0, 3, 1)
    terms = {key: _tree_predictors(links, tri, explicit, per, new, *key)
             for key in {_terms_key(k, m) for k, m in options}}
    averaged = parallelograms(tri, explicit) if any(k == GroupKind.SHELL_WALK_MULTI for k, _ in options) else None
    grid = grid_bytes(shell, 4)
    fields = []
    for kind, m in options:
        v = indices if m & MODE_TABLES else values
        prediction = _predict(v, terms[_terms_key(kind, m)])
        if kind == GroupKind.SHELL_WALK_MULTI:
            prediction = predict_averaged(v, *averaged, prediction)
        elif kind == GroupKind.SHELL_WALK_REFLECT:
            prediction = predict_reflected(v, terms[_terms_key(kind, m)][:, 0], prediction)
        fields.append({"mode": bytes([m]), "grid": grid, "tables": tables if m & MODE_TABLES else b"",
                       "coordinates": varint.encode(varint.zigzag((v - prediction)[explicit].T))})
    best = _smallest(fields, decide)
    return options[fields.index(best)][0], best


def _terms_key(kind: GroupKind, mode: int) -> tuple[bool, bool]:
    """The arguments of ``_tree_predictors`` after ``new`` for a walk of ``kind`` in ``mode``: whether
    parallelograms predict (mode bit 0), whether steps are from the later gate corner (kind 13)."""
    return bool(mode & MODE_PARALLELOGRAM), kind == GroupKind.SHELL_WALK_LATER


#: Deflate level that ranks a walk's codings (kind and mode), and how many of the best (within what
#: ratio of the best) Brotli, the file's coder, then decides between: over the corpus at Draco-14's
#: error, deflate at level 1 picks codings 998 bytes worse than the smallest body (capsule.obj 552
#: bytes, quadknot.obj 342), level 6 464; Brotli deciding between the best two within 10 % 17, in
#: 0.09 s of ranking over the whole corpus (bench/walk_modes.py). Brotli decides at
#: quality 10, which ranks these parts as 11 does at 2.6 times the speed (quality 9 and below do not:
#: 5 and 9 took the wrong mode on quadknot.obj), and at 9 above RANK_DENSEST_BYTES: 10 on
#: bun_zipper.ply's 150 kB of coordinates took seconds of an encode that ranks several shells.
RANK_LEVEL, RANK_TOP, RANK_CLOSE = 6, 2, 1.10
RANK_DENSEST_BYTES = 64 * 1024


def _smallest(options: list[dict[str, bytes]], decide: bool = True) -> dict[str, bytes]:
    """Of candidate coordinate fields, the one whose body compresses smallest, as deflate ranks them,
    with Brotli (the writer's coder) deciding between the best ``RANK_TOP`` where deflate finds them
    within ``RANK_CLOSE`` of the best, if ``decide`` (else deflate's best: a size to compare codings by)."""
    if len(options) == 1:
        return options[0]
    sizes = [len(zlib.compress(f["tables"] + f["coordinates"], RANK_LEVEL)) for f in options]
    order = np.argsort(sizes, kind="stable")[:RANK_TOP]
    close = [options[i] for i in order if sizes[i] <= RANK_CLOSE * sizes[order[0]]]
    if len(close) == 1 or not decide:
        return close[0]
    return min(close, key=lambda f: _brotli_size(f["tables"] + f["coordinates"]))


#: Brotli sizes of the parts ranked lately, by digest: an encode ranks the walks of several candidate
#: shells (one per plane coding tried), whose explicit corners are often the same bytes.
_SIZES: Recent[int] = Recent(64)


#: The position of the kind among the options and the coordinate fields of the last few walks' explicit
#: corners, by the digest of what they are made of (:func:`_fields`).
_COORDINATES: Recent[tuple[int, dict[str, bytes]]] = Recent(16)


def forget() -> None:
    """Drop the bodies and sizes kept from earlier encodes."""
    _SIZES.clear()
    _BODIES.clear()
    _COORDINATES.clear()


def _brotli_size(part: bytes) -> int:
    return _SIZES.get(hashlib.blake2b(part, digest_size=16).digest(), lambda: len(
        brotli.compress(part, quality=10 if len(part) <= RANK_DENSEST_BYTES else 9)))


#: The shell walk kinds: kind 9 (spec §9.13), kind 10 (§9.14), kind 12 (§9.16) and kind 13 (§9.17), which
#: differ only in predictions. The encoder writes kinds 10, 12 and 13 without mode bit 0 only: the bit
#: decides their corners without parallelograms or turning chains alone (kind 13: without
#: parallelograms, where the later gate corner differs from i0), a few per mesh, and over the corpus at
#: 1e-6, 1e-4 and Draco-14's error no kind 10 group was smallest with it; its near copies of the
#: bit-0-clear bodies only crowded the ranking's best two (on quadknot.obj they pushed out the smallest
#: coding, 7 % smaller).
WALK_KINDS = (GroupKind.SHELL_WALK, GroupKind.SHELL_WALK_MULTI, GroupKind.SHELL_WALK_REFLECT,
              GroupKind.SHELL_WALK_LATER)


def codings(kinds: tuple[GroupKind, ...], mode: int | None = None) -> tuple[tuple[GroupKind, int], ...]:
    """The (kind, mode) pairs the encoder tries for a walk of one of ``kinds``: ``mode`` alone if given,
    else every mode of kind 9 and those of kinds 10, 12 and 13 without bit 0 (see :data:`WALK_KINDS`)."""
    return tuple((k, m) for k in kinds for m in (MODES if mode is None else (mode,))
                 if mode is not None or k == GroupKind.SHELL_WALK or not m & MODE_PARALLELOGRAM)


def _fields(shell: Shell, kinds: tuple[GroupKind, ...], mode: int | None = None,
            decide: bool = True) -> tuple[GroupKind, dict[str, bytes]]:
    common = surface_fields(shell)
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    tri, links = fc[:, 1:], np.asarray(shell.links, dtype=np.int64)
    root = links == 0
    stream, new, before = code_stream(tri, root)
    codes = _codes(tri, links, len(explicit))
    children = _children(links)
    symbols = np.where(root, children, 4 * children + np.minimum(codes, 3))
    # Escapes in triangle order: a root's three codes (spec §9.10's), an attached triangle's step.
    root_codes = np.where(new, 0, before - stream)[np.repeat(root, np.where(root, 3, 1))].reshape(-1, 3)
    count = np.where(root, 3, codes >= 3)
    escapes = np.zeros(int(count.sum()), dtype=np.int64)
    at = np.cumsum(count) - count
    escapes[(at[root, None] + np.arange(3)).reshape(-1)] = root_codes.reshape(-1)
    step = ~root & (codes >= 3)
    escapes[at[step]] = codes[step] - 3
    out = {"counts": varint.encode([len(explicit), len(links), len(escapes)]), "symbols": varint.encode(symbols),
           "escapes": varint.encode(escapes), "faces": common["faces"], "flags": common["flags"],
           "picks": common["picks"]}
    if not explicit.any():
        # Nothing to predict: the kinds' bodies are alike, and the first needs the lower version.
        return kinds[0], out
    options = codings(kinds, mode)
    # The coordinates depend on the corners and the walk only: the writer's copy of a shell, its references
    # renumbered or freed, has the same ones (chair_model.obj at 1e-4: every walk's were made twice so).
    h = hashlib.blake2b(repr(([(int(k), m) for k, m in options], decide, float(shell.step))).encode(), digest_size=16)
    for a in (explicit, np.asarray(shell.grid, dtype=np.int64), tri, links, np.asarray(shell.origin, dtype=np.float64)):
        h.update(np.ascontiguousarray(a).tobytes())
        h.update(b"|")

    def made() -> tuple[int, dict[str, bytes]]:
        kind, coordinates = _coordinates(shell, tri, links, new, options, decide)
        return [int(k) for k, _ in options].index(int(kind)), coordinates

    at, coordinates = _COORDINATES.get(h.digest(), made)
    return options[at][0], {**out, **coordinates}


def shell_walk_fields(shell: Shell, mode: int | None = None, kind: GroupKind = GroupKind.SHELL_WALK) -> dict[str, bytes]:
    """The fields of ``shell`` (a shell tree whose links are a depth-first walk, as
    ``groups.shells.spanning_walk`` makes them) as a ``kind`` body (a walk kind, :data:`WALK_KINDS`), by
    name in body order; its explicit corners in ``mode``, or in whichever
    of the modes the encoder tries compresses smallest."""
    return _fields(shell, (kind,), mode)[1]


def shell_kind_data(kind: GroupKind, shell: Shell, decide: bool = True, major: int = 4) -> bytes:
    """The kind data of a SHELL (spec §9.10), SHELL_TREE (§9.11), SHELL_TREE_PARALLELOGRAM (§9.12),
    SHELL_WALK (§9.13), SHELL_WALK_MULTI (§9.14) or SHELL_WALK_REFLECT (§9.16) group in a version ``major``
    file (``decide``:
    :func:`shell_walk_body`'s)."""
    if kind == GroupKind.SHELL:
        return _shell_body(shell, major)
    if kind in WALK_KINDS:
        return shell_walk_body(shell, kind, decide, major)
    return _shell_tree_body(shell, kind == GroupKind.SHELL_TREE_PARALLELOGRAM, major)


#: The last few bodies made, by the digest of the shell they were made of and by kind and whether
#: Brotli decided the mode, with the kind :func:`shell_walk_choice` chose: an encode sizes, writes and
#: verifies one shell several times, and the writer's copy of a shell (its references renumbered in
#: the same order, or none) is another object with the same arrays (DamagedHelmet.glb at 1e-4: 4 of
#: 16 walks were made again so).
_BODIES: Recent[dict] = Recent(8)


def _digest(shell: Shell) -> bytes:
    h = hashlib.blake2b(digest_size=16)
    for a in (shell.explicit, shell.vertex_planes, shell.grid, shell.facets, shell.links, shell.origin):
        a = np.ascontiguousarray(np.asarray(a if a is not None else ()))
        h.update(repr((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    h.update(np.float64(shell.step).tobytes())
    return h.digest()


def _held(shell: Shell) -> dict:
    return _BODIES.get(_digest(shell), dict)


def shell_walk_choice(shell: Shell, kinds: tuple[GroupKind, ...] = WALK_KINDS) -> tuple[GroupKind, bytes]:
    """Whichever of ``kinds`` (shell walk kinds) codes ``shell`` smallest, and its kind data (as a
    version 4 file holds it). Shells are frozen and their arrays never written to, so a body made once
    for a shell object is its body."""
    bodies = _held(shell)
    if kinds not in bodies:
        kind, fields = _fields(shell, kinds)
        bodies[kinds] = kind
        bodies[kind, True] = fields
    return bodies[kinds], _joined(shell, bodies[bodies[kinds], True], 4)


def shell_walk_body(shell: Shell, kind: GroupKind = GroupKind.SHELL_WALK, decide: bool = True,
                    major: int = 4) -> bytes:
    """The kind data of ``shell`` as a ``kind`` group (a walk kind: SHELL_WALK, spec §9.13; SHELL_WALK_MULTI,
    §9.14; SHELL_WALK_REFLECT, §9.16) in a version ``major`` file, its coordinates in the mode that compresses smallest (``decide``
    False: as deflate ranks them, for a size to compare codings by; :func:`shell_walk_choice` decides
    again)."""
    bodies = _held(shell)
    if (kind, True) in bodies:
        return _joined(shell, bodies[kind, True], major)
    if (kind, decide) not in bodies:
        bodies[kind, decide] = _fields(shell, (kind,), decide=decide)[1]
    return _joined(shell, bodies[kind, decide], major)


def _joined(shell: Shell, fields: dict[str, bytes], major: int) -> bytes:
    """A walk body's ``fields`` joined, its grid (made for version 4) as a version ``major`` file
    stores it: the coding chosen does not depend on the grid's width, so one choice serves both."""
    if major >= 5 and "grid" in fields:
        fields = {**fields, "grid": grid_bytes(shell, major)}
    return b"".join(fields.values())


def check_shell_walk(shell: Shell, bounding: np.ndarray, kind: GroupKind = GroupKind.SHELL_WALK) -> None:
    """``FormatError`` (``BAD_GROUP_STRUCTURE``) unless ``shell``'s body as a ``kind`` group (a shell
    walk kind) decodes to it."""
    if shell.links is None or len(shell.links) != len(shell.facets):
        raise FormatError("shell walk: one link per triangle", code="BAD_GROUP_STRUCTURE")
    back = decode_shell_walk(np.frombuffer(shell_walk_body(shell, kind), dtype=np.uint8), np.asarray(bounding, bool),
                             kind)
    if not same_tree(back, shell):
        raise FormatError("shell walk: its body does not decode to it (links not a depth-first walk, corners "
                          "not numbered by first use, or named corners not three of their face planes in "
                          "ascending order)", code="BAD_GROUP_STRUCTURE")
