"""``pln preview FILE -o out.png``: a picture of the decoded mesh, each part group in its own colour.

Headless (no display, no GPU): decodes every part group, places it with its
object's world transform and draws it with a small z-buffer
(``planefmt_converters.render``), the file's up axis (``--up``; Z where the
file names none) towards the top. The PNG is written atomically. Part groups
of kinds this version cannot decode are left out and named on stderr.
"""

from __future__ import annotations

import argparse
import sys

from planefmt.errors import PlnError
from planefmt.model import UP_AXES

from . import limits


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("preview", help="draw a .pln file to a PNG, one colour per part group",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="a .pln file, or - for standard input")
    p.add_argument("-o", "--output", required=True, help="the PNG to write")
    p.add_argument("--size", type=int, default=640, help="image width and height in pixels (default 640)")
    p.add_argument("--up", choices=UP_AXES,
                   help="the model axis drawn upwards (default: the file's up axis, spec §10.3; Z where it "
                        "names none)")
    p.add_argument("--view", type=float, nargs=3, metavar=("X", "Y", "Z"),
                   help="direction from the model towards the eye, in model coordinates (default 1 -1.4 0.9 "
                        "with Z up, 1 0.9 1.4 with Y up: the same view of an upright model)")
    limits.add_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from planefmt import codec
    from planefmt.container import reader
    from planefmt.geometry.planes import transform_points

    from ..atomic import write_bytes
    from ..render import default_view, png_bytes, render

    if not 16 <= args.size <= 8192:
        raise PlnError(f"--size {args.size} is outside 16..8192", code="CONVERSION_FAILED")
    if args.view is not None and not np.linalg.norm(args.view) > 0:
        raise PlnError("--view must be a non-zero direction", code="CONVERSION_FAILED")
    vertices, triangles, groups, skipped = [], [], [], []
    offset = 0
    with reader.open(sys.stdin.buffer if args.file == "-" else args.file, limits=limits.limits_of(args)) as r:
        error = codec.header_plane_error(r.header)
        worlds: list[np.ndarray] = []
        for g in r.part_groups():
            for o in r.objects[len(worlds):]:
                local = np.eye(4) if o.transform is None else o.transform
                worlds.append(local if o.parent is None else worlds[o.parent] @ local)
            if int(g.kind) not in codec.DECODERS:
                skipped.append(g.index)
                continue
            d = codec.decode_group(g.planes, g, g.index, error)
            r.budget.charge_decoded(g, len(d.vertices), len(d.triangles))
            vertices.append(transform_points(d.vertices, worlds[g.object]))
            triangles.append(d.triangles + offset)
            groups.append(np.full(len(d.triangles), g.index))
            offset += len(d.vertices)
        up = args.up or r.up_axis or "Z"
    if skipped:
        print(f"pln: warning: {args.file}: part groups {', '.join(map(str, skipped))} are of kinds this "
              f"version cannot decode; not drawn", file=sys.stderr)
    image = render(np.concatenate(vertices) if vertices else np.zeros((0, 3)),
                   np.concatenate(triangles) if triangles else np.zeros((0, 3), dtype=np.int64),
                   np.concatenate(groups) if groups else np.zeros(0, dtype=np.int64),
                   size=args.size, view=default_view(up) if args.view is None else args.view, up=up)
    write_bytes(args.output, png_bytes(image))
    return 1 if skipped else 0
