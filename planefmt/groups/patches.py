"""Open, non-manifold and soup surfaces as pseudo-convex and pseudo-concave patches (paper, algorithm 2).

A set of triangles is *pseudo-convex* when every two of them are positively
oriented: each lies in the inner half-space ``omega . x <= h`` of the other's
plane (the paper's definition, tested exactly on the vertices, within a
tolerance ``tol`` relative to the diagonal plus the fitting drift of the two
planes); *pseudo-concave* when every two are negatively oriented. A
pseudo-convex patch lies on the boundary of the convex polytope of its face
planes; *bounding planes* through its border edges cut that polytope down so
that its faces on the face planes are exactly the patch's polygons (spec
§9.8). A pseudo-concave patch is stored with every plane inverted, which
makes it pseudo-convex; the decoder flips its faces back.

What the encoder needs for the decoded faces to be the source polygons:

* each face plane carries one convex polygon of the patch (the face of a
  convex polytope on a plane is one convex polygon), so a triangle joins a
  patch only if the union on its plane stays convex (2D hull area test);
* every border edge lies on some plane of the group that keeps all of the
  patch's vertices inside and cuts the face (is not nearly parallel to it).

Bounding planes, in order of preference: the face plane of the triangle
across the edge, as it is (no new plane at all: the neighbour is positively
oriented there) or inverted; a plane already chosen for this patch or for
the neighbouring patch across the same edge; a new plane through the edge,
tilted (about the edge, in the plane spanned by the face's outward in-plane
normal ``o`` and normal ``omega``) to the middle of the range that keeps the
vertices of both patches inside, so that both can use it; failing that, of
this patch alone, tilted down by 45 degrees where possible (so that small
patches close into a bounded polytope without a closing plane).

The encoder then decodes every patch (:mod:`planefmt.geometry.polytopes`) and
compares each decoded face with its source triangles by exact point-triangle
distances (:mod:`planefmt.geometry.trianglegeom`): the distance of a decoded vertex to
the source polygon, and of a source vertex to the decoded face (convex, so
its maximum over a source triangle is at a vertex), plus twice the plane's
fitting drift. A patch that misses its bound, has no face on a face plane or
is unbounded is split in two, down to single triangles.

Conventions: planes ``(omega, h)`` outward unit normals, inside where
``omega . x <= h``; lengths in model units; triangles counter-clockwise seen
from outside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ..errors import GeometryError, LimitError
from ..geometry.planetable import PlaneTable
from ..geometry.polygonize import edge_adjacency
from ..geometry.polytopes import OK, intersect_many
from ..geometry.trianglegeom import point_triangle_distance

#: Pairwise orientation tolerance, as a fraction of the diagonal (plus the planes' fitting drift).
ORIENTATION_TOLERANCE = 1e-9
#: A bounding plane must make at least this angle (radians) with the faces it cuts: a plane at
#: angle a moves the cut edge by (plane errors) / sin a. Where the planes are exact (drift 0),
#: shallow cuts are as good as steep ones; MIN_CUT_SINE_DRIFT raises the bound with the drift.
MIN_CUT_ANGLE = math.radians(0.5)
MIN_CUT_SINE_DRIFT = 8.0
#: Largest tilt (radians) of a bounding plane under its face: closes small patches.
DOWN_TILT = math.radians(45.0)


@dataclass(frozen=True)
class Patch:
    """One encoded patch: ``kind`` 3 (pseudo-convex) or 4 (pseudo-concave), its triangles,
    ``refs`` into the :class:`PlaneTable` (as stored: inverted for kind 4) and ``bounding``
    (True for bounding planes, False for face planes)."""

    kind: int
    triangles: np.ndarray
    refs: np.ndarray
    bounding: np.ndarray


@dataclass(frozen=True)
class PatchReport:
    """What :func:`encode_patches` did: patches by kind, splits, verified error (model units), and
    how border edges got their planes (``reused`` an existing plane, a new plane ``shared`` by
    the two patches at the edge, or the patch's ``own``; ``closing`` planes added)."""

    convex: int
    concave: int
    splits: int
    error: float
    planes: dict


def encode_patches(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, drift: np.ndarray,
                   table: PlaneTable, target: float) -> tuple[list[Patch], PatchReport]:
    """Patches covering every triangle of ``faces`` that lies on a plane (``face_plane >= 0``).

    ``vertices`` (n, 3), ``faces`` (m, 3); ``face_plane`` (m,) indexes
    ``table``'s input planes, ``drift`` (k,) each plane's largest vertex
    distance (model units). ``target`` (model units) is the error each patch
    must meet. Raises ``GeometryError`` (``TOLERANCE_NOT_MET``) if even a
    single triangle cannot.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    live = np.flatnonzero(face_plane >= 0)
    diag = float(np.linalg.norm(np.ptp(v[f[live]].reshape(-1, 3), axis=0))) if len(live) else 0.0
    geo = _Geometry(v, f, face_plane, table, drift, ORIENTATION_TOLERANCE * diag)
    geo.target = target
    label = np.full(len(f), -1, dtype=np.int64)
    sign = np.zeros(0, dtype=np.int64)
    # The paper's passes, pseudo-concave first: a pocket's walls are positively oriented with the
    # faces around its rim too, and a pseudo-convex pass would take them apart. Concave patches
    # must bend (hold a concave edge); singletons and flat pieces are released for the next pass;
    # what is left becomes single pseudo-convex triangles.
    for s, keep_single in ((-1, False), (1, False), (1, True)):
        label, sign = geo.grow(live, label, sign, s, keep_single)
    # Work items: (triangles, orientation, level). Level 0 builds the group as the module docstring
    # says; 1 with bounding planes as perpendicular to the faces as the patch allows and shared with
    # no one (where a plane strays from its polygon's vertices, tilted cuts multiply the error);
    # 2, for a single triangle, on the triangle's own plane.
    todo = [(np.flatnonzero(label == p), int(s), 0) for p, s in enumerate(sign)]
    done: list[Patch] = []
    splits = 0
    error = 0.0
    while todo:
        built = [geo.bounding(tris, s, level) for tris, s, level in todo]
        ok = [i for i, b in enumerate(built) if b is not None]
        errs = np.full(len(todo), np.inf)
        if ok:
            errs[ok] = geo.verify([built[i] for i in ok])
        # A patch whose planes do not close (often: the face planes of its neighbours) gets a
        # closing plane under it, or failing that a far tetrahedron, before anything else.
        for stage in (1, 4):
            again = [i for i in ok if not np.isfinite(errs[i])]
            if not again:
                break
            closed = [geo.close(built[i], stage) for i in again]
            for i, c, e in zip(again, closed, geo.verify(closed)):
                built[i], errs[i] = c, e
        nxt = []
        for (tris, s, level), patch, err in zip(todo, built, errs):
            if err <= target:
                done.append(patch)
                error = max(error, float(err))
            elif level == 0 or (level == 1 and len(tris) == 1):
                nxt.append((tris, s, level + 1))
            elif len(tris) == 1:
                raise GeometryError(f"a single triangle decodes {err:.3g} from its source (or has no "
                                    f"bounded polytope), above the target {target:.3g}",
                                    code="TOLERANCE_NOT_MET")
            else:
                splits += 1
                nxt += [(half, s, 0) for half in geo.halves(tris)]
        todo = nxt
    convex = sum(p.kind == 3 for p in done)
    return done, PatchReport(convex=convex, concave=len(done) - convex, splits=splits, error=error,
                             planes=dict(geo.stats))


class _Geometry:
    """Triangles, planes and adjacency of one body, and the patch operations on them."""

    def __init__(self, v: np.ndarray, f: np.ndarray, face_plane: np.ndarray, table: PlaneTable,
                 drift: np.ndarray, tol: float) -> None:
        self.v, self.f, self.fp, self.table, self.tol = v, f, face_plane, table, tol
        self.drift = drift
        self.omega, self.h = table.arrays()
        p = v[f]
        self.area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        edges = edge_adjacency(f, len(v))
        ta, tb = edges.a // 3, edges.b // 3
        # Rows (triangle, neighbour, side in triangle, side in neighbour) for both directions.
        pairs = np.concatenate([np.column_stack([ta, tb, edges.a % 3, edges.b % 3]),
                                np.column_stack([tb, ta, edges.b % 3, edges.a % 3])])
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]
        order = np.argsort(pairs[:, 0], kind="stable")
        pairs = pairs[order]
        self.nbr = pairs[:, 1]
        self.nbr_ptr = np.searchsorted(pairs[:, 0], np.arange(len(f) + 1))
        # Edge type seen from each side: +1 convex (the neighbour's far corner below this face's
        # plane), -1 concave, 0 flat or degenerate. Patches grow only across edges of their kind
        # or flat ones: the paper's separation of convex and concave surface elements.
        t1, t2 = pairs[:, 0], pairs[:, 1]
        shared = f[t2]
        far = np.where((shared != f[t1, pairs[:, 2], None]) & (shared != f[t1, (pairs[:, 2] + 1) % 3, None]))
        far_vertex = np.full(len(pairs), -1, dtype=np.int64)
        far_vertex[far[0]] = shared[far]
        p1 = face_plane[t1]
        ok = (p1 >= 0) & (far_vertex >= 0)
        d = np.zeros(len(pairs))
        d[ok] = np.einsum("ij,ij->i", self.omega[p1[ok]], v[far_vertex[ok]]) - self.h[p1[ok]]
        slack = tol + drift[np.maximum(p1, 0)] + drift[np.maximum(face_plane[t2], 0)]
        self.nbr_type = np.where(d < -slack, 1, np.where(d > slack, -1, 0))
        # The triangles across each side (a list where the edge is non-manifold).
        self.across: dict[tuple[int, int], list[int]] = {}
        for t1_, t2_, k1 in zip(t1.tolist(), t2.tolist(), pairs[:, 2].tolist()):
            self.across.setdefault((t1_, k1), []).append(t2_)
        self._tri_hull: dict[int, tuple] = {}
        self.bplanes: dict[tuple[int, int], list[int]] = {}
        self.target = 1.0
        self.stats = {"reused": 0, "shared": 0, "own": 0, "closing": 0}

    # -- growth ---------------------------------------------------------------------------

    def grow(self, live: np.ndarray, label: np.ndarray, sign: np.ndarray, s: int,
             keep_single: bool) -> tuple[np.ndarray, np.ndarray]:
        """Grow patches of orientation ``s`` from every unassigned triangle over its neighbours."""
        signs = list(sign)
        for seed in live:
            if label[seed] >= 0:
                continue
            members = self._grow_one(seed, label, s)
            if len(members) == 1 and not keep_single:
                continue
            if s < 0 and not self._bends(members, s):
                # Flat pieces are as pseudo-convex as pseudo-concave: left to the convex pass.
                continue
            label[members] = len(signs)
            signs.append(s)
        return label, np.asarray(signs, dtype=np.int64)

    def _grow_one(self, seed: int, label: np.ndarray, s: int) -> list[int]:
        v, f, fp = self.v, self.f, self.fp
        members = [seed]
        p0 = int(fp[seed])
        planes = {p0: [seed]}
        hulls: dict[int, tuple | None] = {}
        pl = [p0]
        verts = set(f[seed].tolist())
        tried = {seed}
        queue = self._across(seed, s, set())
        while queue:
            t = queue.pop()
            if t in tried or label[t] >= 0 or fp[t] < 0:
                continue
            tried.add(t)
            p = int(fp[t])
            w = s * self.omega[pl]
            hh = s * self.h[pl]
            slack = self.tol + self.drift[pl] + self.drift[p]
            if ((w @ v[f[t]].T - hh[:, None]) > slack[:, None]).any():
                continue
            xs = v[np.fromiter(verts, dtype=np.int64)]
            d_new = s * (xs @ self.omega[p] - self.h[p])
            slack_new = self.tol + self.drift[p] + self.drift[pl].max()
            if (d_new > slack_new).any():
                continue
            hull = self._hull(planes[p] + [t], p) if p in planes else None
            if p in planes and hull is None:
                continue
            members.append(t)
            planes.setdefault(p, []).append(t)
            hulls[p] = hull
            if len(planes[p]) == 1:
                pl.append(p)
            verts.update(f[t].tolist())
            queue.extend(self._across(t, s, tried))
        # A patch vertex on a face plane must lie in that plane's polygon, or the polytope's face there
        # reaches out to it and no bounding plane can cut it back. (Checked at the end: while the
        # patch grows, a polygon may still miss the triangles that will cover such a vertex.) The
        # last triangles added go until it holds.
        for q, tq in planes.items():
            if hulls.get(q) is None:
                hulls[q] = self._hull(tq, q)
        while len(members) > 1 and not self._complete(members, hulls, s):
            t = members.pop()
            q = int(fp[t])
            planes[q].remove(t)
            hulls[q] = self._hull(planes[q], q) if planes[q] else None
        return members

    def _complete(self, members: list[int], hulls: dict, s: int) -> bool:
        """Whether every vertex of the patch lying on one of its face planes lies in that plane's polygon."""
        xs = self.v[np.unique(self.f[members])]
        for q, hull in hulls.items():
            if hull is None:
                continue
            d = s * (xs @ self.omega[q] - self.h[q])
            if not _inside(hull, xs[d > -(self.tol + self.drift[q])]):
                return False
        return True

    def _hull(self, tris: list[int], p: int) -> tuple[np.ndarray, np.ndarray, float] | None:
        """The polygon of triangles ``tris`` on plane ``p`` as ``(e1e2 (2, 3), equations (k, 3), tol)``:
        2D half-planes ``a u + b v + c <= 0``; None unless the triangles form one convex polygon
        (their 2D hull has their area)."""
        if len(tris) == 1 and tris[0] in self._tri_hull:
            return self._tri_hull[tris[0]]
        pts = self.v[self.f[tris]].reshape(-1, 3)
        e = np.stack(_basis(self.omega[p]))
        uv = pts @ e.T
        slack = self.tol + self.drift[p]
        if len(tris) == 1:
            # A triangle is its own hull: its three edge lines, outward, as a u + b v + c <= 0.
            a, b = uv, uv[[1, 2, 0]]
            n = np.column_stack([b[:, 1] - a[:, 1], a[:, 0] - b[:, 0]])
            n /= np.linalg.norm(n, axis=1)[:, None]
            c = -(n * a).sum(axis=1)
            inside = (n @ uv[[2, 0, 1]].T)[np.arange(3), np.arange(3)] + c
            n, c = np.where(inside[:, None] > 0, -n, n), np.where(inside > 0, -c, c)
            self._tri_hull[tris[0]] = (e, np.column_stack([n, c]), slack)
            return self._tri_hull[tris[0]]
        try:
            hull = ConvexHull(uv)
        except QhullError:
            return None
        total = float(self.area[tris].sum())
        # Hull "volume" in 2D is its area; the perimeter term allows for the tolerance band.
        if hull.volume - total > slack * hull.area + 1e-12 * total:
            return None
        return e, hull.equations, slack

    def _bends(self, members: list[int], s: int) -> bool:
        """Whether two triangles of ``members`` meet at an edge of orientation ``s`` (not flat)."""
        inside = set(members)
        for t in members:
            lo, hi = self.nbr_ptr[t], self.nbr_ptr[t + 1]
            if any(k == s and int(u) in inside for u, k in zip(self.nbr[lo:hi], self.nbr_type[lo:hi])):
                return True
        return False

    def _across(self, t: int, s: int, tried: set) -> list[int]:
        """Neighbours of ``t`` across edges a patch of orientation ``s`` may grow over."""
        lo, hi = self.nbr_ptr[t], self.nbr_ptr[t + 1]
        return [int(u) for u, k in zip(self.nbr[lo:hi], self.nbr_type[lo:hi]) if k != -s and u not in tried]

    def halves(self, tris: np.ndarray) -> list[np.ndarray]:
        """Two edge-connected halves of a patch, by breadth-first order from one end."""
        tris = np.asarray(tris)
        inside = set(tris.tolist())
        order = [int(tris[0])]
        seen = {int(tris[0])}
        i = 0
        while i < len(order):
            t = order[i]
            i += 1
            for u in self.nbr[self.nbr_ptr[t]:self.nbr_ptr[t + 1]]:
                u = int(u)
                if u in inside and u not in seen:
                    seen.add(u)
                    order.append(u)
        order += [int(t) for t in tris if int(t) not in seen]
        k = len(order) // 2
        return [np.asarray(order[:k]), np.asarray(order[k:])]

    # -- bounding planes ------------------------------------------------------------------

    def bounding(self, tris: np.ndarray, s: int, level: int = 0) -> Patch | None:
        """The group of a patch of orientation ``s``: face planes (inverted if ``s < 0``) and bounding
        planes; None if some border edge has no plane keeping the patch inside. ``level`` as in
        :func:`encode_patches`."""
        v, f, fp = self.v, self.f, self.fp
        tris = np.asarray(tris, dtype=np.int64)
        faces = np.unique(fp[tris])
        if level == 2:
            p = v[f[tris[0]]]
            n = _cross(p[1] - p[0], p[2] - p[1])
            n /= np.linalg.norm(n)
            refs = [self.table.add(s * n, float(s * n @ p.mean(axis=0)))]
        else:
            refs = [self.table.inverted(int(j)) if s < 0 else int(j) for j in faces]
        chosen: list[int] = []
        xs = v[np.unique(f[tris])]
        for t, k in self._border(tris):
            a, b, c = f[t, k], f[t, (k + 1) % 3], f[t, (k + 2) % 3]
            j = self._edge_plane(t, k, a, b, c, s, xs, chosen, level)
            if j is None:
                return None
            if j not in chosen and j not in refs:
                chosen.append(j)
        return Patch(kind=3 if s > 0 else 4, triangles=tris, refs=np.asarray(refs + chosen, dtype=np.int64),
                     bounding=np.r_[np.zeros(len(refs), dtype=bool), np.ones(len(chosen), dtype=bool)])

    def _border(self, tris: np.ndarray) -> list[tuple[int, int]]:
        """``(triangle, side)`` of each edge of the patch not shared with another of its triangles."""
        f = self.f[tris]
        a = f.reshape(-1)
        b = f[:, [1, 2, 0]].reshape(-1)
        key = np.minimum(a, b) * np.int64(len(self.v)) + np.maximum(a, b)
        _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
        single = np.flatnonzero(cnt[inv] == 1)
        return [(int(tris[i // 3]), int(i % 3)) for i in single]

    def _contains(self, j: int, pts: np.ndarray, slack: float) -> bool:
        w, h = self.table.plane(j)
        return bool((pts @ w - h <= slack).all())

    def _cuts(self, j: int, face_normal: np.ndarray, drift: float) -> bool:
        """Whether plane ``j`` cuts a face of normal ``face_normal`` steeply enough for its drift."""
        w, _ = self.table.plane(j)
        sine = math.sqrt(max(0.0, 1.0 - float(w @ face_normal) ** 2))
        return sine >= max(math.sin(MIN_CUT_ANGLE), MIN_CUT_SINE_DRIFT * drift / self.target)

    def _edge_plane(self, t: int, k: int, a: int, b: int, c: int, s: int, xs: np.ndarray, chosen: list[int],
                    level: int) -> int | None:
        """A plane through edge ``a -> b`` of triangle ``t`` keeping the patch vertices ``xs`` inside."""
        v = self.v
        p = int(self.fp[t])
        drift = self.drift[p]
        on_edge = v[[a, b]]
        slack = self.tol + drift
        normal = self.omega[p]
        edge_key = (min(a, b), max(a, b))
        # The neighbour's face plane, either way round, or a plane already chosen here or next door.
        across = [u for u in self.across.get((t, k), ()) if self.fp[u] >= 0]
        candidates: list[int] = []
        if level == 0:
            for u in across:
                q = int(self.fp[u])
                candidates += [q, self.table.inverted(q)]
            candidates += self.bplanes.get(edge_key, [])
        candidates = chosen + candidates
        for j in candidates:
            w, h = self.table.plane(j)
            dj = self.drift[j] if j < self.table.base else 0.0
            if abs(on_edge @ w - h).max() <= slack + dj and self._cuts(j, normal, drift + dj) \
                    and self._contains(j, xs, slack):
                self.stats["reused"] += 1
                return j
        # A new plane through the edge, shared with the patch across it where one tilt serves both.
        d = v[b] - v[a]
        d /= np.linalg.norm(d)
        o = (v[a] - v[c]) - ((v[a] - v[c]) @ d) * d
        o /= np.linalg.norm(o)
        # The plane must hold the edge exactly: both directions it is spanned from are made
        # perpendicular to it (a polygon plane that strays from this triangle is not).
        w_face = _cross(d, o)
        if w_face @ (s * normal) < 0:
            w_face = -w_face
        others = [xs]
        for u in across:
            others.append(v[self.f[u]])
        tries = [(np.concatenate(others), True), (xs, False)] if level == 0 else [(xs, False)]
        for pts, share in tries:
            alpha = _tilt(pts - v[a], o, w_face, self.tol, upright=level > 0)
            if alpha is None:
                continue
            n = math.cos(alpha) * o + math.sin(alpha) * w_face
            n /= np.linalg.norm(n)
            if share and not all(abs(float(n @ self.omega[self.fp[u]])) <= math.cos(MIN_CUT_ANGLE) for u in across):
                continue
            j = self.table.add(n, float(n @ (0.5 * (v[a] + v[b]))))
            self.stats["shared" if share else "own"] += 1
            if level == 0:
                self.bplanes.setdefault(edge_key, []).append(j)
            return j
        return None

    def close(self, patch: Patch, planes: int) -> Patch:
        """``patch`` with ``planes`` (1 or 4) extra bounding planes far from its faces, making it bounded.

        One plane: under the patch, normal ``-mean(face normals)`` (as stored).
        Four: a regular tetrahedron around it. Either keeps every vertex
        inside by half the patch's extent.
        """
        xs = self.v[np.unique(self.f[patch.triangles])]
        margin = 0.5 * float(np.linalg.norm(np.ptp(xs, axis=0))) + self.tol
        if planes == 1:
            sign = 1.0 if patch.kind == 3 else -1.0
            mean = sign * self.omega[np.unique(self.fp[patch.triangles])].sum(axis=0)
            normals = [-mean / np.linalg.norm(mean)] if np.linalg.norm(mean) > 0 else []
        else:
            normals = list(np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / math.sqrt(3.0))
        extra = [self.table.add(n, float((xs @ n).max() + margin)) for n in normals]
        self.stats["closing"] += len(extra)
        extra = [j for j in extra if j not in patch.refs]
        return Patch(patch.kind, patch.triangles, np.r_[patch.refs, extra].astype(np.int64),
                     np.r_[patch.bounding, np.ones(len(extra), dtype=bool)])

    # -- verification ---------------------------------------------------------------------

    def verify(self, patches: list[Patch]) -> np.ndarray:
        """Error bound (model units) of each patch's decoded faces against its source triangles; inf if unusable."""
        omega, h = self.table.arrays()
        self.omega, self.h = omega, h
        refs = np.concatenate([p.refs for p in patches])
        owner = np.repeat(np.arange(len(patches)), [len(p.refs) for p in patches])
        scale = float(np.abs(h[refs]).max(initial=1.0))
        poly = intersect_many(omega[refs], h[refs], owner, len(patches), 1e-11 * scale)
        errs = np.where(poly.status == OK, 0.0, np.inf)
        is_face = ~np.concatenate([p.bounding for p in patches])
        face_rows = np.flatnonzero(is_face)
        # One decoded face per face plane, matched to the source triangles on that plane.
        decoded_face = np.full(len(refs), -1, dtype=np.int64)
        row_face = poly.polygon_row
        good = is_face[row_face]
        decoded_face[row_face[good]] = np.flatnonzero(good)
        missing = face_rows[decoded_face[face_rows] < 0]
        errs[owner[missing]] = np.inf
        tri_all, tri_face = poly.triangles()
        live = np.flatnonzero(np.isfinite(errs))
        if len(live):
            start = np.concatenate([[0], np.cumsum([len(p.refs) for p in patches])])
            errs[live] = self._face_errors([patches[i] for i in live], poly, decoded_face, start[live],
                                           tri_all, tri_face)
        return errs

    def _face_errors(self, patches: list[Patch], poly, decoded_face: np.ndarray, start: np.ndarray,
                     tri_all: np.ndarray, tri_face: np.ndarray) -> np.ndarray:
        """Per patch, the largest error of its decoded faces against their source triangles (model units).

        For a face: the exact distance of each decoded corner to the source
        triangles on that plane, plus twice the plane's drift when there are
        several (the distance to a single triangle is convex, so its corners
        bound it exactly); and of each source corner to the decoded face's
        triangles (the face is convex). All pairs are evaluated in one batch.
        """
        v, f, fp = self.v, self.f, self.fp
        # One record per (patch, face plane): its decoded face and its source triangles.
        tris = np.concatenate([p.triangles for p in patches])
        t_patch = np.repeat(np.arange(len(patches)), [len(p.triangles) for p in patches])
        planes = [np.unique(fp[p.triangles]) for p in patches]
        rec_patch = np.repeat(np.arange(len(patches)), [len(q) for q in planes])
        rec_plane = np.concatenate(planes)
        rec_face = decoded_face[np.concatenate([start[i] + np.arange(len(q)) for i, q in enumerate(planes)])]
        order = np.lexsort((fp[tris], t_patch))
        tris = tris[order]
        width = np.int64(int(fp.max()) + 2)
        key_t = t_patch[order] * width + fp[tris]
        key_r = rec_patch * width + rec_plane
        rec_of_tri = np.searchsorted(key_r, key_t)
        n_src = np.bincount(rec_of_tri, minlength=len(key_r))
        src_start = np.concatenate([[0], np.cumsum(n_src)[:-1]])
        # d1: decoded corners x source triangles of the same record.
        off = poly.polygon_offsets
        n_ring = off[rec_face + 1] - off[rec_face]
        ring_rec = np.repeat(np.arange(len(key_r)), n_ring)
        ring_pts = poly.vertices[poly.polygon_vertices[_ranges(off[rec_face], n_ring)]]
        d1 = _min_pairs(ring_pts, ring_rec, v[f[tris]], src_start, n_src)
        corner = np.zeros(len(key_r))
        np.maximum.at(corner, ring_rec, d1)
        corner += np.where(n_src > 1, 2.0 * self.drift[rec_plane], 0.0)
        # d2: source corners x decoded triangles of the same record.
        by_face = np.argsort(tri_face, kind="stable")
        sorted_face = tri_face[by_face]
        face_start = np.searchsorted(sorted_face, rec_face)
        n_dec = np.searchsorted(sorted_face, rec_face, side="right") - face_start
        dec = poly.vertices[tri_all[by_face]]
        src_pts = v[f[tris]].reshape(-1, 3)
        src_rec = np.repeat(rec_of_tri, 3)
        d2 = _min_pairs(src_pts, src_rec, dec, face_start, n_dec)
        back = np.zeros(len(key_r))
        np.maximum.at(back, src_rec, d2)
        out = np.zeros(len(patches))
        np.maximum.at(out, rec_patch, np.maximum(corner, back))
        return out


def _ranges(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Concatenated ``arange(start[i], start[i] + count[i])``."""
    count = np.asarray(count, dtype=np.int64)
    first = np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64)
    return np.repeat(np.asarray(start, dtype=np.int64) - first, count) + np.arange(int(count.sum()))


def _min_pairs(pts: np.ndarray, rec: np.ndarray, tri: np.ndarray, tri_start: np.ndarray,
               tri_count: np.ndarray) -> np.ndarray:
    """For each point ``pts[i]``, the exact distance to the nearest of the triangles of its record
    ``tri[tri_start[rec[i]] : + tri_count[rec[i]]]`` (inf if none)."""
    k = tri_count[rec]
    pi = np.repeat(np.arange(len(pts)), k)
    ti = _ranges(tri_start[rec], k)
    out = np.full(len(pts), np.inf)
    if len(pi):
        d = point_triangle_distance(pts[pi], tri[ti, 0], tri[ti, 1], tri[ti, 2])
        np.minimum.at(out, pi, d)
    return out


def _tilt(rel: np.ndarray, o: np.ndarray, w: np.ndarray, tol: float, upright: bool = False) -> float | None:
    """The tilt ``alpha`` of ``n = cos(alpha) o + sin(alpha) w`` keeping points ``rel`` (relative to
    the edge) in ``n . x <= 0``; None if no tilt that cuts the face does.

    With ``u = o . x``, ``z = w . x <= 0``: ``u cos a + z sin a <= 0`` means
    ``a >= atan2(u, -z)`` for points below the face; points on it must not
    lie beyond the edge. The tilt is mid-range, but at most
    :data:`DOWN_TILT` below the perpendicular; ``upright`` takes the
    feasible tilt nearest the perpendicular (the best conditioned corners).
    """
    u = rel @ o
    z = rel @ w
    flat = z > -tol
    if (u[flat] > tol).any():
        return None
    lo = float(np.arctan2(u[~flat], -z[~flat]).max(initial=-math.pi / 2))
    hi = math.pi / 2 - math.radians(5.0)
    if lo >= hi:
        return None
    if upright:
        return max(0.0, 0.5 * (lo + hi)) if lo > 0 else 0.0
    return max(0.5 * (lo + hi), -DOWN_TILT)


def _inside(hull: tuple[np.ndarray, np.ndarray, float], pts: np.ndarray) -> bool:
    """Whether points (n, 3) lie in a polygon of :meth:`_Geometry._hull`, within its tolerance."""
    if len(pts) == 0:
        return True
    e, eq, slack = hull
    uv = pts @ e.T
    return bool((uv @ eq[:, :2].T + eq[:, 2] <= slack).all())


def _basis(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``e1, e2`` with ``(e1, e2, w)`` right-handed."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(w)))] = 1.0
    e1 = _cross(w, axis)
    e1 /= math.sqrt(float(e1 @ e1))
    return e1, _cross(w, e1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of two 3-vectors (``np.cross`` costs microseconds of overhead per call)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def decode_patch_faces(omega: np.ndarray, h: np.ndarray, owner: np.ndarray, count: int, face: np.ndarray,
                       concave: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Decode many patch groups at once (spec §9.8).

    ``omega``, ``h`` the stored planes of all groups' references (rows),
    ``owner`` (rows,) sorted group ids, ``face`` (rows,) True for face
    planes, ``concave`` (count,) True for kind 4. Returns ``(vertices,
    triangles, triangle_row, status)``: triangles of the faces on face
    planes, counter-clockwise seen from outside of the source surface
    (flipped back for kind 4), the row each lies on, and each group's
    :mod:`planefmt.geometry.polytopes` status.
    """
    scale = float(np.abs(h).max(initial=1.0))
    poly = intersect_many(omega, h, owner, count, 1e-11 * scale)
    tris, tri_face = poly.triangles()
    row = poly.polygon_row[tri_face]
    keep = face[row]
    tris, row = tris[keep], row[keep]
    flip = concave[owner[row]]
    tris[flip] = tris[flip][:, ::-1]
    # Vertices only on bounding faces are not part of the surface.
    used, tris = np.unique(tris, return_inverse=True)
    return poly.vertices[used], tris.reshape(-1, 3), row, poly.status


def first_references(refs: np.ndarray, omega: np.ndarray, h: np.ndarray,
                     owner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(first, twin)``: for each row, the first row of its group (``owner``) with the same plane
    index (``refs``), whose plane bounds the polytope for all of a repeated reference's rows (spec
    §9.8); and whether its plane equals that of an earlier reference of the group with another index,
    which makes it redundant, bounding no face (§9.4's near-copies at distance 0)."""
    refs = np.asarray(refs, dtype=np.int64)
    owner = np.asarray(owner, dtype=np.int64)
    if len(refs) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    _, first, inverse = np.unique(owner * (int(refs.max()) + 1) + refs, return_index=True, return_inverse=True)
    first = first[inverse.reshape(-1)]
    value = np.column_stack([owner.astype(np.float64), omega, h])
    _, same, inverse = np.unique(value, axis=0, return_index=True, return_inverse=True)
    return first, same[inverse.reshape(-1)] != first


def repeat_faces(tri_row: np.ndarray, first: np.ndarray, face: np.ndarray,
                 max_triangles: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """Spec §9.8: a face reference that appears k times yields its face k times. ``tri_row`` the row of
    each decoded triangle (rows where ``first`` is the row itself), ``face`` (rows,) the face rows.
    Returns the triangles to emit (indices into ``tri_row``), face row after face row in row order, and
    each one's row. Raises ``LimitError`` before allocating more than ``max_triangles``: k repeats of a
    face of n sides are k (n - 2) triangles from a body of k + n references."""
    rows = len(first)
    order = np.argsort(tri_row, kind="stable")
    count = np.bincount(tri_row, minlength=rows)
    begin = np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64)
    emit = np.flatnonzero(face)
    per = count[first[emit]]
    total = int(per.sum())
    if total > max_triangles:
        raise LimitError(f"its repeated face references make {total:,} triangles, above this reader's limit "
                         f"of {int(max_triangles):,} left (raise it with Limits(max_triangles=...) or "
                         f"pln --max-triangles)")
    return order[_ranges(begin[first[emit]], per)], np.repeat(emit, per)


def decode_patch_groups(omega: np.ndarray, h: np.ndarray, sizes: list[int], face: np.ndarray,
                        concave: np.ndarray, refs: np.ndarray | None = None,
                        max_triangles: float = math.inf) -> list[tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                        np.ndarray, np.ndarray]]:
    """Decode patch groups in one batch: per group ``(vertices, triangles, inc_vertex, inc_ref,
    triangle_ref)``.

    ``omega``, ``h``, ``face`` hold the stored planes and roles of every
    group's references, group after group (``sizes`` references each), ``refs``
    their plane table indices (each reference a plane of its own without: a
    reference that repeats another's plane under another index is redundant);
    ``concave`` (groups,) marks kind 4. Triangles are those of faces on face
    planes (flipped back for kind 4), once per face reference (spec §9.8: a
    repeated reference bounds the polytope once); incidences pair each vertex
    with the first local reference of every plane it lies on (faces on
    bounding planes included). Raises ``EMPTY_POLYTOPE`` or
    ``UNBOUNDED_POLYTOPE`` naming the first bad group (by position), ``LimitError``
    where the batch's triangles would exceed ``max_triangles``.
    """
    count = len(sizes)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    owner = np.repeat(np.arange(count), sizes)
    first, twin = np.arange(len(h)), np.zeros(len(h), dtype=bool)
    if refs is not None:
        first, twin = first_references(refs, omega, h, owner)
    distinct = np.flatnonzero((first == np.arange(len(h))) & ~twin)
    # Each group's own scale: a group decodes the same in any batch, and alone.
    scale = np.ones(count)
    np.maximum.at(scale, owner, np.abs(h))
    poly = intersect_many(omega[distinct], h[distinct], owner[distinct], count, 1e-11 * scale)
    bad = np.flatnonzero(poly.status != OK)
    if len(bad):
        code = "UNBOUNDED_POLYTOPE" if poly.status[bad[0]] == 2 else "EMPTY_POLYTOPE"
        raise GeometryError(f"patch group {int(bad[0])}: its planes bound no {'finite ' if code[0] == 'U' else ''}"
                            f"polytope", code=code)
    tris, tri_face = poly.triangles()
    emit, row = repeat_faces(distinct[poly.polygon_row[tri_face]], first, face & ~twin, max_triangles)
    tris = tris[emit]
    flip = concave[owner[row]]
    tris[flip] = tris[flip][:, ::-1]
    size = np.diff(poly.polygon_offsets)
    inc_v = poly.polygon_vertices
    inc_row = distinct[np.repeat(poly.polygon_row, size)]
    tri_owner = owner[row]
    inc_owner = owner[inc_row]
    # Each group's vertices, numbered in its own order: one sort over (group, vertex) keys for all.
    nv = np.int64(len(poly.vertices))
    used, local = np.unique(tri_owner[:, None] * nv + tris, return_inverse=True)
    v_split = np.searchsorted(used // nv, np.arange(count + 1))
    local = local.reshape(-1, 3) - v_split[tri_owner][:, None]
    # Incidences of vertices of a group's triangles, as sorted (vertex, reference) pairs per group.
    key = inc_owner * nv + inc_v
    pos = np.minimum(np.searchsorted(used, key), max(len(used) - 1, 0))
    on = used[pos] == key if len(used) else np.zeros(len(key), dtype=bool)
    span = np.int64(int(np.max(sizes, initial=0)) + 1)
    pairs = np.unique(pos[on] * span + (inc_row[on] - start[inc_owner[on]]))
    p_split = np.searchsorted(pairs // span, v_split)
    vertex_of = used % nv
    t_split = np.searchsorted(tri_owner, np.arange(count + 1))
    out = []
    for g in range(count):
        a, b = v_split[g], v_split[g + 1]
        pg = pairs[p_split[g]:p_split[g + 1]]
        out.append((poly.vertices[vertex_of[a:b]], local[t_split[g]:t_split[g + 1]], pg // span - a, pg % span,
                    row[t_split[g]:t_split[g + 1]] - start[g]))
    return out
