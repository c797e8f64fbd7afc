"""Write the fuzzing seed corpus: the conformance files plus small files of every coding and kind."""

from __future__ import annotations

import io
import shutil
import sys
from pathlib import Path

import numpy as np

import planefmt
from planefmt.model import BSP_IN, BSP_OUT, Coding, GroupKind, Header, Quantization

ROOT = Path(__file__).resolve().parent.parent
CUBE = np.column_stack([np.radians([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]]),
                        [1, 1, 0, 0, 1, 0]])


def generated() -> dict[str, bytes]:
    out = {}
    codings = {"f32": (Coding.FLOAT32, None), "f64": (Coding.FLOAT64, None),
               "q": (Coding.QUANTIZED, Quantization(7, 9, 11, -1.0, 2.0))}
    for name, (coding, q) in codings.items():
        for compress in (False, True):
            sink = io.BytesIO()
            with planefmt.Writer(sink, Header(coding=coding, quantization=q, bbox=np.array([[0, 0, 0], [1, 1, 1.]]),
                                              tolerance=1e-6, error_bound=0.0), compress=compress) as w:
                o = w.add_object("cube", transform=np.eye(4))
                c = w.add_object("child", parent=o)
                w.add_planes(np.tile(CUBE, (8, 1)))
                w.add_group(o, GroupKind.CONVEX, np.arange(6))
                w.add_group(c, GroupKind.CELLS, np.arange(6), cells=(np.arange(0, 12, 2, dtype=np.uint32),))
                w.add_group(c, GroupKind.BSP, np.arange(6), tree=np.array([0, BSP_IN, BSP_OUT], np.uint32))
                w.add_group(o, GroupKind.PSEUDO_CONCAVE, np.arange(6), np.arange(6) > 3)
                w.add_colours(0, np.full((6, 4), 200, np.uint8))
                w.add_chunk(b"tEXt", b"comment")
            out[f"seed_{name}{'_z' if compress else ''}.pln"] = sink.getvalue()
    return out


def main(target: str) -> None:
    dest = Path(target)
    dest.mkdir(parents=True, exist_ok=True)
    for name, data in generated().items():
        (dest / name).write_bytes(data)
    for path in sorted((ROOT / "conformance").rglob("*.pln")):
        shutil.copy(path, dest / f"conf_{path.parent.name}_{path.name}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "fuzz/corpus")
