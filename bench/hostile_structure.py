"""Hostile structure (issue 49, items 2 and 3): both readers side by side on files built from the spec.

Each file is decoded by planefmt (``decode_mesh`` in a fresh interpreter, timed
inside it) and by the JavaScript
reader (``node js/cli.mjs``), each in its own child; the table gives the outcome (``ok`` or the
error code), the wall time and the peak RSS above the same interpreter's baseline (``python -c
"import planefmt"``, ``node -e 0``), against the issue's target: an answer within 2 s and 256 MB.

Files (``tests/spec_files.py``'s builders, version 5.2, one tree group over x <= 1 and the cube's
other planes, deflated):

* ``chain``: a chain of 200,000 splits on x <= 1 (the issue's 100,000-split attack at 2x; the
  depth sum is 2e10, spec §9.7 allows 2^25);
* ``chain_20k``: the 20,000-split chain that took planefmt 25 s before the bound;
* ``twice``: the IN leaf x <= 1 behind the same split twice (spec §9.7: UNBOUNDED_POLYTOPE);
* ``cube_tree``: the unit cube as a chain of its six splits (a tree that decodes, for the baseline).

Not covered yet: item 2's kind 9 walk of 1,000,000 triangles whose edges collide under the old
fixed edge hash (it needs the walk's explicit-corner head at that size; see the report of issue 49).

Usage: ``python bench/hostile_structure.py``
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from spec_files import pln_file, uv  # noqa: E402

TARGET_SECONDS, TARGET_MB = 2.0, 256.0

#: x <= 1, then y <= 1, x >= -1, y >= -1, z <= 1, z >= -1 as (nu, phi, h).
PLANES = [(math.pi / 2, 0.0, 1.0), (math.pi / 2, math.pi / 2, 1.0), (math.pi / 2, math.pi, 1.0),
          (math.pi / 2, 3 * math.pi / 2, 1.0), (0.0, 0.0, 1.0), (math.pi, 0.0, 1.0)]

#: decode_mesh, timed inside the child after the imports a decode needs (~1 s here, scipy among them).
PYTHON_DECODE = """import sys, time, planefmt
import planefmt.groups.solids, scipy.optimize, scipy.spatial  # what a decode imports on first use
t = time.perf_counter()
try:
    planefmt.decode_mesh(sys.argv[1])
    code = "ok"
except planefmt.PlnError as exc:
    code = exc.code
print(code, time.perf_counter() - t)
sys.exit(code != "ok")"""


def tree_file(tokens: list[int]) -> bytes:
    """A version 5.2 file of one tree group (kind 2) over the six planes, its body deflated."""
    body = uv(len(tokens)) + b"".join(uv(t) for t in tokens)
    data = pln_file([(2, list(range(6)), [], body)], PLANES, major=5, minor=2)
    return _deflated(data, body)


def _deflated(data: bytes, body: bytes) -> bytes:
    # pln_file stores groups; a hostile file is small: rebuild the GRUP with method 1 (zlib, §6).
    import spec_files

    stored = spec_files.grup(0, 0, 2, spec_files.group_body(range(6), [], body))
    deflated = spec_files.grup(0, 0, 2, spec_files.group_body(range(6), [], body), method=1)
    old = spec_files.varint_chunk(b"GRUP", stored)
    assert old in data
    return data.replace(old, spec_files.varint_chunk(b"GRUP", deflated))


def files() -> dict[str, bytes]:
    n = 200_000
    return {
        "chain": tree_file([2] * n + [0] + [1] * n),
        "chain_20k": tree_file([2] * 20_000 + [0] + [1] * 20_000),
        "twice": tree_file([2, 2, 0, 1, 1]),
        "cube_tree": tree_file([2, 3, 4, 5, 6, 7, 0, 1, 1, 1, 1, 1, 1]),
    }


def measure(cmd: list[str]) -> tuple[str, float, float]:
    """(outcome, seconds, peak RSS MB) of one child, measured from a fresh probe interpreter: the
    decode's own time where the child prints it (planefmt), else the child's wall time."""
    probe = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
             "p = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, time.perf_counter() - t, "
             "p.returncode); print(p.stdout[-300:].replace(chr(10), ' ')); "
             "print(p.stderr[-300:].replace(chr(10), ' '))")
    out = subprocess.run([sys.executable, "-c", probe, *cmd], capture_output=True, text=True, check=True).stdout
    head, stdout, stderr = (out.splitlines() + ["", "", ""])[:3]
    rss, secs, code = head.split()
    own = stdout.split()
    if len(own) == 2 and own[0].replace("_", "").isalpha():
        return own[0], float(own[1]), float(rss)
    return _outcome(int(code), stdout, stderr), float(secs), float(rss)


def _outcome(code: int, stdout: str, stderr: str) -> str:
    if code == 0:
        return "ok"
    for text in (stdout, stderr):
        for word in text.replace('"', " ").replace(":", " ").split():
            if word.isupper() and "_" in word:
                return word
    return f"exit {code}"


def main() -> None:
    node = ["node", str(ROOT / "js" / "cli.mjs")]
    python = [sys.executable, "-c", PYTHON_DECODE]
    _, _, py_base = measure([sys.executable, "-c", PYTHON_DECODE.splitlines()[1]])
    _, _, js_base = measure(["node", "-e", "0"])
    print(f"baselines: python + planefmt {py_base:.0f} MB, node {js_base:.0f} MB; target {TARGET_SECONDS:g} s, "
          f"{TARGET_MB:g} MB above baseline; {os.cpu_count()} cores shared")
    print(f"{'file':<11} {'bytes':>7}  {'planefmt':<22} {'js':<22} within target")
    with tempfile.TemporaryDirectory() as tmp:
        for name, data in files().items():
            path = os.path.join(tmp, f"{name}.pln")
            Path(path).write_bytes(data)
            rows = []
            within = True
            for cmd, base in ((python, py_base), (node, js_base)):
                outcome, secs, rss = measure([*cmd, path])
                rows.append(f"{outcome} {secs:.2f} s {max(rss - base, 0):.0f} MB")
                within &= secs <= TARGET_SECONDS and rss - base <= TARGET_MB
            print(f"{name:<11} {len(data):>7}  {rows[0]:<22} {rows[1]:<22} {'yes' if within else 'NO'}")


if __name__ == "__main__":
    main()
