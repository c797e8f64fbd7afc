"""``pln info FILE``: header, objects, part groups by kind (planes per group) and bytes per chunk type.

With ``--source MESH`` (the mesh the file was made from, any format ``pln
convert`` reads) it also gives the file's bytes per source triangle.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import Counter
from typing import TYPE_CHECKING

from planefmt import errors
from planefmt.model import SHELL_KINDS, GroupKind, Metadata, ObjectRecord, PartGroup, PlaneBlock

from . import limits

# The reader and salvage (numpy, construct) are imported where a file is read: every command builds this
# module's parser, ``pln --version`` too.
if TYPE_CHECKING:
    from planefmt.container.chunks import Limits

#: Kinds this version of planefmt names; a newer minor version's kind is shown by number.
KINDS = frozenset(int(k) for k in GroupKind)

#: The names :class:`_Summary` gives shell kinds (spec §9.10 to §9.17), whose triangles are the source's.
_SHELL_NAMES = frozenset(GroupKind(k).name.lower() for k in SHELL_KINDS)


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("info", help="describe a .pln file", description=__doc__)
    p.add_argument("file", help="a .pln file, or - for standard input")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--source", metavar="MESH",
                   help="the mesh the file was encoded from: report bytes per source triangle")
    p.add_argument("--salvage", action="store_true",
                   help="recover every intact part group of a damaged file and list what was lost")
    limits.add_arguments(p)
    p.set_defaults(func=run)


class _Summary:
    """Counts gathered from records as they stream past."""

    def __init__(self) -> None:
        self.objects: dict[int, dict] = {}
        self.kinds: Counter[str] = Counter()
        self.planes_by_kind: Counter[str] = Counter()
        self.largest_by_kind: Counter[str] = Counter()
        self.bounding = 0
        self.planes = 0
        self.groups = 0
        self.metadata: dict[str, str] = {}

    def add(self, rec) -> None:
        if isinstance(rec, Metadata):
            self.metadata[rec.key] = rec.value
        elif isinstance(rec, ObjectRecord):
            self.objects[rec.index] = {
                "index": rec.index, "name": rec.name, "parent": rec.parent,
                "transform": None if rec.transform is None else rec.transform.tolist(), "groups": 0}
        elif isinstance(rec, PlaneBlock):
            self.planes += len(rec.triplets)
        elif isinstance(rec, PartGroup):
            kind = GroupKind(rec.kind).name.lower() if rec.kind in KINDS \
                else f"kind{rec.kind}"
            if rec.source is not None:
                kind = "copy"  # spec §9.15: stored as a copy of an earlier group, decoded as that group
            self.kinds[kind] += 1
            self.planes_by_kind[kind] += len(rec.refs)
            self.largest_by_kind[kind] = max(self.largest_by_kind[kind], len(rec.refs))
            self.bounding += int(rec.bounding.sum())
            self.groups += 1
            if rec.object in self.objects:
                self.objects[rec.object]["groups"] += 1


def describe_salvaged(source: str, caps: Limits | None = None) -> dict:
    """Like :func:`describe` for a damaged file: what salvage recovered, and the losses."""
    from planefmt.container import salvage

    got = salvage.salvage(sys.stdin.buffer if source == "-" else source, limits=caps)
    summary = _Summary()
    for rec in got.records:
        summary.add(rec)
    if got.header is None:
        raise errors.FormatError("no intact header: nothing to salvage", code="MISSING_HEADER", file=source)
    info = _render_dict(source, got.header, summary, chunks={}, file_bytes=None, findings=[])
    info["losses"] = [{"code": x.code, "message": x.message, "offset": x.offset} for x in got.losses]
    return info


def describe(source: str, caps: Limits | None = None) -> dict:
    """Everything ``pln info`` shows, as plain JSON-ready data (memory bounded by one chunk and ``caps``,
    the reader's limits of spec §12.4)."""
    from planefmt.container import reader

    summary = _Summary()
    with reader.open(source, retain_planes=False, limits=caps) as r:
        for rec in r:
            summary.add(rec)
        chunks = {name: {"count": r.chunk_counts[name], "bytes": r.chunk_stats[name]} for name in r.chunk_stats}
        findings = [{"code": c, "severity": errors.CODES[c].severity, "message": m} for c, m in r.findings]
        info = _render_dict(r.name, r.header, summary, chunks, sum(r.chunk_stats.values()) + 8, findings)
        # Version 6: the records of the body segments, by type, in raw (decompressed) bytes (spec §4.6).
        info["records"] = {name: {"count": r.record_counts[name], "bytes": r.record_stats[name]}
                           for name in r.record_stats}
        return info


def _render_dict(name: str, h, summary: _Summary, chunks: dict, file_bytes: int | None,
                 findings: list[dict]) -> dict:
    q = h.quantization
    return {
        "file": name,
        "version": f"{h.version[0]}.{h.version[1]}",
        "lossy": h.lossy,
        # Shells decode the source's triangles one to one; every other kind makes its triangles from planes.
        "source_triangles": bool(summary.groups) and set(summary.kinds) <= _SHELL_NAMES,
        "coding": h.coding.name.lower(),
        "quantization": None if q is None else {
            "bits_nu": q.bits_nu, "bits_phi": q.bits_phi, "bits_h": q.bits_h,
            "h_min": q.h_min, "h_max": q.h_max},
        "units": h.units.name.lower(),
        "metadata": summary.metadata,
        "bbox": None if h.bbox is None else h.bbox.tolist(),
        "tolerance": _num(h.tolerance),
        "error_bound": _num(h.error_bound),
        "counts_in_header": h.plane_count is not None,
        "planes": summary.planes,
        "objects": [summary.objects[k] for k in sorted(summary.objects)],
        "groups": {"total": summary.groups, "by_kind": dict(summary.kinds),
                   "plane_refs_by_kind": dict(summary.planes_by_kind),
                   "largest_by_kind": dict(summary.largest_by_kind), "bounding_refs": summary.bounding},
        "chunks": chunks,
        "file_bytes": file_bytes,
        "findings": findings,
    }


def _num(v: float) -> float | None:
    return None if math.isnan(v) else v


def source_triangles(path: str) -> int:
    """Triangles of a mesh file as ``pln convert`` reads it (all nodes, polygons triangulated)."""
    from planefmt_converters import registry

    scene, _ = registry.read(path)
    return sum(len(n.mesh.faces) for n in scene.nodes if n.mesh is not None)


def run(args: argparse.Namespace) -> int:
    caps = limits.limits_of(args)
    info = describe_salvaged(args.file, caps) if args.salvage else describe(args.file, caps)
    if args.source:
        triangles = source_triangles(args.source)
        info["source"] = {"file": args.source, "triangles": triangles,
                          "bytes_per_triangle": None if not triangles or info["file_bytes"] is None
                          else info["file_bytes"] / triangles}
    if args.json:
        json.dump(info, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(render(info))
    serious = any(f["severity"] in ("error", "warning") for f in info["findings"]) or info.get("losses")
    return 1 if serious else 0


def _promise(info: dict) -> str:
    """What a lossless file keeps of its source (spec §5)."""
    tol = "its tolerance" if info["tolerance"] is None else f"{info['tolerance']:.3g} of the diagonal"
    triangles = "the source's triangles one to one" if info["source_triangles"] else \
        "triangles made from the planes (not the source's)"
    return f"(surface within {tol}; topology kept once welded by position; {triangles})"


def render(info: dict) -> str:
    q = info["quantization"]
    coding = info["coding"] + ("" if q is None else f" (bits nu/phi/h {q['bits_nu']}/{q['bits_phi']}/{q['bits_h']}, "
                                                   f"h in [{q['h_min']:.6g}, {q['h_max']:.6g}])")
    tol = "-" if info["tolerance"] is None else f"{info['tolerance']:.3g}"
    bound = "not measured" if info["error_bound"] is None else f"{info['error_bound']:.3g}"
    size = "" if info["file_bytes"] is None else f" ({info['file_bytes']} bytes)"
    lines = [
        f"file:        {info['file']}{size}",
        f"version:     {info['version']}   {'lossy' if info['lossy'] else 'lossless'}",
        *([] if info["lossy"] else [f"             {_promise(info)}"]),
        f"coding:      {coding}",
        f"units:       {info['units']}",
        *([f"metadata:    {', '.join(f'{k}={v}' for k, v in info['metadata'].items())}"] if info["metadata"] else []),
        f"bbox:        {info['bbox'] if info['bbox'] is not None else '- (not stored)'}",
        f"error:       requested {tol}, verified {bound} (fraction of the bbox diagonal)",
        f"planes:      {info['planes']}",
        f"objects:     {len(info['objects'])}",
    ]
    for o in info["objects"]:
        parent = "" if o["parent"] is None else f", parent {o['parent']}"
        xf = ", transform" if o["transform"] is not None else ""
        lines.append(f"  [{o['index']}] {o['name'] or '(unnamed)'}: {o['groups']} groups{parent}{xf}")
    g = info["groups"]
    lines.append(f"groups:      {g['total']}")
    for kind, n in sorted(g["by_kind"].items()):
        refs = g["plane_refs_by_kind"][kind]
        lines.append(f"  {kind:<15} {n:>8} groups {refs:>10} plane refs   planes per group: "
                     f"mean {refs / n:.1f}, max {g['largest_by_kind'][kind]}")
    if g["bounding_refs"]:
        lines.append(f"  bounding, cut or vertex plane refs: {g['bounding_refs']}")
    src = info.get("source")
    if src is not None:
        per = "-" if src["bytes_per_triangle"] is None else f"{src['bytes_per_triangle']:.2f}"
        lines.append(f"source:      {src['file']}: {src['triangles']} triangles, {per} bytes per triangle")
    lines.append("chunks:")
    # an unknown record is named "tag N": pad every name to the widest so the columns stay aligned
    width = max(map(len, [*info["chunks"], *info.get("records", {})]), default=4)
    for name, c in sorted(info["chunks"].items(), key=lambda kv: -kv[1]["bytes"]):
        lines.append(f"  {name:<{width}}  {c['count']:>8} x  {c['bytes']:>12} bytes")
    if info.get("records"):
        lines.append("records (in body segments, raw bytes):")
        for name, c in sorted(info["records"].items(), key=lambda kv: -kv[1]["bytes"]):
            lines.append(f"  {name:<{width}}  {c['count']:>8} x  {c['bytes']:>12} bytes")
    for f in info["findings"]:
        lines.append(f"{f['severity']}: {f['code']}: {f['message']}")
    for loss in info.get("losses", []):
        at = "" if loss["offset"] is None else f" at byte {loss['offset']}"
        lines.append(f"lost{at}: {loss['code']}: {loss['message']}")
    return "\n".join(lines) + "\n"
