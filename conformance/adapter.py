"""planefmt's side of the conformance contract: ``python -m conformance.adapter FILE``.

Prints one JSON object describing FILE and exits 0, or prints
``{"error": CODE}`` and exits 1 (README.md, "The contract"). Uses only
planefmt's public API: ``planefmt.open`` and the records it yields,
``Reader.group(k)`` for random access through the index, ``records.kinds_of``
for the kinds a file's version has, and, where it is installed, the
geometry decoder ``planefmt.codec``.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

import planefmt
from planefmt import UP_AXIS, GroupKind
from planefmt.container import records

#: Kinds whose summary has a volume (README.md): solids, and sealed surfaces, closed as a rule.
SOLID_KINDS = (GroupKind.CONVEX, GroupKind.CELLS, GroupKind.BSP, GroupKind.SEALED)


def _float(x: float) -> float | None:
    return None if math.isnan(x) else float(x)


def _header(h: planefmt.Header) -> dict:
    q = h.quantization
    return {
        "version": list(h.version),
        "lossy": h.lossy,
        "coding": int(h.coding),
        "bits": [q.bits_nu, q.bits_phi, q.bits_h] if q else [0, 0, 0],
        "h_range": [q.h_min, q.h_max] if q else [0.0, 0.0],
        "units": int(h.units),
        "bbox": None if h.bbox is None else h.bbox.tolist(),
        "tolerance": _float(h.tolerance),
        "error_bound": _float(h.error_bound),
        "counts": None if h.plane_count is None else
        {"planes": h.plane_count, "objects": h.object_count, "groups": h.group_count},
    }


def _group(g: planefmt.PartGroup) -> dict:
    out = {"index": g.index, "object": g.object, "kind": int(g.kind), "refs": g.refs.tolist(),
           "bounding": np.flatnonzero(g.bounding).tolist()}
    if g.source is not None:
        # A copy (spec §9.15) as stored: its source, not the surface it shares.
        return {**out, "kind": int(planefmt.GroupKind.COPY), "source": g.source}
    if g.cells is not None:
        out["cells"] = [c.tolist() for c in g.cells]
    if g.tree is not None:
        out["tree"] = g.tree.tolist()
    if g.vertex_planes is not None:
        out["vertex_planes"] = g.vertex_planes.tolist()
        out["facets"] = g.facets.tolist()
    if g.shell is not None:
        s = g.shell
        out["shell"] = {"explicit": np.flatnonzero(s.explicit).tolist(), "vertex_planes": s.vertex_planes.tolist(),
                        "grid": s.grid.tolist(), "origin": [float(x) for x in s.origin] if s.explicit.any() else None,
                        "step": float(s.step) if s.explicit.any() else None,
                        "facets": s.facets.tolist()}
    return out


def _world(objects: list[planefmt.ObjectRecord]) -> list[np.ndarray]:
    worlds: list[np.ndarray] = []
    for o in objects:
        local = np.eye(4) if o.transform is None else o.transform
        worlds.append(local if o.parent is None else worlds[o.parent] @ local)
    return worlds


def _geometry(groups: list[planefmt.PartGroup], objects: list[planefmt.ObjectRecord],
              header: planefmt.Header) -> dict | None:
    """Per-group summaries of the decoded surface, or None where planefmt cannot decode every group.
    Decoded with the plane error of the header's coding, as ``planefmt.decode_mesh`` decodes the file
    (its merge distance, spec §9.4, sets the vertex counts)."""
    try:
        from planefmt import codec
    except ImportError:
        return None
    worlds = _world(objects)
    kinds = records.kinds_of(*header.version)
    error = codec.header_plane_error(header)
    summaries, corners, complete = [], [], True
    for g in groups:
        if g.kind not in kinds:
            summaries.append(None)  # a kind of a newer minor version, skipped (kind 5 too, before 3.1)
            continue
        if int(g.kind) not in codec.DECODERS:
            complete = False  # still decode the others: their geometry errors count
            continue
        d = codec.decode_group(g.planes, g, g.index, error)
        used = np.unique(d.triangles)
        a, b, c = (d.vertices[d.triangles[:, i]] for i in range(3))
        cross = np.cross(b - a, c - a)
        v = d.vertices[used]
        summaries.append({
            "vertices": len(used), "triangles": len(d.triangles),
            "area": float(np.linalg.norm(cross, axis=1).sum() / 2), "area_vector": (cross.sum(axis=0) / 2).tolist(),
            "volume": float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6) if g.kind in SOLID_KINDS else None,
            # a group planefmt decodes to no triangle (a hostile file can hold one) has no bbox
            "bbox": [v.min(axis=0).tolist(), v.max(axis=0).tolist()] if len(v) else None,
        })
        m = worlds[g.object]
        corners.append(v @ m[:3, :3].T + m[:3, 3])
    if not complete:
        return None
    world = None
    p = np.concatenate(corners) if corners else np.empty((0, 3))
    if len(p):
        world = [p.min(axis=0).tolist(), p.max(axis=0).tolist()]
    return {"world_bbox": world, "groups": summaries}


def describe(path: str) -> dict:
    """The contract's JSON for a valid file; raises ``planefmt.PlnError`` for an invalid one."""
    planes, groups = [], []
    colours: dict[int, dict] = {}  # by group, in the order of its first cOLR: the last applies (§10.1)
    with planefmt.open(path) as r:
        for record in r:
            if isinstance(record, planefmt.PlaneBlock):
                planes.append(record.triplets)
            elif isinstance(record, planefmt.PartGroup):
                groups.append(record)
            elif isinstance(record, planefmt.Colours):
                colours[record.group] = {"group": record.group, "rgba": record.rgba.tolist()}
        if r.index_offset is not None:
            # Random access must work too: every group through the index.
            for k in range(r.group_count):
                r.group(k)
        return {
            "header": _header(r.header),
            "planes": np.concatenate(planes).tolist() if planes else [],
            "objects": [{"name": o.name, "parent": o.parent,
                         "transform": None if o.transform is None else o.transform.ravel().tolist()}
                        for o in r.objects],
            "groups": [_group(g) for g in groups],
            "colours": list(colours.values()),
            "metadata": {**r.metadata, **({UP_AXIS: r.header.up_axis} if r.header.up_axis else {})},
            "findings": sorted({code for code, _ in r.findings}),
            "geometry": _geometry(groups, r.objects, r.header),
        }


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m conformance.adapter FILE", file=sys.stderr)
        return 2
    try:
        result = describe(argv[0])
    except planefmt.PlnError as exc:
        print(json.dumps({"error": exc.code}))
        print(exc, file=sys.stderr)
        return 1
    print(json.dumps(result, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
