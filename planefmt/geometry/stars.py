"""Vertex stars of a triangle mesh: wedges around an axis through a vertex, for Hausdorff bounds.

Take a point c of the mesh and an axis n through it. Half-planes bounded by the
axis, at angles that leave no gap of pi or more between neighbours, cut space
into wedges; each is the intersection of two half-spaces, so convex, and
together they cover space. For x in wedge W and any convex set K_W within
``sigma`` of the mesh, ``d(x, mesh) <= d(x, K_W) + sigma``, a convex function of
x. Over a convex piece P its maximum on ``P & W`` is therefore at a vertex of
that polygon: a corner of P inside W, a point where an edge of P crosses one of
W's half-planes, or the point where the axis pierces P. This holds whatever the
angles and the sets; they only decide how tight the bound is.

The module takes c at a vertex of the mesh, or at the centroid of a *cluster*,
vertices joined by edges shorter than ``cluster_edge`` (a decoded smooth mesh has
them where several nearly coplanar planes meet, off by rounding or
quantization). The half-planes point at the far ends of the edges leaving the
cluster (*spokes*), and each wedge is measured against the convex patches
(:class:`planefmt.geometry.planarpatches.ConvexPatches`) of the triangles on its two
spokes, the least bound of them. So a piece lying over a vertex where several
nearly coplanar faces meet, which neither one convex patch nor a cut between two
patches covers, is certified without refining it down to the size of the
distance divided by the faces' dihedral angles.

Rounding. A side value ``s`` is computed within ``err``; corners within ``err``
of a half-plane count on both sides. A computed crossing point is within
``2 * err * |ab| / |s_a - s_b|`` of the true one (the distance is 1-Lipschitz, so
that shift goes into its bound); a crossing next to a corner whose side is
unsettled is that corner's bound plus the same kind of shift. An edge unsettled
at both ends has its two corners evaluated, which dominates any point between
them. Units are those of the mesh coordinates.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .planarpatches import ConvexPatches

#: Stars with more spokes than this are not used (their wedges would make every piece's arrays wide).
MAX_SPOKES = 24
#: Clusters with more vertices than this are not used.
MAX_CLUSTER = 32
#: Convex sets tried per wedge.
CANDIDATES = 4
#: A wedge must be narrower than pi by this much (radians) to count as convex without doubt.
_WEDGE_MARGIN = 1e-6
#: The axis must cross a piece's plane at least this steeply (cosine) for its piercing point to be well placed.
_MIN_AXIS_COSINE = 0.1

_EPS = float(np.finfo(np.float64).eps)


class VertexStars:
    """The wedges around every vertex (or cluster of vertices) of a mesh, over its convex patches.

    ``row[v]`` is the star of vertex v in the padded ``(k, MAX_SPOKES)`` tables,
    -1 when it has none; a wedge's candidate patches are -1 where padded.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, patches: ConvexPatches,
                 cluster_edge: float) -> None:
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        self.patches = patches
        n_v = len(v)
        tri = v[f]
        area_normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        u = f.ravel()
        w = f[:, [1, 2, 0]].ravel()
        face = np.repeat(np.arange(len(f)), 3)
        short = np.linalg.norm(v[u] - v[w], axis=1) <= cluster_edge
        graph = coo_matrix((np.ones(int(short.sum())), (u[short], w[short])), shape=(n_v, n_v))
        _, cluster = connected_components(graph, directed=False)
        size = np.bincount(cluster)
        centre = np.zeros((len(size), 3))
        np.add.at(centre, cluster, v)
        centre /= size[:, None]
        axis = np.zeros((len(size), 3))
        np.add.at(axis, cluster[f].ravel(), np.repeat(area_normal, 3, axis=0))
        # A triangle inside a cluster adds its normal once per corner; the axis only needs a direction.
        length = np.linalg.norm(axis, axis=1)
        good = (length > 0) & (size <= MAX_CLUSTER)
        axis = np.where(good[:, None], axis / np.where(length > 0, length, 1.0)[:, None], 0.0)
        # Spokes: half-edges from a cluster to a vertex outside it, both ways round each triangle edge.
        a = np.concatenate([u, w])
        b = np.concatenate([w, u])
        t = np.concatenate([face, face])
        out = (cluster[a] != cluster[b]) & good[cluster[a]]
        cl, far, patch = cluster[a[out]], b[out], patches.patch_of[t[out]]
        # One spoke per (cluster, far vertex), carrying the patches of all its triangles.
        key = cl * n_v + far
        order = np.lexsort((patch, key))
        key, cl, far, patch = key[order], cl[order], far[order], patch[order]
        fresh = np.r_[True, (key[1:] != key[:-1]) | (patch[1:] != patch[:-1])]
        key, cl, far, patch = key[fresh], cl[fresh], far[fresh], patch[fresh]
        first = np.r_[True, key[1:] != key[:-1]]
        spoke = np.cumsum(first) - 1
        slot = np.arange(len(key)) - np.flatnonzero(first)[spoke]
        n_s = int(first.sum())
        s_cl, s_far = cl[first], far[first]
        s_cand = np.full((n_s, CANDIDATES), -1, dtype=np.int64)
        fits = slot < CANDIDATES
        s_cand[spoke[fits], slot[fits]] = patch[fits]
        d = v[s_far] - centre[s_cl]
        n = axis[s_cl]
        d -= np.einsum("ij,ij->i", d, n)[:, None] * n
        e1 = np.cross(n, np.where(np.abs(n[:, :1]) < 0.6, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]))
        e1 /= np.maximum(np.linalg.norm(e1, axis=1), 1e-300)[:, None]
        angle = np.arctan2(np.einsum("ij,ij->i", d, np.cross(n, e1)), np.einsum("ij,ij->i", d, e1))
        radial = np.linalg.norm(d, axis=1)
        order = np.lexsort((angle, s_cl))
        s_cl, angle, radial, d, s_cand = s_cl[order], angle[order], radial[order], d[order], s_cand[order]
        starts = np.flatnonzero(np.r_[True, s_cl[1:] != s_cl[:-1]])
        counts = np.diff(np.r_[starts, len(s_cl)])
        group = np.repeat(np.arange(len(starts)), counts)
        pos = np.arange(len(s_cl)) - starts[group]
        nxt = np.where(pos + 1 < counts[group], np.arange(len(s_cl)) + 1, starts[group])
        gap = np.mod(angle[nxt] - angle, 2 * np.pi)
        gap = np.where(counts[group] == 1, 2 * np.pi, gap)
        spoke_ok = (radial > 0) & (gap < np.pi - _WEDGE_MARGIN)
        star_ok = (np.bincount(group, weights=spoke_ok, minlength=len(starts)) == counts) & (counts >= 3) \
            & (counts <= MAX_SPOKES)
        ids = s_cl[starts[star_ok]]
        k = len(ids)
        star_of_cluster = np.full(len(size), -1, dtype=np.int64)
        star_of_cluster[ids] = np.arange(k)
        self.row = star_of_cluster[cluster]
        self.origin = centre[ids]
        self.axis = axis[ids]
        self.cand = np.full((k, MAX_SPOKES, CANDIDATES), -1, dtype=np.int64)
        self.lo = np.zeros((k, MAX_SPOKES, 3))
        self.hi = np.zeros((k, MAX_SPOKES, 3))
        keep = star_ok[group]
        rows = star_of_cluster[s_cl[keep]]
        m = np.cross(axis[s_cl], d)
        m /= np.where(radial > 0, radial, 1.0)[:, None]
        # Wedge i runs from spoke i to the next; its candidates are the patches both spokes touch, else each's.
        self.lo[rows, pos[keep]] = m[keep]
        self.hi[rows, pos[keep]] = m[nxt[keep]]
        self.cand[rows, pos[keep]] = _wedge_candidates(s_cand[keep], s_cand[nxt[keep]])

    def bound(self, corners: np.ndarray, vertex: np.ndarray) -> np.ndarray:
        """Upper bound of ``sup_{x in P} d(x, mesh)`` for each triangle piece P (``(p, 3, 3)`` corners).

        ``vertex`` names, for each piece, the vertex whose star to use. Pieces
        whose vertex has no star, or whose plane the axis crosses too
        obliquely, get ``inf``.
        """
        out = np.full(len(corners), np.inf)
        if not len(self.origin):
            return out
        row = self.row[vertex]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        nlen = np.linalg.norm(normal, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = np.abs(np.einsum("ij,ij->i", normal, self.axis[np.maximum(row, 0)])) / nlen
        use = np.flatnonzero((row >= 0) & (nlen > 0) & (cosine >= _MIN_AXIS_COSINE))
        if not len(use):
            return out
        c, r = corners[use], row[use]
        o, n, cand = self.origin[r], self.axis[r], self.cand[r]
        valid = cand[:, :, 0] >= 0
        rel = c - o[:, None]
        s_lo = np.einsum("pci,pki->pck", rel, self.lo[r])
        s_hi = np.einsum("pci,pki->pck", rel, self.hi[r])
        scale = np.abs(c).max(axis=(1, 2)) + np.abs(o).max(axis=1)
        err = 8.0 * _EPS * (scale + np.maximum(np.abs(s_lo).max(axis=(1, 2)), np.abs(s_hi).max(axis=(1, 2))))
        pts, pk, shift = [], [], []

        def add(mask: np.ndarray, points: np.ndarray, extra: np.ndarray) -> None:
            """Evaluate points in wedge k where ``mask[p, j, k]``, adding ``extra[p, j, k]``.

            ``points`` is ``(p, j, k, 3)``, or ``(p, j, 3)`` for the same point in every wedge.
            """
            pp, jj, kk = np.nonzero(mask & valid[:, None, :])
            pts.append(points[pp, jj, kk] if points.ndim == 4 else points[pp, jj])
            pk.append(np.column_stack([pp, kk]))
            shift.append(np.broadcast_to(extra, mask.shape)[pp, jj, kk])

        tol = err[:, None]
        add((s_lo >= -tol[:, None]) & (s_hi <= tol[:, None]), c, np.zeros(s_lo.shape))
        for a, b in ((0, 1), (1, 2), (2, 0)):
            length = np.linalg.norm(c[:, b] - c[:, a], axis=1)[:, None]
            # A crossing of a wedge's lower half-plane must lie on the inner side of its upper one, and back.
            for s, other, sign in ((s_lo, s_hi, 1.0), (s_hi, s_lo, -1.0)):
                sa, sb = s[:, a], s[:, b]
                set_a, set_b = np.abs(sa) > tol, np.abs(sb) > tol
                cross = set_a & set_b & (np.sign(sa) != np.sign(sb))
                with np.errstate(invalid="ignore", divide="ignore"):
                    t = np.where(cross, sa / (sa - sb), 0.0)
                    moved = np.where(cross, 2.0 * tol * length / np.abs(sa - sb), 0.0)
                x = c[:, a, None] + t[..., None] * (c[:, b] - c[:, a])[:, None]
                o_x = other[:, a] + t * (other[:, b] - other[:, a])
                add((cross & (sign * o_x <= tol + moved))[:, None], x[:, None], moved[:, None])
                for end, s_far, settled_far in ((a, sb, set_b), (b, sa, set_a)):
                    near = (np.abs(s[:, end]) <= tol) & settled_far
                    with np.errstate(invalid="ignore", divide="ignore"):
                        hug = np.where(near, 2.0 * tol * length / np.maximum(np.abs(s_far) - 2.0 * tol, 0.0), 0.0)
                    add((near & (sign * other[:, end] <= tol + hug))[:, None], c[:, end][:, None], hug[:, None])
                both = (~set_a & ~set_b)[:, None]
                add(both, c[:, a][:, None], np.zeros(both.shape))
                add(both, c[:, b][:, None], np.zeros(both.shape))
        # The axis pierces the piece's plane at o + u n: a vertex of every wedge's part when inside P.
        pn = normal[use] / nlen[use][:, None]
        u = np.einsum("ij,ij->i", c[:, 0] - o, pn) / np.einsum("ij,ij->i", n, pn)
        y = o + u[:, None] * n
        pierced = (_barycentric(c, y) >= -1e-9).all(axis=1)
        y_shift = 16.0 * _EPS * (scale + np.abs(u)) / _MIN_AXIS_COSINE
        add(np.broadcast_to(pierced[:, None, None], (len(use), 1, valid.shape[1])), y[:, None], y_shift[:, None, None])
        p_all, pk_all, extra = np.concatenate(pts), np.concatenate(pk), np.concatenate(shift)
        # Every point against each of its wedge's candidate patches.
        wedge_cand = cand[pk_all[:, 0], pk_all[:, 1]]
        qi, ci = np.nonzero(wedge_cand >= 0)
        patch = wedge_cand[qi, ci]
        d = self.patches.distance(p_all[qi], patch) + self.patches.slack[patch] + extra[qi]
        best = np.zeros(cand.shape)
        np.maximum.at(best, (pk_all[qi, 0], pk_all[qi, 1], ci), d)
        best[cand < 0] = np.inf
        per_wedge = np.where(valid, best.min(axis=2), 0.0)
        out[use] = per_wedge.max(axis=1)
        return out


def _wedge_candidates(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """``(k, CANDIDATES)`` patches for wedges between spokes touching ``left`` and ``right`` patches (-1 padded).

    The patches on both spokes come first (the face spanning the wedge), then the others alternately.
    """
    both = (left[:, :, None] == right[:, None, :]).any(axis=2) & (left >= 0)
    rest_r = ~(right[:, :, None] == left[:, None, :]).any(axis=2) & (right >= 0)
    rest_l = ~both & (left >= 0)
    pool = np.concatenate([np.where(both, left, -1), np.where(rest_l, left, -1), np.where(rest_r, right, -1)], axis=1)
    # Stable sort of "is padding" keeps the order: shared, then left-only, then right-only.
    order = np.argsort(pool < 0, axis=1, kind="stable")
    return np.take_along_axis(pool, order, axis=1)[:, :CANDIDATES]


def _barycentric(c: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of points y in the planes of triangles c (``(p, 3, 3)``)."""
    e0, e1, w = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0], y - c[:, 0]
    d00 = np.einsum("ij,ij->i", e0, e0)
    d01 = np.einsum("ij,ij->i", e0, e1)
    d11 = np.einsum("ij,ij->i", e1, e1)
    d20 = np.einsum("ij,ij->i", w, e0)
    d21 = np.einsum("ij,ij->i", w, e1)
    den = d00 * d11 - d01 * d01
    with np.errstate(invalid="ignore", divide="ignore"):
        b1 = (d11 * d20 - d01 * d21) / den
        b2 = (d00 * d21 - d01 * d20) / den
        # Degenerate triangles give NaN coordinates, which no inside test accepts.
        return np.column_stack([1.0 - b1 - b2, b1, b2])
