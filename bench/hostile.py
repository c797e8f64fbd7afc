"""Issue 49's targets, class by class: every class of fuzz/hostile.py at its bench size (10x the
issue's; a declared stream at 256 MiB, the largest raw size the default limits allow) through
planefmt's decode_mesh and node js/cli.mjs side by side: outcome (counts or error code), wall
time, peak RSS above the interpreter's baseline, and whether it meets the target (a result or the
reader's own error within 2 s and 256 MB).

Each run is a child process capped at 60 s CPU and 8 GB (Python: address space; node: heap), so a
class that misses the target by far shows as a cap, not a hung benchmark.

Usage: ``python bench/hostile.py [--only NAME ...] [--scale 1.0] [--keep DIR]``
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

import capped  # noqa: E402
import hostile  # noqa: E402

TARGET_S, TARGET_MB = 2.0, 256.0


def _cell(o: capped.Outcome) -> str:
    ok = o.kind in ("result", "error") and o.seconds <= TARGET_S and o.rss_mb <= TARGET_MB
    what = o.detail if o.kind in ("result", "error") else f"{o.kind.upper()} {o.detail}"
    return f"{what[:34]:<34} {o.seconds:7.2f} {o.rss_mb:7.0f} {'ok' if ok else 'MISS':>4}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="*", help="class names (default: all)")
    ap.add_argument("--scale", type=float, default=1.0, help="times the bench size")
    ap.add_argument("--keep", type=Path, help="write the files here instead of a temporary folder")
    args = ap.parse_args()
    names = args.only or list(hostile.CLASSES)
    readers = ["py"] + (["js"] if capped.node() else [])
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"target: a result or the reader's own error within {TARGET_S:g} s and {TARGET_MB:g} MB above baseline")
    head = f"{'outcome':<34} {'s':>7} {'MB':>7} {'':>4}"
    print(f"{'class':<26} {'size':>12} {'bytes':>11} | py: {head} | js: {head}")
    folder = args.keep or Path(tempfile.mkdtemp(prefix="hostile-"))
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        make, _, size = hostile.CLASSES[name]
        size = int(size * args.scale) if size else 0
        path = folder / f"{name}.pln"
        path.write_bytes(make(size))
        cells = [_cell(capped.run(r, path, cpu_s=60, mem_mb=8192)) for r in readers]
        print(f"{name:<26} {size:>12,} {path.stat().st_size:>11,} | " + " | ".join(
            f"{r}: {c}" for r, c in zip(readers, cells)), flush=True)
        if not args.keep:
            path.unlink()


if __name__ == "__main__":
    main()
