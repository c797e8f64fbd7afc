"""Verifying a decoding against its source: certified two-sided Hausdorff bounds
(:func:`_verify`, :func:`_measure`), from the corners alone for convex groups over convex bodies,
and the first-order prediction of where a coding moves the decoded vertices (:class:`_Incidences`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry.convexbound import convex_hausdorff
from ..geometry.halfspace import resolve_vertices
from ..geometry.hausdorff import DEFAULT_MAX_PIECES, closest_distance, hausdorff
from ..geometry.planes import from_triplets, transform_points
from ..model import GroupKind, Mesh
from .decoding import DecodedGroup, PlaneError, decode_groups
from .preparing import _Object


#: Attempts at a certified Hausdorff bound with a rising target (each 1.1x the last at least).
_MEASURE_STEPS = 64

#: A predicted vertex step larger than this many times its planes' offset from it is not trusted
#: (:meth:`_Incidences.moved`).
_STEP_LIMIT = 1e3

#: An incidence whose vertex is farther than this fraction of the largest |h| from its plane (in
#: the exact decoding) is not used to predict where the vertex goes.
_ON_PLANE = 1e-7


def _decode_object(triplets: np.ndarray, obj: _Object, error: PlaneError) -> list[DecodedGroup]:
    return decode_groups([(triplets[g.refs], g, i) for i, g in enumerate(obj.groups)], error)


def _peak(values: np.ndarray) -> float:
    return float(values.max(initial=0.0))


@dataclass(frozen=True)
class _Incidences:
    """An object's decoded vertices, all groups together, and the object-table planes they lie on."""

    vertices: np.ndarray
    inc_vertex: np.ndarray
    inc_plane: np.ndarray

    @staticmethod
    def of(decoded: list[DecodedGroup], obj: _Object) -> _Incidences:
        """From ``decoded``, the object's groups decoded from its exact planes. Incidences whose
        vertex is off its plane there (welded across a crack: octagonal_pocket.stl has 6 of 6,236,
        up to 0.27 of the diagonal off) would pull the vertex away; they are left out."""
        # One array for all groups: patch meshes have tens of thousands (bun_zipper.ply).
        offsets = np.cumsum([0] + [len(d.vertices) for d in decoded])
        empty = np.zeros(0, dtype=np.int64)
        vertices = np.concatenate([d.vertices for d in decoded]) if decoded else np.zeros((0, 3))
        inc_vertex = np.concatenate([d.inc_vertex + k for d, k in zip(decoded, offsets)] or [empty])
        inc_plane = np.concatenate([np.asarray(g.refs)[d.inc_ref] for d, g in zip(decoded, obj.groups)] or [empty])
        omega, h = from_triplets(obj.triplets)
        gap = np.abs(np.einsum("ij,ij->i", omega[inc_plane], vertices[inc_vertex]) - h[inc_plane])
        on = gap <= _ON_PLANE * float(np.abs(h).max(initial=1.0))
        return _Incidences(vertices=vertices, inc_vertex=inc_vertex[on], inc_plane=inc_plane[on])

    def moved(self, triplets: np.ndarray) -> tuple[np.ndarray, float]:
        """The vertices as the planes ``triplets`` would put them (model units), and the largest
        offset of those planes from a vertex whose step is not to be trusted.

        A vertex of nearly dependent planes can get a step thousands of times what its planes moved
        (octagonal_pocket.stl: 0.38 of the diagonal for planes moved 1e-6 at it, at every width):
        such a vertex keeps its place and counts with its planes' offset instead.
        """
        omega, h = from_triplets(triplets)
        out = resolve_vertices(self.vertices, self.inc_vertex, self.inc_plane, omega, h)
        gap = np.abs(np.einsum("ij,ij->i", omega[self.inc_plane], self.vertices[self.inc_vertex])
                     - h[self.inc_plane])
        offset = np.zeros(len(out))
        np.maximum.at(offset, self.inc_vertex, gap)
        wild = np.linalg.norm(out - self.vertices, axis=1) > _STEP_LIMIT * offset
        out[wild] = self.vertices[wild]
        return out, _peak(offset[wild])


def _verify(mesh: Mesh, obj: _Object, target: float, pieces: int,
            decoded: list[DecodedGroup] | None = None) -> tuple[float, float]:
    """``(upper, lower)``: certified bounds (world model units) of the two-sided Hausdorff distance to
    the source, refined until ``upper <= target`` or the decision is made; ``upper`` is infinity
    when it is not at most ``target``.

    Convex groups over convex source bodies (``decoded`` given) are bounded from their corners
    (:func:`planefmt.geometry.convexbound.convex_hausdorff`), group by group, without a search.
    """
    shift = _mended(obj)
    convex = _convex_bounds(decoded, obj) if decoded is not None else None
    if convex is not None:
        upper, lower = convex
    else:
        a = transform_points(mesh.vertices, obj.world)
        b = transform_points(obj.vertices, obj.world)
        r = hausdorff(a, mesh.faces, b, obj.faces, target=target - shift, max_pieces=pieces)
        upper, lower = float(r.upper), float(r.lower)
    upper += shift
    return (upper if upper <= target else math.inf), max(lower - shift, 0.0)


def _convex_bounds(decoded: list[DecodedGroup], obj: _Object) -> tuple[float, float] | None:
    """``(upper, lower)`` of the two-sided Hausdorff distance (world model units) of an object made
    of convex groups, each against its source body, or None where a group or body is not convex.

    The distance between the unions is at most the largest between a body and its own group's
    decoding: each is part of its union's surface."""
    groups = obj.groups
    if not groups or any(g.kind != GroupKind.CONVEX for g in groups):
        return None
    if len(groups) == 1 and groups[0].faces is None:
        sources = [obj.faces]
    elif all(g.faces is not None for g in groups):
        sources = [obj.faces[g.faces] for g in groups]
    else:
        return None
    upper = lower = 0.0
    b = transform_points(obj.vertices, obj.world)
    for d, faces in zip(decoded, sources):
        found = convex_hausdorff(transform_points(d.vertices, obj.world), d.triangles, b, faces)
        if found is None:
            return None
        upper, lower = max(upper, found[0]), max(lower, found[1])
    return upper, lower


def _mended(obj: _Object) -> float:
    """How far (world units) the source the decoding is measured against lies from the input."""
    return obj.mended * float(np.linalg.norm(obj.world[:3, :3], 2))


def _measure(mesh: Mesh, obj: _Object, target: float) -> float:
    """Certified upper bound (world model units) of the two-sided Hausdorff distance to the source,
    within about 10% of the distance.

    The target starts at 1.1 times the largest distance of a decoded vertex
    to the source (a lower bound of the distance) and is raised to 1.1 times
    the certified lower bound (which exceeds a failed target) until a bound
    is certified.
    """
    a = transform_points(mesh.vertices, obj.world)
    b = transform_points(obj.vertices, obj.world)
    shift = _mended(obj)
    target = max(target, 1.1 * float(closest_distance(a, b, obj.faces)[0].max(initial=0.0)))
    for _ in range(_MEASURE_STEPS):
        r = hausdorff(a, mesh.faces, b, obj.faces, target=target, max_pieces=DEFAULT_MAX_PIECES)
        if r.upper <= target:
            return float(r.upper) + shift
        target = 1.1 * max(target, float(r.lower))
    return float(r.upper) + shift
