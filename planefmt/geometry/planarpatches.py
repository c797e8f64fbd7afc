"""Convex planar patches of a triangle mesh, and the cut planes between adjacent patches.

A *patch* is a set of edge-connected, consistently oriented, (nearly) coplanar
triangles whose union is (nearly) a convex polygon; a triangle that joins no
other forms a patch alone. Patches serve the Hausdorff bounds of
:mod:`planefmt.geometry.hausdorff`, which rely on one fact: the distance to a convex set
is a convex function.

For a patch C the module keeps a convex set K (the convex hull of the patch's
outer loop, stored as a fan of triangles over its hull vertices) and a slack
``sigma`` with ``d(x, union C) <= d(x, K) + sigma`` for every x, so
``d(x, mesh) <= d(x, K) + sigma``. With the vertices of C within ``tau`` of a
fitted plane and the projected loop within ``pocket`` of its projected convex
hull, ``sigma = 2*tau + pocket``: a point of K is within ``tau`` of the plane, its
projection is within ``pocket`` of the projected union, and the point of C above
that is within ``tau`` of the plane again. ``pocket`` is measured exactly: every
loop vertex between two consecutive hull vertices is within ``pocket`` of that
hull edge, and the pocket region lies in the strip those points span. The
projected union is the region bounded by the loop because a patch must be a
topological disc (one boundary loop, Euler characteristic 1) whose triangles all
face the same side of the plane. Singleton patches are their own triangle
(``sigma = 0``) and need none of this.

Units are those of the mesh coordinates.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .trianglegeom import TriangleIndex, table_distances, triangle_table

#: A cut plane between two patches is skipped when their sides fold onto each
#: other (the in-plane directions into the two faces nearly coincide).
_MIN_CUT_NORMAL = 1e-6
_ROWS_PER_CHUNK = 1 << 20


class ConvexPatches:
    """The convex planar patches of a mesh, their slacks and the cut planes between neighbours.

    ``merge_tol`` (model units) bounds the slack of every merged patch and the
    off-plane distance of triangles considered coplanar. ``flatness`` (model
    units) bounds the flatness ``tau`` of a coplanar region: a region less flat
    is split where its triangles' planes part, and what is still less flat
    serves no region bound.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, merge_tol: float,
                 flatness: float = np.inf) -> None:
        self.vertices, self.faces = vertices, faces
        tri = vertices[faces]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(cross, axis=1)
        longest = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
        # Degenerate triangles (no reliable normal) never join a patch.
        self._solid = norm > 1e-9 * longest**2
        self._longest = longest
        self._height = norm / np.where(longest > 0, longest, 1.0)
        self._flatness = flatness
        self._unit = np.where(self._solid[:, None], cross / np.where(norm > 0, norm, 1.0)[:, None], 0.0)
        self._area_normal = cross
        self._pairs = _manifold_edge_pairs(faces)
        patch_of, fans, slack = self._grow(merge_tol)
        self.patch_of = patch_of
        self.slack = slack
        counts = np.array([len(fan) for fan in fans])
        self.singleton = counts == 0
        # Rows of the patch table: a singleton patch is its own triangle, a
        # merged one the fan over its hull vertices.
        self._ptr = np.concatenate([[0], np.cumsum(np.maximum(counts, 1))])
        k_tri = np.empty((self._ptr[-1], 3, 3))
        owner = np.empty(len(slack), dtype=np.int64)
        owner[patch_of] = np.arange(len(faces))
        singles = np.flatnonzero(self.singleton)
        k_tri[self._ptr[singles]] = tri[owner[singles]]
        merged = np.flatnonzero(~self.singleton)
        if len(merged):
            rows = np.concatenate([np.arange(self._ptr[p], self._ptr[p + 1]) for p in merged])
            k_tri[rows] = vertices[np.concatenate([np.asarray(fans[p]) for p in merged])]
        self._table = triangle_table(k_tri)
        self._build_cuts()

    @property
    def count(self) -> int:
        return len(self.slack)

    def distance(self, points: np.ndarray, patch: np.ndarray) -> np.ndarray:
        """Upper bound on ``d(points[i], K[patch[i]])`` (exact up to rounding); add ``slack`` for the mesh."""
        counts = self._ptr[patch + 1] - self._ptr[patch]
        out = np.empty(len(patch))
        # Chunks of about _ROWS_PER_CHUNK triangle rows bound the index arrays for patches with big fans.
        ends = np.searchsorted(np.cumsum(counts), np.arange(1, counts.sum() // _ROWS_PER_CHUNK + 1) * _ROWS_PER_CHUNK)
        for lo, hi in zip(np.r_[0, ends], np.r_[ends, len(patch)]):
            if hi <= lo:
                continue
            c = counts[lo:hi]
            start = np.cumsum(c) - c
            qi = np.repeat(np.arange(lo, hi), c)
            rows = np.arange(len(qi)) - np.repeat(start, c) + np.repeat(self._ptr[patch[lo:hi]], c)
            out[lo:hi] = np.minimum.reduceat(table_distances(points[qi], self._table, rows), start)
        return out

    def region_cover(self, corners: np.ndarray, anchor: np.ndarray, region: np.ndarray,
                     inset: float) -> tuple[np.ndarray, np.ndarray]:
        """Whether each triangle ``corners[i]`` projects into coplanar region ``region[i]``, up to a thin rim.

        ``anchor[i]`` must be a point of the region. Projected onto the region's
        plane, the triangle shrunk by ``inset`` (a homothety about its incentre)
        must hold the anchor and meet none of the region's boundary edges; being
        connected, it then lies inside the region, whose projected outline is
        made of those edges. Returns ``(ok, rim)``: every point of the triangle
        projects within ``rim`` of the shrunk triangle, hence of the region.
        Rounding is covered by testing against half and twice the inset.
        """
        n = self.region_normal[region]
        k = np.argmin(np.abs(n), axis=1)
        u = np.cross(n, np.eye(3)[k])
        u /= np.linalg.norm(u, axis=1)[:, None]
        w = np.cross(n, u)
        basis = np.stack([u, w], axis=2)
        c = np.einsum("kij,kjl->kil", corners, basis)
        a = np.einsum("kj,kjl->kl", anchor, basis)
        e = np.roll(c, -1, axis=1) - c
        length = np.linalg.norm(e, axis=2)
        twice_area = e[:, 0, 0] * e[:, 1, 1] - e[:, 0, 1] * e[:, 1, 0]
        sign = np.where(twice_area < 0, -1.0, 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            inward = np.stack([-e[..., 1], e[..., 0]], axis=2) * (sign[:, None] / length)[..., None]
            inradius = np.abs(twice_area) / length.sum(axis=1)
            incentre = np.einsum("ki,kij->kj", np.roll(length, -1, axis=1), c) / length.sum(axis=1)[:, None]
            rim = inset / inradius * np.linalg.norm(c - incentre[:, None], axis=2).max(axis=1)
        ok = (inradius > 4.0 * inset) & np.isfinite(rim)
        ok &= (np.einsum("kij,kij->ki", inward, a[:, None] - c) >= 2.0 * inset).all(axis=1)
        # Boundary edges near enough to meet the projection: within the piece's
        # reach from its centroid plus its height over the plane and the flatness.
        centroid = corners.mean(axis=1)
        height = np.abs(np.einsum("kij,kj->ki", corners, n) - self.region_offset[region][:, None]).max(axis=1)
        reach = (np.linalg.norm(corners - centroid[:, None], axis=2).max(axis=1) + height
                 + 2.0 * self.region_tau[region] + inset)
        rows = np.flatnonzero(ok)
        qi, node = self.boundary.candidates(centroid[rows], reach[rows])
        own = self._boundary_region[node] == region[rows[qi]]
        qi, node = qi[own], node[own]
        seg = self.boundary.faces[node][:, :2]
        piece = rows[qi]
        s0 = np.einsum("kj,kjl->kl", self.vertices[seg[:, 0]], basis[piece])
        d = np.einsum("kj,kjl->kl", self.vertices[seg[:, 1]], basis[piece]) - s0
        lo, hi = np.zeros(len(piece)), np.ones(len(piece))
        for j in range(3):
            m = inward[piece, j]
            alpha = np.einsum("kl,kl->k", m, s0 - c[piece, j]) - 0.5 * inset
            beta = np.einsum("kl,kl->k", m, d)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -alpha / beta
            lo = np.where(beta > 0, np.maximum(lo, t), lo)
            hi = np.where(beta < 0, np.minimum(hi, t), hi)
            hi = np.where((beta == 0) & (alpha < 0), -1.0, hi)
        ok[piece[lo <= hi]] = False
        return ok, rim

    def cut(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cut planes between patches ``lo < hi``: ``(found, point, normal)``; the positive side goes to ``lo``."""
        key = lo * self.count + hi
        if len(self._cut_key) == 0:
            return np.zeros(len(key), dtype=bool), np.zeros((len(key), 3)), np.zeros((len(key), 3))
        pos = np.minimum(np.searchsorted(self._cut_key, key), len(self._cut_key) - 1)
        found = self._cut_key[pos] == key
        return found, self._cut_point[pos], self._cut_normal[pos]

    def _grow(self, tol: float) -> tuple[np.ndarray, list[list[tuple[int, int, int]]], np.ndarray]:
        f1, f2, shared = self._pairs
        v, f = self.vertices, self.faces
        opposite = f[f1, (shared[:, 0] + 1) % 3] == f[f2, shared[:, 1]]
        apex1 = v[f[f1, (shared[:, 0] + 2) % 3]]
        apex2 = v[f[f2, (shared[:, 1] + 2) % 3]]
        off12 = np.abs(np.einsum("ij,ij->i", self._unit[f1], apex2 - v[f[f1, 0]]))
        off21 = np.abs(np.einsum("ij,ij->i", self._unit[f2], apex1 - v[f[f2, 0]]))
        flat = (opposite & self._solid[f1] & self._solid[f2] & (off12 <= tol) & (off21 <= tol)
                & (np.einsum("ij,ij->i", self._unit[f1], self._unit[f2]) > 0))
        n = len(f)
        graph = coo_matrix((np.ones(flat.sum()), (f1[flat], f2[flat])), shape=(n, n))
        _, region = connected_components(graph, directed=False)
        patch_of = np.full(n, -1, dtype=np.int64)
        fans: list[list[tuple[int, int, int]]] = []
        slack: list[float] = []
        sizes = np.bincount(region)
        order = np.argsort(region, kind="stable")
        bounds = np.concatenate([[0], np.cumsum(sizes)])
        edge_region = region[f1[flat]]
        edge_order = np.argsort(edge_region, kind="stable")
        edge_bounds = np.searchsorted(edge_region[edge_order], np.arange(len(sizes) + 1))
        flat_ids = np.flatnonzero(flat)
        self._xyz = v.tolist()
        pairs = np.flatnonzero((sizes == 2) & (np.diff(edge_bounds) == 1))
        k = flat_ids[edge_order[edge_bounds[pairs]]]
        quad_fans, quad_slack = self._quad_shapes(f1[k], f2[k], shared[k])
        for t1, t2, fan, s in zip(f1[k].tolist(), f2[k].tolist(), quad_fans, quad_slack.tolist()):
            if s <= tol:
                patch_of[[t1, t2]] = len(slack)
                fans.append(fan)
                slack.append(s)
        larger = np.ones(len(sizes), dtype=bool)
        larger[pairs] = False
        for r in np.flatnonzero((sizes > 1) & larger):
            members = order[bounds[r]:bounds[r + 1]]
            sel = flat_ids[edge_order[edge_bounds[r]:edge_bounds[r + 1]]]
            for group, fan, s in self._convex_groups(members, f1[sel], f2[sel], shared[sel, 0], tol):
                patch_of[group] = len(slack)
                fans.append(fan)
                slack.append(s)
        rest = np.flatnonzero(patch_of < 0)
        patch_of[rest] = len(slack) + np.arange(len(rest))
        fans.extend([] for _ in rest)
        slack = np.concatenate([np.asarray(slack, dtype=np.float64), np.zeros(len(rest))])
        self._build_regions(region, f1[flat], f2[flat], shared[flat], tol)
        return patch_of, fans, slack

    def _quad_shapes(self, f1: np.ndarray, f2: np.ndarray,
                     shared: np.ndarray) -> tuple[list[list[tuple[int, int, int]]], np.ndarray]:
        """Hull fans and slacks of the two-triangle regions, all at once (as :meth:`_patch_shape`).

        Triangles (a, b, c) and (b, a, d) bound the loop a, d, b, c. A simple
        quadrilateral has at most one reflex vertex: the pocket is its depth
        below the chord of its neighbours, and the hull is the other three.
        """
        f = self.faces
        s1 = shared[:, 0]
        loop = np.column_stack([f[f1, s1], f[f2, (shared[:, 1] + 2) % 3], f[f1, (s1 + 1) % 3], f[f1, (s1 + 2) % 3]])
        normal = self._area_normal[f1] + self._area_normal[f2]
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        p = self.vertices[loop]
        height = np.einsum("kij,kj->ki", p, normal)
        tau = 0.5 * (height.max(axis=1) - height.min(axis=1))
        prev, nxt = np.roll(p, 1, axis=1), np.roll(p, -1, axis=1)
        chord = nxt - prev
        depth = (np.einsum("kij,kj->ki", np.cross(chord, p - prev), normal)
                 / np.linalg.norm(chord, axis=2))
        reflex = np.argmax(depth, axis=1)
        pocket = np.maximum(depth.max(axis=1), 0.0)
        convex = pocket == 0.0
        ids = loop.tolist()
        fans = [[(q[0], q[1], q[2]), (q[0], q[2], q[3])] if c else [tuple(q[(j + i) % 4] for i in (1, 2, 3))]
                for q, c, j in zip(ids, convex.tolist(), reflex.tolist())]
        facing = (self._unit[f1] * normal).sum(axis=1) > 0
        facing &= (self._unit[f2] * normal).sum(axis=1) > 0
        return fans, np.where(facing, 2.0 * tau + pocket, np.inf)

    def _convex_groups(self, members: np.ndarray, e1: np.ndarray, e2: np.ndarray, slot: np.ndarray,
                       tol: float) -> list[tuple[np.ndarray, list[tuple[int, int, int]], float]]:
        """Split one coplanar region (internal edges: slot ``slot`` of face ``e1``, shared with ``e2``)
        into convex patches with slack at most ``tol``: the whole region if it is one, else greedy merges."""
        whole = self._patch_shape(members)
        if whole is not None and whole[1] <= tol:
            return [(members, whole[0], whole[1])]
        out = []
        for group in self._greedy_merge(members, e1, e2, slot):
            shape = self._patch_shape(np.asarray(group))
            if shape is not None and shape[1] <= tol:
                out.append((np.asarray(group), shape[0], shape[1]))
        return out

    def _greedy_merge(self, members: np.ndarray, e1: np.ndarray, e2: np.ndarray, slot: np.ndarray) -> list[list[int]]:
        """Merge convex groups across internal edges, longest edge first, in passes until none merges.

        Each group keeps its boundary loop as successor and predecessor maps, so
        testing a merge only looks at the two ends of the shared boundary chain:
        the union of two convex polygons sharing a chain is convex iff it turns
        left at both ends. The merged groups are checked rigorously afterwards.
        """
        f = self.faces
        normal = self._area_normal[members].sum(axis=0)
        normal = (normal / np.linalg.norm(normal)).tolist()
        xyz = self._xyz

        def left(a: int, s: int, d: int) -> bool:
            p, q, r = xyz[a], xyz[s], xyz[d]
            u = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
            w = (r[0] - q[0], r[1] - q[1], r[2] - q[2])
            turn = ((u[1] * w[2] - u[2] * w[1]) * normal[0] + (u[2] * w[0] - u[0] * w[2]) * normal[1]
                    + (u[0] * w[1] - u[1] * w[0]) * normal[2])
            return turn >= -1e-12 * ((u[0] ** 2 + u[1] ** 2 + u[2] ** 2) * (w[0] ** 2 + w[1] ** 2 + w[2] ** 2)) ** 0.5

        parent = {int(t): int(t) for t in members}
        groups = {int(t): [int(t)] for t in members}
        succ = {int(t): {int(f[t, 0]): int(f[t, 1]), int(f[t, 1]): int(f[t, 2]), int(f[t, 2]): int(f[t, 0])}
                for t in members}
        pred = {t: {b: a for a, b in m.items()} for t, m in succ.items()}

        def root(t: int) -> int:
            while parent[t] != t:
                parent[t] = parent[parent[t]]
                t = parent[t]
            return t

        ends = np.stack([f[e1, slot], f[e1, (slot + 1) % 3]], axis=1)
        length = np.linalg.norm(self.vertices[ends[:, 0]] - self.vertices[ends[:, 1]], axis=1)
        order = np.argsort(-length, kind="stable").tolist()
        e1l, e2l, ends = e1.tolist(), e2.tolist(), ends.tolist()
        merged = True
        while merged:
            merged = False
            for k in order:
                p, q = root(e1l[k]), root(e2l[k])
                if p == q:
                    continue
                sp, pp, sq, pq = succ[p], pred[p], succ[q], pred[q]
                u, v = ends[k]
                if sp.get(u) != v:
                    u, v = v, u
                if sp.get(u) != v or sq.get(v) != u:
                    continue
                # Grow the shared chain s -> ... -> e (P's direction) both ways.
                s, e, steps = u, v, 0
                while pp[s] == sq[s] and steps < len(sp):
                    s, steps = pp[s], steps + 1
                while sp[e] == pq[e] and steps < len(sp):
                    e, steps = sp[e], steps + 1
                if steps >= min(len(sp), len(sq)) - 2 or not (left(pp[s], s, sq[s]) and left(pq[e], e, sp[e])):
                    continue
                chain = [s]
                while chain[-1] != e:
                    chain.append(sp[chain[-1]])
                if len(sp.keys() & sq.keys()) != len(chain):
                    continue
                for a, b in zip(chain, chain[1:]):
                    del sp[a], pp[b], sq[b], pq[a]
                if len(sp) < len(sq):
                    p, q = q, p
                succ[p].update(succ.pop(q))
                pred[p].update(pred.pop(q))
                parent[q] = p
                groups[p] += groups.pop(q)
                merged = True
        return [g for g in groups.values() if len(g) > 1]

    def _patch_shape(self, tris: np.ndarray) -> tuple[list[tuple[int, int, int]], float] | None:
        """Hull fan and slack ``2*tau + pocket`` of a triangle set, or None if it is not a convex disc."""
        f = self.faces[tris].tolist()
        directed = {(a, b) for t in f for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
        if len(directed) != 3 * len(f):
            return None
        succ: dict[int, int] = {}
        for a, b in directed:
            if (b, a) not in directed:
                if a in succ:
                    return None
                succ[a] = b
        verts = list({x for t in f for x in t})
        if len(verts) - (3 * len(f) + len(succ)) // 2 + len(f) != 1:
            return None
        loop = [next(iter(succ))]
        for _ in range(len(succ) - 1):
            loop.append(succ[loop[-1]])
        if succ[loop[-1]] != loop[0] or len(set(loop)) != len(loop):
            return None
        normal = self._area_normal[tris].sum(axis=0)
        normal /= np.linalg.norm(normal)
        if (self._unit[tris] @ normal).min() <= 0:
            return None
        height = self.vertices[verts] @ normal
        tau = 0.5 * float(height.max() - height.min())
        # An in-plane orthonormal basis (u, normal x u).
        k = int(np.argmin(np.abs(normal)))
        u = np.zeros(3)
        u[(k + 1) % 3], u[(k + 2) % 3] = -normal[(k + 2) % 3], normal[(k + 1) % 3]
        u /= np.linalg.norm(u)
        w = np.array([normal[1] * u[2] - normal[2] * u[1], normal[2] * u[0] - normal[0] * u[2],
                      normal[0] * u[1] - normal[1] * u[0]])
        pts = (self.vertices[loop] @ np.stack([u, w], axis=1)).tolist()
        hull = _convex_hull(pts)
        start = hull.index(min(hull))
        hull = hull[start:] + hull[:start]
        if len(hull) < 3 or any(b <= a for a, b in zip(hull, hull[1:])):
            return None
        # Each loop vertex against the hull edge spanning it (inner side positive).
        pocket = 0.0
        closed = hull + [hull[0] + len(loop)]
        for h0, h1 in zip(closed, closed[1:]):
            ax, ay = pts[h0]
            bx, by = pts[h1 % len(loop)]
            ex, ey = bx - ax, by - ay
            norm = (ex * ex + ey * ey) ** 0.5
            for j in range(h0 + 1, h1):
                px, py = pts[j % len(loop)]
                pocket = max(pocket, (ex * (py - ay) - ey * (px - ax)) / norm)
        ids = [loop[i] for i in hull]
        fan = [(ids[0], ids[i], ids[i + 1]) for i in range(1, len(ids) - 1)]
        return fan, 2.0 * tau + pocket

    def _build_regions(self, region: np.ndarray, f1: np.ndarray, f2: np.ndarray, shared: np.ndarray,
                       tol: float) -> None:
        """Planes, flatness and boundary edges of the coplanar regions of two or more triangles.

        A region qualifies when every triangle faces the side of its fitted plane,
        so that projected onto the plane the region is the image of an immersion
        whose boundary lies in the projection of its boundary edges, and when its
        flatness is within ``self._flatness``.

        Flatness is not transitive: a triangle thinner than ``tol`` lies within
        ``tol`` of every plane through its long edge, so a chain of them joins
        faces at any angle (angle_block.STL's exact decoding has facets 1e-10
        across: one region 0.35 of the diagonal thick, whose boundary edges
        fell within reach of every piece, 76 million pairs). A region less flat
        than allowed keeps only the pairs of triangles thicker than ``tol``
        whose planes stay within ``tol`` of each other across the pair.
        """
        v, f = self.vertices, self.faces
        normal, offset, tau, facing = self._region_planes(region)
        rough = tau > self._flatness
        if rough.any():
            spread = np.linalg.norm(np.cross(self._unit[f1], self._unit[f2]), axis=1) * np.maximum(
                self._longest[f1], self._longest[f2])
            keep = (rough[region[f1]] & (self._height[f1] > tol) & (self._height[f2] > tol) & (spread <= tol))
            n = len(f)
            graph = coo_matrix((np.ones(keep.sum()), (f1[keep], f2[keep])), shape=(n, n))
            _, split = connected_components(graph, directed=False)
            # A rough region's triangles take their component's label (offset past the old ones).
            key = np.where(rough[region], len(tau) + split, region)
            _, region = np.unique(key, return_inverse=True)
            normal, offset, tau, facing = self._region_planes(region)
        sizes = np.bincount(region)
        valid = (sizes > 1) & (facing > 0) & (tau <= self._flatness)
        self.region_of = np.where(valid[region], region, -1)
        self.region_normal = normal
        self.region_offset = offset
        self.region_tau = tau
        internal = np.zeros(f.shape, dtype=bool)
        joined = region[f1] == region[f2]
        internal[f1[joined], shared[joined, 0]] = True
        internal[f2[joined], shared[joined, 1]] = True
        edge = ~internal & valid[region][:, None]
        t, k = np.nonzero(edge)
        segments = np.column_stack([f[t, k], f[t, (k + 1) % 3], f[t, (k + 1) % 3]])
        self.boundary = TriangleIndex(v, segments) if len(segments) else None
        self._boundary_region = region[t]

    def _region_planes(self, region: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per region label: unit area-weighted normal, mid offset, flatness ``tau`` (half the spread
        of its vertices' heights) and the least cosine of a member's normal to the region's."""
        v, f = self.vertices, self.faces
        count = int(region.max(initial=-1)) + 1
        normal = np.zeros((count, 3))
        np.add.at(normal, region, self._area_normal)
        normal /= np.maximum(np.linalg.norm(normal, axis=1), np.finfo(np.float64).tiny)[:, None]
        facing = np.full(count, np.inf)
        np.minimum.at(facing, region, np.einsum("ij,ij->i", self._unit, normal[region]))
        heights = np.einsum("tkj,tj->tk", v[f], normal[region])
        top = np.full(count, -np.inf)
        bottom = np.full(count, np.inf)
        np.maximum.at(top, region, heights.max(axis=1))
        np.minimum.at(bottom, region, heights.min(axis=1))
        return normal, 0.5 * (top + bottom), 0.5 * (top - bottom), facing

    def _build_cuts(self) -> None:
        f1, f2, shared = self._pairs
        v, f = self.vertices, self.faces
        p1, p2 = self.patch_of[f1], self.patch_of[f2]
        ok = (p1 != p2) & self._solid[f1] & self._solid[f2]
        f1, f2, shared, p1, p2 = f1[ok], f2[ok], shared[ok], p1[ok], p2[ok]
        start = v[f[f1, shared[:, 0]]]
        t = v[f[f1, (shared[:, 0] + 1) % 3]] - start
        t /= np.linalg.norm(t, axis=1)[:, None]

        def inward(apex: np.ndarray) -> np.ndarray:
            r = apex - start
            r -= np.einsum("ij,ij->i", r, t)[:, None] * t
            return r / np.linalg.norm(r, axis=1)[:, None]

        # The plane through the shared edge bisecting the two faces: on it the
        # two faces' planes are equally far, so it splits a piece where its
        # nearest face changes.
        m = inward(v[f[f1, (shared[:, 0] + 2) % 3]]) - inward(v[f[f2, (shared[:, 1] + 2) % 3]])
        size = np.linalg.norm(m, axis=1)
        ok = size > _MIN_CUT_NORMAL
        m = m[ok] / size[ok, None]
        lo, hi = np.minimum(p1, p2)[ok], np.maximum(p1, p2)[ok]
        m[p1[ok] != lo] *= -1.0
        key = lo * self.count + hi
        key, first = np.unique(key, return_index=True)
        self._cut_key = key
        self._cut_point = start[ok][first]
        self._cut_normal = m[first]


def _convex_hull(pts: list[list[float]]) -> list[int]:
    """Indices of the strict convex hull of 2D points, counterclockwise (Andrew's monotone chain)."""
    order = sorted(range(len(pts)), key=lambda i: (pts[i][0], pts[i][1]))

    def half(seq: list[int]) -> list[int]:
        out: list[int] = []
        for i in seq:
            while len(out) >= 2:
                (ox, oy), (ax, ay), (bx, by) = pts[out[-2]], pts[out[-1]], pts[i]
                if (ax - ox) * (by - oy) - (ay - oy) * (bx - ox) > 0:
                    break
                out.pop()
            out.append(i)
        return out[:-1]

    return half(order) + half(order[::-1])


def _manifold_edge_pairs(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Faces ``f1, f2`` sharing an edge used by exactly two faces, and that edge's slot in each (k, 2)."""
    n = int(faces.max()) + 1
    u = faces
    w = np.roll(faces, -1, axis=1)
    key = (np.minimum(u, w) * n + np.maximum(u, w)).ravel()
    order = np.argsort(key, kind="stable")
    k = key[order]
    first = np.r_[True, k[1:] != k[:-1]]
    starts = np.flatnonzero(first)
    counts = np.diff(np.r_[starts, len(k)])
    two = starts[counts == 2]
    a, b = order[two], order[two + 1]
    return a // 3, b // 3, np.stack([a % 3, b % 3], axis=1)
