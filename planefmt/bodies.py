"""Bodies of a mesh and the part groups chosen for each: convex, solid decomposition, or patches.

A *body* is an edge-connected set of triangles. Each is encoded on its own
(touching bodies stay separate, so coincident faces of two bodies survive):

* closed, outward and convex: one ``CONVEX`` group (the convex codec's, see
  :mod:`planefmt.codec`; here only recognised);
* closed and outward (edge-manifold, consistently oriented, positive
  volume): a BSP tree on its own face planes (:mod:`planefmt.solids`). The
  encoder decodes it and accepts it only if the surface is a closed
  2-manifold with the source's Euler characteristic and volume and every
  vertex within the target distance; otherwise it tries two more splitter
  seeds, then the same planes with the faces' exact ones where the decoded
  surface strayed (:func:`_mixed_solid`), then exact planes throughout, then
  a ``SEALED`` group (:mod:`planefmt.sealed`: the source's connectivity,
  each vertex where three planes meet), then falls back to patches;
* anything else (open, non-manifold, inside-out, soup): pseudo-convex and
  pseudo-concave patches (:mod:`planefmt.patches`), each verified.

Lengths in model units unless a name says *relative* (a fraction of the
bounding-box diagonal). Planes ``(omega, h)``: outward unit normals, inside
where ``omega . x <= h``.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import QhullError

from .errors import GeometryError
from .halfspace import intersect
from .hausdorff import hausdorff
from .model import GroupKind
from .patches import Patch, PatchReport, PlaneTable, decode_patch_faces, encode_patches
from .planes import from_triplets, to_triplets
from .polygonize import COPLANAR_TOLERANCE, edge_adjacency, polygonize
from .repair import merge_close_vertices
from .sealed import decode_sealed, encode_sealed
from .solids import STRATEGIES, Partition, Splitter, TreeSurface, decode_tree, partition
from .trianglegeom import TriangleIndex

#: Splitter seeds tried before a closed body falls back to patches.
SEEDS = (0, 1, 2)
#: Pieces the certified distance of an exact decoding may take at encoding (about 10 s).
EXACT_CERTIFY_PIECES = 250_000
#: Coplanarity of the planes a closed body's second BSP attempt uses (fraction of the diagonal):
#: float64 rounding of the faces' own planes, far below any tolerance.
EXACT_COPLANAR = 1e-12
#: Rounds of :func:`encode_body`'s mixed plane set (exact planes in place of merged ones where a
#: tree strayed) before the all-exact one.
MIXED_ROUNDS = 4
#: Volume agreement required of a decoded solid (relative).
VOLUME_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Group:
    """A part group over a :class:`PlaneTable`: ``refs`` indices, ``bounding`` roles, ``tree`` tokens,
    a sealed group's ``vertex_planes`` and ``facets`` (local references, spec §9.9)."""

    kind: GroupKind
    refs: np.ndarray
    bounding: np.ndarray
    tree: np.ndarray | None = None
    triangles: int = 0  # source triangles it covers
    vertex_planes: np.ndarray | None = None
    facets: np.ndarray | None = None
    splitter: Splitter | None = None  # the strategy that built a BSP tree (encoder only)


@dataclass
class BodyReport:
    """How one body was encoded: ``kind`` chosen ("convex", "solid", "patches"), why, and numbers."""

    kind: str
    triangles: int
    groups: int
    note: str = ""
    error: float = 0.0  # verified bound, model units (vertex screen for solids)
    seconds: float = 0.0
    details: dict = field(default_factory=dict)
    #: Table planes next to where the first refused tree with a closed surface strayed beyond the
    #: target (:func:`encode_solid`).
    stray: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))


