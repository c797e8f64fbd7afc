"""Hostile files of issue 49 (items 1, 5, 6, 7) at ten times the issue's sizes, through both readers:
each must end in a result or its own error within 2 s and 256 MB above its baseline.

Files are built by ``tests/spec_files.py`` (from spec/pln.md alone) into a temporary folder; each
reader runs in its own process under ``/usr/bin/time -v``: Python's ``planefmt.decode_mesh`` and
``node js/cli.mjs``. "Above baseline" is the peak RSS minus that of the same command on a 10-triangle
walk. Item 6 is at the largest raw size a reader accepts (256 MiB): ten times is past the limit.

Usage: ``python bench/budget.py``
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
from spec_files import (fan_walk, group_body, pack, stored_file, uv, varint_chunk, walk_file,  # noqa: E402
                        zero_planes_block)

PY = ("import sys, planefmt\n"
      "try:\n"
      "    m = planefmt.decode_mesh(sys.argv[1]); print(f'{len(m.faces)} triangles')\n"
      "except planefmt.PlnError as e:\n"
      "    print(e.code)\n")


def repeated_groups(body: bytes, count: int, method: int) -> bytes:
    """``count`` groups with the same raw body (stored once compressed), in one object."""
    stored = pack(body, method)
    one = stored_file([])
    head, end = one[: one.rindex(b"PEND") ], one[one.rindex(b"PEND"):]
    groups = b"".join(varint_chunk(b"GRUP", uv(i) + uv(0) + bytes([9, method]) + uv(len(body)) + stored)
                      for i in range(count))
    return head + groups + end


def planes_bomb(count: int, blocks: int) -> bytes:
    one = zero_planes_block(0, count)
    stored = one[len(uv(0)):]  # count, method, raw size, data: the same in every block
    return stored_file([], plns_blocks=[uv(k * count) + stored for k in range(blocks)])


def brotli_bomb(raw_size: int) -> bytes:
    """A walk body declared ``raw_size`` bytes, Brotli-compressed, that does not compress past the ratio
    limit: bytes of 2 bits each after a fan walk's counts."""
    noise = np.random.default_rng(0).integers(0, 4, raw_size, dtype=np.uint8).tobytes()
    body = group_body([], [], fan_walk(3)[:4]) + noise
    return stored_file([(0, 9, body[:raw_size], 2)])


CASES = {
    "baseline: a 10-triangle walk": lambda: walk_file(10),
    "1 copies: 3,394-triangle walk + 50,000 copies": lambda: walk_file(3394, 1, 50_000),
    "7 walk declaring 10,000,000 triangles": lambda: walk_file(10_000_000, 2),
    "7 nine walks of 49,000,000 (441 M)": lambda: repeated_groups(group_body([], [], fan_walk(49_000_000)), 9, 1),
    "5 220 M zero planes (10 x 22 M, zlib)": lambda: planes_bomb(22_000_000, 10),
    "6 Brotli body declared 256 MiB": lambda: brotli_bomb(256 << 20),
}


def run(cmd: list[str]) -> tuple[float, int, str]:
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True, timeout=600)
    seconds = time.perf_counter() - t0
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1)) * 1024
    out = (p.stdout.strip().splitlines() or ["?"])[-1]
    return seconds, rss, out.replace('{"error":"', "").replace('"}', "")[:40]


def main() -> None:
    readers = {"python": lambda f: [sys.executable, "-c", PY, f], "node": lambda f: ["node", str(ROOT / "js/cli.mjs"), f]}
    print(f"{'case':<48} {'bytes':>10} | " + " | ".join(f"{r + ' s':>8} {'MB over':>8} {'outcome':<22}" for r in readers))
    base: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, make in CASES.items():
            path = os.path.join(tmp, "case.pln")
            data = make()
            Path(path).write_bytes(data)
            del data
            cells = []
            for reader, cmd in readers.items():
                seconds, rss, out = run(cmd(path))
                base.setdefault(reader, rss)
                cells.append(f"{seconds:>8.2f} {(rss - base[reader]) / 1e6:>8.0f} {out:<22}")
            print(f"{name:<48} {os.path.getsize(path):>10,} | " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
