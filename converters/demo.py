"""``python -m planefmt_converters.demo OUTDIR``: the main job on a bundled sample.

Writes the paper's unit cube as planes, reads it back through a pipe-like
stream and prints ``pln info``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

import planefmt
from planefmt.model import Coding, GroupKind, Header, Units

from .cli import main as pln


def main(argv: list[str] | None = None) -> int:
    out = Path((argv or sys.argv[1:] or ["out"])[0])
    out.mkdir(parents=True, exist_ok=True)
    target = out / "cube.pln"
    degrees = np.array([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]], dtype=float)
    triplets = np.column_stack([np.radians(degrees), [1, 1, 0, 0, 1, 0]])
    header = Header(coding=Coding.FLOAT32, units=Units.METRE, bbox=np.array([[0, 0, 0], [1, 1, 1.0]]),
                    tolerance=1e-6, error_bound=0.0)
    with planefmt.Writer(target, header) as w:
        cube = w.add_object("cube")
        w.add_planes(triplets)
        w.add_group(cube, GroupKind.CONVEX, np.arange(6))
    print(f"wrote {target} ({target.stat().st_size} bytes; the paper's cube as 6 planes)")
    with planefmt.open(target) as r:
        for group in r.part_groups():
            print(f"group {group.index}: planes (nu, phi in degrees, h) =",
                  [(round(math.degrees(a)), round(math.degrees(b)), h) for a, b, h in group.planes.tolist()])
    return pln(["info", str(target)])


if __name__ == "__main__":
    sys.exit(main())