def body_labels(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """Components of faces connected through manifold edges.

    Only an edge shared by exactly two faces, running opposite ways, joins
    them: two solids touching along an edge (sharing vertices there) fall
    apart into two closed bodies. (Solids sharing a whole face fall apart
    into open pieces instead; :func:`encode_body` uses the split only when
    every part is closed.)
    """
    f = np.asarray(faces, dtype=np.int64)
    m = len(f)
    start = f.reshape(-1)
    end = f[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(start, end) * np.int64(vertex_count) + np.maximum(start, end)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    first = np.r_[True, ks[1:] != ks[:-1]]
    count = np.diff(np.r_[np.flatnonzero(first), len(ks)])
    two = np.flatnonzero(first)[count == 2]
    a, b = order[two], order[two + 1]
    opposite = (start[a] == end[b]) & (end[a] == start[b])
    a, b = a[opposite], b[opposite]
    g = coo_matrix((np.ones(len(a), dtype=np.int8), (a // 3, b // 3)), shape=(m, m))
    return connected_components(g, directed=False)[1]


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by triangles (model units cubed; positive for outward, closed surfaces)."""
    p = vertices[faces]
    c = p.reshape(-1, 3).mean(axis=0)
    p = p - c
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum()) / 6.0


def euler_characteristic(faces: np.ndarray) -> int:
    """``V - E + F`` of a triangle mesh (vertices counted as used)."""
    e = np.sort(np.column_stack([faces.reshape(-1), faces[:, [1, 2, 0]].reshape(-1)]), axis=1)
    return len(np.unique(faces)) - len(np.unique(e, axis=0)) + len(faces)


def is_closed_manifold(faces: np.ndarray, vertex_count: int) -> bool:
    """Every edge shared by exactly two faces running opposite ways."""
    return bool(len(faces)) and edge_adjacency(faces, vertex_count).closed


def plane_positions(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, omega: np.ndarray,
                    h: np.ndarray) -> tuple[np.ndarray, float]:
    """Vertices moved onto the planes of their faces, and the largest remaining residual.

    Each vertex takes the least-squares point of its incident planes closest
    to where it is (eigen-directions the planes do not constrain are left
    alone). This is where the decoder puts it, so the BSP is built on the
    geometry the planes describe, with every fragment on its plane.
    """
    ok = face_plane >= 0
    vi = faces[ok].reshape(-1)
    pi = np.repeat(face_plane[ok], 3)
    inc = np.unique(np.column_stack([vi, pi]), axis=0)
    vi, pi = inc[:, 0], inc[:, 1]
    w = omega[pi]
    r = h[pi] - np.einsum("ij,ij->i", w, vertices[vi])
    a = np.zeros((len(vertices), 3, 3))
    np.add.at(a, vi, w[:, :, None] * w[:, None, :])
    b = np.zeros((len(vertices), 3))
    np.add.at(b, vi, w * r[:, None])
    lam, vec = np.linalg.eigh(a)
    inv = np.where(lam > 1e-12, 1.0 / np.where(lam > 1e-12, lam, 1.0), 0.0)
    x = vertices + np.einsum("nij,nj,nkj,nk->ni", vec, inv, vec, b)
    res = np.abs(np.einsum("ij,ij->i", omega[pi], x[vi]) - h[pi])
    return x, float(res.max(initial=0.0))


def reflex_planes(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, omega: np.ndarray,
                  h: np.ndarray, tol: float) -> np.ndarray:
    """Planes with a concave edge: the far vertex of a neighbour lies outside them by more than ``tol``."""
    out = np.zeros(len(h), dtype=bool)
    edges = edge_adjacency(faces, len(vertices))
    ta, sa = np.divmod(edges.a, 3)
    tb, sb = np.divmod(edges.b, 3)
    for t1, t2, s2 in ((ta, tb, sb), (tb, ta, sa)):
        far = faces[t2, (s2 + 2) % 3]
        pl = face_plane[t1]
        ok = pl >= 0
        d = np.einsum("ij,ij->i", omega[pl[ok]], vertices[far[ok]]) - h[pl[ok]]
        out[pl[ok][d > tol]] = True
    return out


def exact_planes(vertices: np.ndarray, faces: np.ndarray, table: PlaneTable) -> np.ndarray:
    """Each face's plane in a polygonization that merges only coplanar faces (within
    :data:`EXACT_COPLANAR` of the diagonal), added to ``table``; -1 for faces of no area."""
    poly = polygonize(vertices, faces, tolerance=EXACT_COPLANAR)
    index = table.extend(poly.omega, poly.h)
    return np.where(poly.face_plane >= 0, index[np.maximum(poly.face_plane, 0)], -1)


def encode_solid(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, omega: np.ndarray,
                 h: np.ndarray, target: float, report: BodyReport, seeds: tuple[int, ...] = SEEDS,
                 splitters: tuple[Splitter, ...] = STRATEGIES) -> Group | None:
    """A BSP group of a closed outward body, verified; None (reason in ``report.note``) if none passes.

    ``face_plane`` indexes ``omega``, ``h`` (the table's planes); ``target``
    (model units) bounds the vertex distances checked both ways; ``seeds``
    the splitter seeds tried in turn; ``splitters`` the splitter strategies
    (:func:`_trees`). The planes where the first refused
    closed surface strays beyond the target are left in ``report.stray``.
    """
    live = face_plane >= 0
    f = faces[live]
    fp = face_plane[live]
    diag = float(np.linalg.norm(np.ptp(vertices[f].reshape(-1, 3), axis=0)))
    x, rmax = plane_positions(vertices, f, fp, omega, h)
    scale = float(np.abs(x[np.unique(f)]).max())
    eps = max(1e-14 * diag, 4.0 * rmax, 64.0 * np.finfo(np.float64).eps * scale)
    reflex = reflex_planes(x, f, fp, omega, h, eps)
    volume = signed_volume(vertices, faces)
    chi = euler_characteristic(faces)
    source = TriangleIndex(vertices, faces)
    reasons = []
    report.stray = np.zeros(0, dtype=np.int64)
    for seed, part in _trees(omega, h, x[f], fp, eps, reflex, seeds, splitters, reasons):
        base = part.strategy == splitters[0]
        label = f"seed {seed}" if base else f"seed {seed}, strategy {part.strategy}"
        try:
            used, local = np.unique(part.tokens[part.tokens <= np.uint32(0xFFFFFFEF)], return_inverse=True)
            tokens = part.tokens.copy()
            tokens[part.tokens <= np.uint32(0xFFFFFFEF)] = local.astype(np.uint32)
            # Decoded from the planes as a float64 file holds them, (nu, phi, h): the surface a reader makes.
            w, c = from_triplets(to_triplets(omega[used], h[used]))
            surface = TreeSurface(w, c, tokens, np.ones(len(used), dtype=bool))
            dv, dt, dplane = surface.rounded
            # The decoder's exact last resort doubles the time a failing tree takes: tried for the
            # first seed's tree of each plane set only (a tree it would close may then be refused,
            # never one accepted that a reader decodes otherwise).
            exact = base and seed == seeds[0] and not surface.closed
            if exact:
                dv, dt, dplane = surface.exact() or surface.rounded
        except GeometryError as err:
            reasons.append(f"{label}: {err.reason}")
            continue
        except (ArithmeticError, ValueError, np.linalg.LinAlgError, QhullError) as err:
            # What a file's decoder would report as DEGENERATE_GEOMETRY (codec.decode_group): not
            # this tree.
            reasons.append(f"{label}: the tree does not decode ({type(err).__name__}: {err})")
            continue
        why = _check_solid(vertices, faces, dv, dt, volume, chi, source, target)
        if why is not None and base and not len(report.stray) and is_closed_manifold(dt, len(dv)):
            report.stray = _stray_planes(vertices, faces, face_plane, dv, dt, used[dplane], source, target)
        if why is None and exact:
            why = _certify(vertices, faces, dv, dt, target)
        report.details[label.replace(" ", "")] = {"splits": part.splits, "pieces": part.pieces,
                                                   "tokens": len(tokens), "check": why or "ok"}
        if why is None:
            report.error = _vertex_screen(vertices, faces, dv, dt, source)
            report.details["tokens"] = len(tokens)
            return Group(GroupKind.BSP, used.astype(np.int64), np.zeros(len(used), dtype=bool), tokens,
                         triangles=len(faces), splitter=part.strategy)
        reasons.append(f"{label}: {why}")
    report.note = "; ".join(reasons)
    return None


def _trees(omega: np.ndarray, h: np.ndarray, tri: np.ndarray, tri_plane: np.ndarray, eps: float,
           reflex: np.ndarray, seeds: tuple[int, ...], splitters: tuple[Splitter, ...],
           reasons: list[str]) -> Iterator[tuple[int, Partition]]:
    """(seed, tree) in the order :func:`encode_solid` tries them: first the smallest tree of the
    first seed's other ``splitters`` where it is smaller than that seed's tree of the first
    splitter, then each seed's tree of the first splitter. A tree that fails
    only costs one more check, and the fallbacks (other seeds, the mixed and exact plane sets,
    which follow the planes the first strategy's tree strayed on) are those of that strategy alone.
    A partition that fails is skipped, its reason appended to ``reasons``."""
    for seed in seeds:
        try:
            base = partition(omega, h, tri, tri_plane, eps, reflex, seed=seed, strategy=splitters[0])
        except GeometryError as err:
            reasons.append(f"seed {seed}: {err.reason}")
            continue
        if seed == seeds[0] and len(splitters) > 1:
            others = []
            for strategy in splitters[1:]:
                try:
                    others.append(partition(omega, h, tri, tri_plane, eps, reflex, seed=seed, strategy=strategy))
                except GeometryError as err:
                    reasons.append(f"seed {seed}, strategy {strategy}: {err.reason}")
            best = min(others, key=lambda p: len(p.tokens), default=None)
            if best is not None and len(best.tokens) < len(base.tokens):
                yield seed, best
        yield seed, base


def _check_solid(vertices: np.ndarray, faces: np.ndarray, dv: np.ndarray, dt: np.ndarray, volume: float,
                 chi: int, source: TriangleIndex, target: float) -> str | None:
    """Why a decoded solid is not acceptable, or None."""
    if not is_closed_manifold(dt, len(dv)):
        return "decoded surface not a closed 2-manifold"
    got = euler_characteristic(dt)
    if got != chi:
        return f"Euler characteristic {got}, source {chi}"
    vol = signed_volume(dv, dt)
    if not abs(vol - volume) <= VOLUME_TOLERANCE * abs(volume):
        return f"volume off by {abs(vol - volume) / abs(volume):.2g} (relative)"
    err = _vertex_screen(vertices, faces, dv, dt, source)
    if not err <= target:
        return f"a vertex {err:.3g} from the other surface (target {target:.3g})"
    return None


def _stray_planes(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, dv: np.ndarray,
                  dt: np.ndarray, dt_plane: np.ndarray, source: TriangleIndex, target: float) -> np.ndarray:
    """Table planes next to where a decoded surface strays beyond ``target``: those of decoded
    triangles (planes ``dt_plane``) at decoded vertices beyond it from the source, and of source
    faces at source vertices beyond it from the decoded surface."""
    far_d = np.zeros(len(dv), dtype=bool)
    at = np.unique(dt)
    far_d[at[source.query(dv[at])[0] > target]] = True
    far_s = np.zeros(len(vertices), dtype=bool)
    at = np.unique(faces)
    far_s[at[TriangleIndex(dv, dt).query(vertices[at])[0] > target]] = True
    return np.unique(np.concatenate([dt_plane[far_d[dt].any(axis=1)], face_plane[far_s[faces].any(axis=1)]]))


def _certify(vertices: np.ndarray, faces: np.ndarray, dv: np.ndarray, dt: np.ndarray, target: float) -> str | None:
    """Why an exact decoding is refused: its distance to the source not certified within ``target``
    in ``EXACT_CERTIFY_PIECES``, or None.

    An exact surface keeps what rounding cannot see (facets 1e-10 across where planes nearly
    meet); the certified bound can need more pieces around those than the codec's verification
    allows (angle_block.STL: not within 8 million), and a body refused here is stored as patches.
    """
    r = hausdorff(dv, dt, vertices, faces, target=target, max_pieces=EXACT_CERTIFY_PIECES)
    return None if r.upper <= target else (f"exact surface not certified within {target:.3g} in "
                                           f"{EXACT_CERTIFY_PIECES:,} pieces (bound {r.upper:.3g})")


def _vertex_screen(vertices: np.ndarray, faces: np.ndarray, dv: np.ndarray, dt: np.ndarray,
                   source: TriangleIndex) -> float:
    """Largest exact distance of a decoded vertex to the source and of a source vertex to the decoded surface.

    A lower bound of the Hausdorff distance that catches every structural
    error; the certified bound is measured on the whole mesh by the codec.
    """
    d1, _ = source.query(dv[np.unique(dt)])
    d2, _ = TriangleIndex(dv, dt).query(vertices[np.unique(faces)])
    return float(max(d1.max(initial=0.0), d2.max(initial=0.0)))


def encode_open(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, drift: np.ndarray,
                table: PlaneTable, target: float) -> tuple[list[Group], PatchReport]:
    """Verified patch groups of any body (see :mod:`planefmt.patches`)."""
    patches, rep = encode_patches(vertices, faces, face_plane, drift, table, target)
    return [_patch_group(p) for p in patches], rep


def _patch_group(p: Patch) -> Group:
    kind = GroupKind.PSEUDO_CONVEX if p.kind == 3 else GroupKind.PSEUDO_CONCAVE
    return Group(kind, p.refs, p.bounding, triangles=len(p.triangles))


def is_convex_body(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, omega: np.ndarray,
                   h: np.ndarray, tol: float) -> bool:
    """Closed, outward, and every vertex inside every face plane (within ``tol`` plus nothing else)."""
    if not is_closed_manifold(faces, len(vertices)) or not signed_volume(vertices, faces) > 0:
        return False
    planes = np.unique(face_plane[face_plane >= 0])
    pts = vertices[np.unique(faces)]
    for lo in range(0, len(planes), 1024):
        sel = planes[lo:lo + 1024]
        if (omega[sel] @ pts.T - h[sel][:, None] > tol).any():
            return False
    return True


def encode_body(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, drift: np.ndarray,
                table: PlaneTable, target: float, splitters: tuple[Splitter, ...] = STRATEGIES
                ) -> tuple[list[Group], BodyReport]:
    """The part groups of one body: convex, BSP solid, or patches (see the module docstring).

    ``vertices``, ``faces`` of this body; ``face_plane`` indexes ``table``'s
    input planes; ``drift`` (per input plane) the fitting drift; ``target``
    the error bound to meet (model units); ``splitters`` the BSP splitter
    strategies (:data:`~planefmt.solids.STRATEGIES` or
    :data:`~planefmt.solids.FLAT_STRATEGIES`).
    """
    labels = body_labels(faces, len(vertices))
    parts = [labels == b for b in range(int(labels.max(initial=0)) + 1)]
    if len(parts) > 1 and all(is_closed_manifold(faces[p], len(vertices)) for p in parts):
        # Closed bodies joined only at non-manifold edges (touching solids sharing vertices): each
        # on its own, one report for all.
        groups: list[Group] = []
        reports = []
        for sel in parts:
            g, r = encode_body(vertices, faces[sel], face_plane[sel], drift, table, target, splitters)
            groups += g
            reports.append(r)
        kinds = sorted({r.kind for r in reports})
        merged = BodyReport(kind="+".join(kinds), triangles=len(faces), groups=len(groups),
                            note=f"{len(reports)} manifold parts", error=max(r.error for r in reports),
                            seconds=sum(r.seconds for r in reports),
                            details={"parts": [(r.kind, r.note, r.details) for r in reports]})
        return groups, merged
    start = time.perf_counter()
    omega, h = table.arrays()
    live = face_plane >= 0
    report = BodyReport(kind="patches", triangles=len(faces), groups=0)
    if live.any() and is_convex_body(vertices, faces, face_plane, omega, h, target):
        refs = np.unique(face_plane[live])
        report.kind = "convex"
        groups = [Group(GroupKind.CONVEX, refs, np.zeros(len(refs), dtype=bool), triangles=len(faces))]
    else:
        groups = []
        closed = is_closed_manifold(faces, len(vertices))
        inside_out = closed and not signed_volume(vertices, faces) > 0
        if closed and not inside_out:
            solid = encode_solid(vertices, faces, face_plane, omega[:table.base], h[:table.base], target, report,
                                 splitters=splitters)
            if solid is None:
                # Merged planes pass near, not through, their vertices: where many meet (smooth
                # surfaces), or nearly parallel ones meet, the cells' corners stray or leave
                # cracks. Planes of exactly coplanar faces only pass through them all.
                first = report.note
                exact = exact_planes(vertices, faces, table)
                solid = _mixed_solid(vertices, faces, face_plane, exact, table, target, report, splitters)
                if solid is None:
                    mixed = report.note
                    solid = encode_solid(vertices, faces, exact, *table.arrays(), target, report,
                                         splitters=splitters)
                    report.note = (f"{first}; {mixed}exact planes: {report.note}" if solid is None
                                   else "exact planes")
            if solid is not None:
                report.kind = "solid"
            else:
                solid = _sealed_group(vertices, faces, face_plane, table, target, report)
            if solid is not None:
                groups = [solid]
        else:
            report.note = "inside-out" if inside_out else "open or non-manifold"
        if not groups:
            groups, rep = encode_open(vertices, faces, face_plane, drift, table, target)
            report.error = rep.error
            report.details.update(convex=rep.convex, concave=rep.concave, splits=rep.splits, edges=rep.planes)
            if inside_out:
                # Patches of a closed surface facing inwards close only where one polytope holds
                # them all (a cube); its triangles and connectivity always do.
                dv, dt = decode_groups(*table.arrays(), groups)
                why = _check_solid(vertices, faces, dv, dt, signed_volume(vertices, faces),
                                   euler_characteristic(faces), TriangleIndex(vertices, faces), target)
                if why is not None:
                    report.note += f"; patches: {why}"
                    sealed = _sealed_group(vertices, faces, face_plane, table, target, report)
                    groups = groups if sealed is None else [sealed]
    report.groups = len(groups)
    report.seconds = time.perf_counter() - start
    return groups, report


def _sealed_group(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, table: PlaneTable,
                  target: float, report: BodyReport) -> Group | None:
    """A closed body no BSP tree decodes faithfully as a ``SEALED`` group (:mod:`planefmt.sealed`),
    checked as a solid; None (reason appended to ``report.note``) if it fails.

    Its vertices move at most half the ``target`` (model units), which bounds the two-sided
    Hausdorff distance (corresponding points of corresponding triangles are no farther apart
    than their corners), and its connectivity is the source's.
    """
    sealed = encode_sealed(vertices, faces, face_plane, table, target / 2)
    refs = np.unique(np.concatenate([sealed.facets[:, 0], sealed.vertex_planes.reshape(-1)]))
    omega, h = table.arrays()
    dv, dt = decode_sealed(omega, h, sealed.vertex_planes, sealed.facets)
    why = _check_solid(vertices, faces, dv, dt, signed_volume(vertices, faces), euler_characteristic(faces),
                       TriangleIndex(vertices, faces), target)
    if why is not None:
        report.note += f"; sealed: {why}"
        return None
    report.kind = "sealed"
    report.note += f"; sealed ({len(sealed.added)} vertex planes for {len(sealed.vertex_planes)} vertices)"
    report.error = sealed.error
    report.details.update(vertices=len(sealed.vertex_planes), **{"vertex planes": len(sealed.added)})
    local = np.searchsorted(refs, sealed.facets[:, 0])
    facets = np.column_stack([local, sealed.facets[:, 1:]])
    return Group(GroupKind.SEALED, refs, ~np.isin(refs, sealed.facets[:, 0]), triangles=len(faces),
                 vertex_planes=np.searchsorted(refs, sealed.vertex_planes), facets=facets)


def _mixed_solid(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, exact: np.ndarray,
                 table: PlaneTable, target: float, report: BodyReport,
                 splitters: tuple[Splitter, ...] = STRATEGIES) -> Group | None:
    """A solid on the merged planes ``face_plane`` but, where the merged tree strayed, the faces'
    ``exact`` planes; None if :data:`MIXED_ROUNDS` rounds of replacing do not give one.

    A merged plane passes within the tolerance of its vertices, but where it meets a plane at a
    grazing angle their edge moves by that distance over the angle's sine (angle_block.STL at
    1e-6: a corner 1.9e-5 off for a target of 2.2e-6). Replacing only those planes keeps the
    merged planes' fewer, wider faces elsewhere. When no round passes, ``report.note`` holds
    their reasons as ``"mixed planes: ...; "``, the caller's to prefix (empty when none was tried).
    """
    fp = face_plane
    reasons = []
    for _ in range(MIXED_ROUNDS):
        swap = np.isin(fp, report.stray) & (fp != exact)
        if not swap.any():
            break
        fp = np.where(swap, exact, fp)
        solid = encode_solid(vertices, faces, fp, *table.arrays(), target, report, seeds=SEEDS[:1],
                             splitters=splitters)
        if solid is not None:
            report.details["exact faces"] = int((fp == exact).sum())
            report.note = f"mixed planes ({report.details['exact faces']} of {len(fp)} faces on exact ones)"
            return solid
        reasons.append(report.note)
    report.note = f"mixed planes: {' / '.join(reasons)}; " if reasons else ""
    return None


@dataclass(frozen=True)
class MeshGroups:
    """A mesh encoded as part groups: planes ``omega`` (n, 3), ``h`` (n,) (only those used, in
    first-use order), the groups over them, one report per body, and the source surface (after
    welding) the groups were verified against."""

    omega: np.ndarray
    h: np.ndarray
    groups: list[Group]
    reports: list[BodyReport]
    vertices: np.ndarray
    faces: np.ndarray


def encode_groups(vertices: np.ndarray, faces: np.ndarray, *, tolerance: float = 1e-6,
                  coplanar: float | None = None,
                  splitters: tuple[Splitter, ...] = STRATEGIES) -> MeshGroups:
    """Encode a triangle mesh body by body (module docstring); ``tolerance`` relative to the diagonal.

    Vertices closer than ``tolerance / 1000`` of the diagonal are welded
    first; planes come from :func:`planefmt.polygonize.polygonize` with
    ``coplanar`` (relative; default its own, capped at half the tolerance);
    ``splitters`` the BSP splitter strategies (:func:`encode_body`).
    One plane table serves all bodies, so planes shared by bodies (and the
    bounding planes patches share) are stored once.
    """
    v = np.asarray(vertices, dtype=np.float64)
    diag = float(np.linalg.norm(np.ptp(v[np.unique(faces)], axis=0)))
    v, f, _, _ = merge_close_vertices(v, faces, 1e-3 * tolerance * diag)
    # As the codec does: merging nearly coplanar triangles keeps the BSP free of thin wedges; where
    # a merged plane strays too far for a patch, the patch falls back to the triangle's own plane.
    poly = polygonize(v, f, tolerance=min(coplanar or COPLANAR_TOLERANCE, tolerance / 2))
    v, f = poly.vertices, poly.faces
    table = PlaneTable(poly.omega, poly.h)
    target = tolerance * poly.diagonal
    edges = edge_adjacency(f, len(v))
    m = len(f)
    labels = connected_components(coo_matrix((np.ones(len(edges.a), dtype=np.int8),
                                              (edges.a // 3, edges.b // 3)), shape=(m, m)), directed=False)[1]
    groups: list[Group] = []
    reports: list[BodyReport] = []
    for b in range(int(labels.max(initial=-1)) + 1):
        sel = np.flatnonzero(labels == b)
        g, r = encode_body(v, f[sel], poly.face_plane[sel], poly.distance, table, target, splitters)
        groups += g
        reports.append(r)
    omega, h = table.arrays()
    used = np.concatenate([g.refs for g in groups]) if groups else np.zeros(0, dtype=np.int64)
    _, first = np.unique(used, return_index=True)
    order = used[np.sort(first)]
    index = np.full(len(h), -1, dtype=np.int64)
    index[order] = np.arange(len(order))
    groups = [replace(g, refs=index[g.refs]) for g in groups]
    return MeshGroups(omega[order], h[order], groups, reports, v, f)


def decode_groups(omega: np.ndarray, h: np.ndarray, groups: list[Group]) -> tuple[np.ndarray, np.ndarray]:
    """Triangles ``(vertices, faces)`` of all groups; patches are decoded in one batch."""
    parts_v, parts_f = [], []
    patch = [g for g in groups if g.kind in (GroupKind.PSEUDO_CONVEX, GroupKind.PSEUDO_CONCAVE)]
    for g in groups:
        if g.kind == GroupKind.CONVEX:
            p = intersect(omega[g.refs], h[g.refs])
            parts_v.append(p.vertices)
            parts_f.append(p.triangles)
        elif g.kind == GroupKind.BSP:
            dv, dt, _ = decode_tree(omega[g.refs], h[g.refs], g.tree, ~g.bounding)
            parts_v.append(dv)
            parts_f.append(dt)
        elif g.kind == GroupKind.SEALED:
            dv, dt = decode_sealed(omega[g.refs], h[g.refs], g.vertex_planes, g.facets)
            parts_v.append(dv)
            parts_f.append(dt)
    if patch:
        refs = np.concatenate([g.refs for g in patch])
        owner = np.repeat(np.arange(len(patch)), [len(g.refs) for g in patch])
        face = ~np.concatenate([g.bounding for g in patch])
        concave = np.array([g.kind == GroupKind.PSEUDO_CONCAVE for g in patch])
        pv, pt, _, status = decode_patch_faces(omega[refs], h[refs], owner, len(patch), face, concave)
        if (status != 0).any():
            raise GeometryError(f"{int((status != 0).sum())} patch groups are empty or unbounded",
                                code="UNBOUNDED_POLYTOPE")
        parts_v.append(pv)
        parts_f.append(pt)
    offsets = np.cumsum([0] + [len(x) for x in parts_v[:-1]])
    return (np.concatenate(parts_v) if parts_v else np.zeros((0, 3)),
            np.concatenate([t + o for t, o in zip(parts_f, offsets)]).astype(np.int64) if parts_f
            else np.zeros((0, 3), dtype=np.int64))
