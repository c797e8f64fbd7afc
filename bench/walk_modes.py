"""How well the encoder ranks a shell walk's coordinate modes (spec §9.13): bytes lost against an oracle.

For every corpus mesh at draco-14's measured error on it (read from the per-mesh table of
``docs/benchmarks.md``, the draco-14 column), the default encoder writes the file; for each shell walk
group in it, the kind data of every coding the encoder tries (``shellwalk.codings``: kind 9, spec §9.13,
in every coordinate mode, kind 10, §9.14, in those without bit 0) is built
(``shellwalk.shell_walk_fields(shell, mode, kind)``)
and compressed whole with Brotli at quality 11, the writer's coder: the *oracle* is the smallest of
them. Each *ranking* picks a mode from its own score, and loses the oracle's bytes less the picked
mode's. Rankings: deflate at levels 1, 6 and 9 and Brotli at quality 1 and 5 of the tables and
coordinates; Brotli at quality 10 and 11 of the same (what the oracle would cost to run, nearly); and
``encoder``, what ``shellwalk._smallest`` picks (deflate at ``RANK_LEVEL``, Brotli deciding the best
two where they are within ``RANK_CLOSE``). Printed: the meshes where a ranking loses more than 20
bytes, then per ranking the bytes lost over the corpus and the seconds its scores took.

Usage: ``python bench/walk_modes.py``
"""

from __future__ import annotations

import io
import os
import re
import sys
import time
import zlib

import brotli

sys.path.insert(0, os.path.dirname(__file__))
from compare import CORPUS, load  # noqa: E402

import planefmt  # noqa: E402
from planefmt import codec  # noqa: E402
from planefmt.container import shellwalk  # noqa: E402
from planefmt.model import GroupKind  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROW = re.compile(r"\| (CAD|convex|non-convex watertight|open|smooth dense|scenes)/(\S+) \| \d+ \| [^|]+\| [\d,]+ \(\S+\) (\S+) \|")


def d14_errors() -> dict[str, float]:
    """Draco-14's measured error per corpus file name, from docs/benchmarks.md."""
    out: dict[str, float] = {}
    with open(os.path.join(HERE, "..", "docs", "benchmarks.md"), encoding="utf-8") as f:
        for line in f:
            m = ROW.match(line)
            if m and m.group(2) not in out:
                out[m.group(2)] = float(m.group(3))
    return out


def corpus_path(name: str) -> str:
    for root, _, files in os.walk(CORPUS):
        if name in files:
            return os.path.join(root, name)
    raise FileNotFoundError(name)


def part(f: dict[str, bytes]) -> bytes:
    return f["tables"] + f["coordinates"]


RANKINGS = {
    "deflate-1": lambda f: len(zlib.compress(part(f), 1)),
    "deflate-6": lambda f: len(zlib.compress(part(f), 6)),
    "deflate-9": lambda f: len(zlib.compress(part(f), 9)),
    "brotli-1": lambda f: len(brotli.compress(part(f), quality=1)),
    "brotli-5": lambda f: len(brotli.compress(part(f), quality=5)),
    "brotli-10": lambda f: len(brotli.compress(part(f), quality=10)),
    "brotli-11": lambda f: len(brotli.compress(part(f), quality=11)),
}


def main() -> int:
    lost = dict.fromkeys([*RANKINGS, "encoder"], 0)
    seconds = dict.fromkeys(lost, 0.0)
    for name, error in d14_errors().items():
        scene, _, _ = load(corpus_path(name))
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=error, compress=True, compact=True)
        with planefmt.open(io.BytesIO(buf.getvalue())) as r:
            shells = [g.shell for g in r.part_groups() if g.kind in shellwalk.WALK_KINDS]
        for shell in shells:
            options = [shellwalk.shell_walk_fields(shell, m, kind) for kind, m in shellwalk.codings(shellwalk.WALK_KINDS)]
            if "mode" not in options[0]:
                continue
            true = [len(brotli.compress(b"".join(f.values()), quality=11)) for f in options]
            best = min(true)
            picks = {}
            for key, score in RANKINGS.items():
                t0 = time.perf_counter()
                scores = [score(f) for f in options]
                seconds[key] += time.perf_counter() - t0
                picks[key] = true[scores.index(min(scores))]
            t0 = time.perf_counter()
            chosen = shellwalk._smallest([{k: f[k] for k in ("tables", "coordinates")} for f in options])
            seconds["encoder"] += time.perf_counter() - t0
            picks["encoder"] = true[[part(f) for f in options].index(part(chosen))]
            for key, size in picks.items():
                lost[key] += size - best
            worse = {k: s - best for k, s in picks.items() if s - best > 20}
            if worse:
                print(f"{name}: oracle {best} B; lost " + ", ".join(f"{k} {v}" for k, v in worse.items()), flush=True)
    for key in lost:
        print(f"{key:10s} lost {lost[key]:6d} B over the corpus, scores {seconds[key]:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
