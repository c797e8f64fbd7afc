"""``python -m planefmt_converters.demo OUTDIR``: the main job on a bundled sample.

Converts ``samples/cylinder.stl`` to .pln (lossless: tolerance 1e-6 of the
bounding-box diagonal, verified by the encoder), prints ``pln info``, and
converts the .pln back to GLB and OBJ, and draws it to ``cylinder.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .cli import main as pln

SAMPLES = Path(__file__).resolve().parent.parent / "samples"


def main(argv: list[str] | None = None) -> int:
    out = Path((argv if argv is not None else sys.argv[1:] or ["out"])[0])
    out.mkdir(parents=True, exist_ok=True)
    source = SAMPLES / "cylinder.stl"
    steps = [
        ["convert", str(source), str(out / "cylinder.pln")],
        ["info", str(out / "cylinder.pln")],
        ["convert", str(out / "cylinder.pln"), str(out / "cylinder.glb")],
        ["convert", str(out / "cylinder.pln"), str(out / "cylinder.obj")],
        ["preview", str(out / "cylinder.pln"), "-o", str(out / "cylinder.png")],
    ]
    for step in steps:
        print("$ pln " + " ".join(step), flush=True)
        code = pln(step)
        if code:
            return code
    size_in, size_pln = source.stat().st_size, (out / "cylinder.pln").stat().st_size
    print(f"{source.name}: {size_in} bytes as binary STL, {size_pln} bytes as .pln")
    return 0


if __name__ == "__main__":
    sys.exit(main())
