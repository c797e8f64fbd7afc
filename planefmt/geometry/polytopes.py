"""Many small convex polytopes from their half-spaces at once (decoding cells and patches).

Each polytope is ``{x : omega_i . x <= h_i}`` over its own rows of one
concatenated half-space list (outward unit normals ``omega``, ``h`` in model
units). Solids decode into thousands of cells and open surfaces into
thousands of patches, each of a dozen planes or so; one Qhull call per
polytope (:mod:`planefmt.geometry.halfspace`) costs about a millisecond of overhead,
so small polytopes are computed here in numpy batches instead:

* Vertices. Every triple of a polytope's planes (plus four far planes of a
  tetrahedron, which bound every polytope; a vertex on them means the polytope is
  unbounded) is solved as a 3x3 system; solutions inside all half-spaces
  (within ``tol``) are vertices. A vertex is identified by the set of planes
  it is tight on (``|omega . x - h| <= tol``), as a bit mask, so the triples
  of a degenerate vertex (four or more planes through a point, as at every
  corner of a cube cut by a diagonal plane) give one vertex. Vertices of one
  polytope closer than ``tol`` are merged as well, with their masks united.
* Faces. The vertices tight on a plane, ordered by angle in the right-handed
  basis ``(e1, e2, omega)``: counter-clockwise seen from outside. Planes with
  fewer than three vertices or no area bound no face.

Polytopes with more than :data:`SMALL` planes go to Qhull
(:func:`planefmt.geometry.halfspace.intersect`), whose cost grows as ``n log n``.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import GeometryError
from .halfspace import intersect
from .planes import in_plane_basis

#: Polytopes with at most this many planes are computed by triple enumeration.
SMALL = 14

#: Status of a polytope.
OK, EMPTY, UNBOUNDED = 0, 1, 2

#: Far planes that close every polytope (a regular tetrahedron's normals): a vertex on one of
#: them means the polytope is unbounded. Their distance is _FAR times the largest |h|.
_BOX = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3.0)
_FAR = 1e8
_TABLES: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _tables(k: int, nb: int) -> tuple[np.ndarray, np.ndarray]:
    """Triples of plane indices (not all far planes) and the index of each pair in ``triu_indices``."""
    if k not in _TABLES:
        n = k + nb
        trip = np.array(list(combinations(range(n), 3)), dtype=np.int64)
        pair_of = np.zeros((n, n), dtype=np.int64)
        pa, pb = np.triu_indices(n, 1)
        pair_of[pa, pb] = np.arange(len(pa))
        _TABLES[k] = (trip[trip[:, 0] < k], pair_of)
    return _TABLES[k]


@dataclass(frozen=True)
class Polytopes:
    """Faces of many convex polytopes.

    ``vertices`` (V, 3) model units; faces are ``polygon_vertices[o[i]:o[i+1]]``
    with ``o = polygon_offsets``, counter-clockwise seen from outside, on the
    half-space row ``polygon_row`` (an index into the input rows) of polytope
    ``polygon_owner``. ``status`` (P,) is :data:`OK`, :data:`EMPTY` (no
    interior) or :data:`UNBOUNDED`; such polytopes have no faces.
    """

    vertices: np.ndarray
    polygon_offsets: np.ndarray
    polygon_vertices: np.ndarray
    polygon_row: np.ndarray
    polygon_owner: np.ndarray
    status: np.ndarray

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Fan triangles of the faces ``(T, 3)`` and the face each came from ``(T,)``."""
        size = np.diff(self.polygon_offsets)
        per = np.maximum(size - 2, 0)
        poly = np.repeat(np.arange(len(size)), per)
        local = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per) + 1
        base = self.polygon_offsets[:-1][poly]
        pv = self.polygon_vertices
        return np.column_stack([pv[base], pv[base + local], pv[base + local + 1]]), poly


def intersect_many(omega: np.ndarray, h: np.ndarray, owner: np.ndarray, count: int,
                   tol: float | np.ndarray) -> Polytopes:
    """The polytopes ``{x : omega_i . x <= h_i for owner_i == p}``, ``p < count``.

    ``omega`` (n, 3) unit normals, ``h`` (n,), ``owner`` (n,) sorted.
    ``tol`` (model units, one for all or one per polytope) is the distance
    within which a point counts as on a plane; it must exceed rounding (about
    ``1e-15`` of the coordinates) and stay below any feature size. A polytope
    with less than about ``tol`` of thickness is reported :data:`EMPTY`. Each
    polytope's result depends on its own planes and tolerance only, not on
    the others computed with it.
    """
    omega = np.asarray(omega, dtype=np.float64).reshape(-1, 3)
    h = np.asarray(h, dtype=np.float64).reshape(-1)
    owner = np.asarray(owner, dtype=np.int64)
    tol = np.broadcast_to(np.asarray(tol, dtype=np.float64), (count,))
    start = np.searchsorted(owner, np.arange(count + 1))
    size = np.diff(start)
    status = np.full(count, OK, dtype=np.int8)
    parts: list[_Faces] = []
    reach = np.zeros(count)
    np.maximum.at(reach, owner, np.abs(h))
    scale = _FAR * (reach + tol)  # per polytope: the far planes of one do not depend on the others
    for k in np.unique(size):
        ids = np.flatnonzero(size == k)
        if k < 4:
            status[ids] = UNBOUNDED
        elif k <= SMALL:
            for chunk in np.array_split(ids, max(1, len(ids) * _triples(int(k)) // _BATCH)):
                parts.append(_enumerate(omega, h, start[chunk], int(k), chunk, tol, scale, status))
        else:
            parts.extend(_qhull(omega, h, int(start[p]), int(k), int(p), status) for p in ids)
    return _assemble(parts, status)


#: Triple systems solved per numpy batch (bounds temporary memory).
_BATCH = 1 << 18


def _triples(k: int) -> int:
    n = k + len(_BOX)
    return n * (n - 1) * (n - 2) // 6


@dataclass(frozen=True)
class _Faces:
    """Faces of some polytopes with their own vertex array (see :class:`Polytopes`)."""

    vertices: np.ndarray
    offsets: np.ndarray
    polygon_vertices: np.ndarray
    row: np.ndarray
    owner: np.ndarray


def _enumerate(omega: np.ndarray, h: np.ndarray, first: np.ndarray, k: int, ids: np.ndarray,
               tol: np.ndarray, scale: np.ndarray, status: np.ndarray) -> _Faces:
    """Faces of ``len(ids)`` polytopes of ``k`` planes each, by triple enumeration (``tol`` and
    ``scale`` per polytope of the whole batch, indexed by ``ids``)."""
    n = len(ids)
    rows = first[:, None] + np.arange(k)
    nb = len(_BOX)
    w = np.concatenate([omega[rows], np.broadcast_to(_BOX, (n, nb, 3))], axis=1)
    hh = np.concatenate([h[rows], np.repeat(scale[ids][:, None], nb, axis=1)], axis=1)
    tol_p = tol[ids]
    trip, pair_of = _tables(k, nb)
    # Cramer's rule, elementwise: x = (b1 n2 x n3 + b2 n3 x n1 + b3 n1 x n2) / n1 . (n2 x n3), with
    # the cross products computed once per pair of planes.
    pa, pb = np.triu_indices(k + nb, 1)
    cross = np.cross(w[:, pa], w[:, pb])  # (n, pairs, 3)
    t0, t1, t2 = trip[:, 0], trip[:, 1], trip[:, 2]
    c23 = cross[:, pair_of[t1, t2]]
    c31 = -cross[:, pair_of[t0, t2]]
    c12 = cross[:, pair_of[t0, t1]]
    det = np.einsum("ntj,ntj->nt", w[:, t0], c23)
    ok = np.abs(det) > 1e-12
    inv = 1.0 / np.where(ok, det, 1.0)[:, :, None]

    def solve(b0: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
        return (b0[:, :, None] * c23 + b1[:, :, None] * c31 + b2[:, :, None] * c12) * inv

    x = solve(hh[:, t0], hh[:, t1], hh[:, t2])
    # Cramer's rule loses digits as the determinant shrinks: where three nearly parallel planes
    # meet (RoughnessTest.usdz: |det| 1.7e-9) the point misses its own planes by 1e-8, more than
    # tol, and was on no face. One step of refinement on the triple's own residuals puts it back.
    own = [np.einsum("ntj,ntj->nt", x, w[:, t]) - hh[:, t] for t in (t0, t1, t2)]
    x = x - solve(*own)
    res = np.matmul(x, w.transpose(0, 2, 1)) - hh[:, None, :]  # (n, t, k + nb)
    # A feasible vertex on a far plane means the polytope does not end in that direction; such
    # vertices are far out, so their feasibility allows for rounding at their distance.
    far = t2 >= k
    slack = np.where(far, tol_p[:, None] + 1e-12 * np.abs(x).max(axis=2), tol_p[:, None])
    feasible = ok & (res <= slack[:, :, None]).all(axis=2)
    status[ids[np.unique(np.nonzero(feasible & far)[0])]] = UNBOUNDED
    pi, ti = np.nonzero(feasible & ~far)
    x, res = x[pi, ti], res[pi, ti]
    tight = np.abs(res) <= tol_p[pi][:, None]
    keep = status[ids[pi]] == OK
    pi, x, tight = pi[keep], x[keep], tight[keep, :k]
    mask = (tight.astype(np.int64) << np.arange(k, dtype=np.int64)).sum(axis=1)
    pi, x, mask = _merge(pi, x, mask, tol_p)
    # Incidences (vertex, local plane) from the masks, grouped into faces.
    vi, j = np.nonzero((mask[:, None] >> np.arange(k)) & 1)
    return _faces(omega, x, vi, pi[vi] * k + j, ids[pi[vi]], rows[pi[vi], j], tol, status, ids)


def _merge(owner: np.ndarray, x: np.ndarray, mask: np.ndarray,
           tol: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One vertex per tight-plane set per polytope; vertices of one polytope within its ``tol[owner]``
    join too."""
    if len(x) == 0:
        return owner, x, mask
    _, label = np.unique(np.column_stack([owner, mask]), axis=0, return_inverse=True)
    label = label.reshape(-1)
    pairs = cKDTree(x).query_pairs(float(tol[owner].max()), output_type="ndarray")
    if len(pairs):
        a, b = pairs[:, 0], pairs[:, 1]
        # query_pairs counts pairs within r inclusively: the same test per pair, with its own tol.
        pairs = pairs[(owner[a] == owner[b]) & (np.linalg.norm(x[a] - x[b], axis=1) <= tol[owner[a]])]
    if len(pairs):
        n = int(label.max()) + 1
        g = coo_matrix((np.ones(len(pairs)), (label[pairs[:, 0]], label[pairs[:, 1]])), shape=(n, n))
        label = connected_components(g, directed=False)[1][label]
    m = int(label.max()) + 1
    count = np.bincount(label, minlength=m).astype(np.float64)
    pos = np.column_stack([np.bincount(label, weights=x[:, i], minlength=m) for i in range(3)])
    merged = np.zeros(m, dtype=np.int64)
    np.bitwise_or.at(merged, label, mask)
    own = np.zeros(m, dtype=np.int64)
    own[label] = owner
    return own, pos / count[:, None], merged


def _faces(omega: np.ndarray, x: np.ndarray, vi: np.ndarray, key: np.ndarray, owner: np.ndarray,
           row: np.ndarray, tol: np.ndarray, status: np.ndarray, ids: np.ndarray) -> _Faces:
    """Polygons from incidences: vertex ``vi`` lies on face ``key`` (plane ``row`` of polytope ``owner``).

    Vertices are ordered by angle in the basis ``(e1, e2, omega)``; faces with
    fewer than three vertices or an extent below ``tol`` are dropped, and a
    polytope left with fewer than four faces has no interior (:data:`EMPTY`).
    """
    order = np.argsort(key, kind="stable")
    vi, key, owner, row = vi[order], key[order], owner[order], row[order]
    _, first, cnt = np.unique(key, return_index=True, return_counts=True)
    face = np.repeat(np.arange(len(first)), cnt)
    centre = np.column_stack([np.bincount(face, weights=x[vi, c]) for c in range(3)]) / cnt[:, None]
    row_first, owner_first = row[first], owner[first]
    e1, e2 = in_plane_basis(omega[row_first])
    d = x[vi] - centre[face]
    angle = np.arctan2(np.einsum("ij,ij->i", d, e2[face]), np.einsum("ij,ij->i", d, e1[face]))
    order = np.lexsort((angle, face))
    vi, d = vi[order], d[order]
    face_tol = tol[owner_first]
    vi, d, face, cnt = _strictly_convex(vi, d, face, cnt, omega[row[first]], face_tol)
    first = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    nxt = np.arange(len(vi)) + 1
    nxt[first + cnt - 1] = first
    area2 = np.bincount(face, weights=np.einsum("ij,ij->i", np.cross(d, d[nxt]), omega[row_first][face]),
                        minlength=len(cnt))
    good = (cnt >= 3) & (area2 > face_tol * np.sqrt(np.maximum(area2, 0.0)))
    face_owner = owner_first
    faces_per = np.bincount(face_owner[good], minlength=len(status))
    flat = ids[faces_per[ids] < 4]
    status[flat[status[flat] == OK]] = EMPTY
    good &= status[face_owner] == OK
    sel = good[face]
    return _Faces(vertices=x, offsets=np.concatenate([[0], np.cumsum(cnt[good])]),
                  polygon_vertices=vi[sel], row=row_first[good], owner=face_owner[good])


def _strictly_convex(vi: np.ndarray, d: np.ndarray, face: np.ndarray, cnt: np.ndarray, normal: np.ndarray,
                     tol: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Drop ring corners that do not turn left by more than ``tol`` (rounding reflexes, collinear points).

    Rings are grouped by ``face`` (sorted), ``d`` their corners relative to the
    face centre, ``normal`` (faces, 3). A corner ``b`` between ``a`` and ``c``
    stays if ``c`` lies more than ``tol`` to the left of the line ``a -> b``.
    Removal repeats until every ring is strictly convex.
    """
    while len(cnt):
        first = np.concatenate([[0], np.cumsum(cnt)[:-1]])
        idx = np.arange(len(vi))
        nxt, prv = idx + 1, idx - 1
        nxt[first + cnt - 1] = first
        prv[first] = first + cnt - 1
        e_in = d - d[prv]
        e_out = d[nxt] - d
        turn = np.einsum("ij,ij->i", np.cross(e_in, e_out), normal[face])
        length = np.linalg.norm(e_in, axis=1)
        drop = (turn <= tol[face] * length) & (cnt[face] > 3)
        if not drop.any():
            return vi, d, face, cnt
        # Never drop two neighbours in one round: their removal conditions interact.
        drop &= ~drop[prv] | (np.arange(len(vi)) == first[face])
        keep = ~drop
        vi, d, face = vi[keep], d[keep], face[keep]
        cnt = np.bincount(face, minlength=len(cnt))
    return vi, d, face, cnt


def _qhull(omega: np.ndarray, h: np.ndarray, first: int, k: int, p: int, status: np.ndarray) -> _Faces:
    """One large polytope through Qhull."""
    try:
        poly = intersect(omega[first:first + k], h[first:first + k])
    except GeometryError as err:
        status[p] = UNBOUNDED if err.code == "UNBOUNDED_POLYTOPE" else EMPTY
        return _Faces(np.empty((0, 3)), np.zeros(1, dtype=np.int64), np.empty(0, dtype=np.int64),
                      np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64))
    return _Faces(vertices=poly.vertices, offsets=poly.polygon_offsets,
                  polygon_vertices=poly.polygon_vertices, row=poly.polygon_plane + first,
                  owner=np.full(len(poly.polygon_plane), p, dtype=np.int64))


def _assemble(parts: list[_Faces], status: np.ndarray) -> Polytopes:
    """One :class:`Polytopes` from the parts, faces of non-OK polytopes dropped."""
    verts, pv, offs, rows, owners = [], [], [np.zeros(1, dtype=np.int64)], [], []
    base = 0
    top = 0
    for part in parts:
        keep = status[part.owner] == OK
        sizes = np.diff(part.offsets)[keep]
        sel = np.repeat(keep, np.diff(part.offsets))
        verts.append(part.vertices)
        pv.append(part.polygon_vertices[sel] + base)
        offs.append(top + np.cumsum(sizes))
        rows.append(part.row[keep])
        owners.append(part.owner[keep])
        base += len(part.vertices)
        top += int(sizes.sum())
    empty_i = np.empty(0, dtype=np.int64)
    return Polytopes(vertices=np.concatenate(verts) if verts else np.empty((0, 3)),
                     polygon_offsets=np.concatenate(offs).astype(np.int64),
                     polygon_vertices=np.concatenate(pv).astype(np.int64) if pv else empty_i,
                     polygon_row=np.concatenate(rows).astype(np.int64) if rows else empty_i,
                     polygon_owner=np.concatenate(owners).astype(np.int64) if owners else empty_i,
                     status=status)
