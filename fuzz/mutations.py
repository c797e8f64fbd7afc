"""N mutations of the seed corpus through both readers, counting what issue 49 forbids: foreign
exceptions (outside PlnError), crashes, and inputs over 2 s. By hand, not in the test suite (its
verdict would depend on the machine's speed):

    python fuzz/mutations.py --runs 20000 --js-runs 2000 [--seed 1] [--save DIR]

Each mutation damages 1 (half the time) to 4 places of a seed (``fuzz/seeds.py``: the conformance files and
generated files, every group kind 0-13 among them): a byte set, a bit flipped, a run zeroed, a
varint lengthened, bytes cut or repeated; then, for most, the CRC of every chunk is recomputed
so that the damage reaches the payload parsers and the geometry decoders, not only the framing.
Python: ``decode_mesh`` in process, each input timed. JavaScript: ``fuzz/decode_many.mjs`` reads
the same kind of inputs (written to one file, each with its length) and decodes each with
``readPln(..., {decode: true})``. An input over 2 s, or one that raised a foreign exception, is
written to ``--save`` for fuzz/regressions/.
"""

from __future__ import annotations

import argparse
import io
import json
import random
import struct
import subprocess
import sys
import time
import traceback
import warnings
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

import seeds  # noqa: E402

SLOW_S = 2.0


def corpus() -> list[bytes]:
    files = list(seeds.generated().values())
    files += [p.read_bytes() for p in sorted((ROOT / "conformance").rglob("*.pln"))]
    return files


def chunks(data: bytes) -> list[tuple[int, int, int]]:
    """(type offset, payload offset, payload length) of each chunk that frames cleanly (§4.1)."""
    out, pos, major = [], 8, None
    while pos + 8 <= len(data):
        if major is None or major < 5:
            length, start = struct.unpack_from("<I", data, pos + 4)[0], pos + 8
        else:
            length, shift, start = 0, 0, pos + 4
            while start < len(data) and data[start] & 0x80 and shift < 35:
                length |= (data[start] & 0x7F) << shift
                shift += 7
                start += 1
            if start >= len(data):
                break
            length |= data[start] << shift
            start += 1
        if start + length + 4 > len(data):
            break
        if major is None and length:
            major = data[start]
        out.append((pos, start, length))
        pos = start + length + 4
    return out


def mutate(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    framing = chunks(data)
    for _ in range(rng.choice((1, 1, 1, 2, 3, 4))):
        if not b:
            break
        body = [c for c in framing if c[2]]
        if body and rng.random() < 0.8:
            _, start, length = rng.choice(body)
            at = start + rng.randrange(length)
        else:
            at = rng.randrange(len(b))
        at = min(at, len(b) - 1)  # an earlier cut may have shortened it
        how = rng.random()
        if how < 0.3:
            b[at] = rng.randrange(256)
        elif how < 0.55:
            b[at] ^= 1 << rng.randrange(8)
        elif how < 0.65:
            b[at:at + rng.randint(1, 8)] = bytes(min(8, len(b) - at))
        elif how < 0.75:
            b[at] = rng.choice([0x7F, 0x80, 0xFF, 0x00, 0x01])
        elif how < 0.85:
            b[at:at] = b[at:at + rng.randint(1, 16)]
        elif how < 0.95:
            del b[at:at + rng.randint(1, 16)]
        else:
            b = b[:at]
    if rng.random() < 0.85:
        for pos, start, length in chunks(bytes(b)):
            end = start + length
            b[end:end + 4] = struct.pack("<I", zlib.crc32(bytes(b[pos:pos + 4]) + bytes(b[start:end])))
    return bytes(b)


def inputs(runs: int, seed: int) -> list[bytes]:
    rng, files = random.Random(seed), corpus()
    return [mutate(rng.choice(files), rng) for _ in range(runs)]


def run_python(cases: list[bytes], save: Path | None) -> dict:
    import planefmt
    from planefmt.codec import decode_mesh
    warnings.simplefilter("ignore")  # skipped groups of newer minor versions: findings, not failures
    counts = {"inputs": len(cases), "results": 0, "errors": 0, "foreign": 0, "slow": 0, "slowest_s": 0.0}
    foreign: dict[str, int] = {}
    for i, data in enumerate(cases):
        t0 = time.perf_counter()
        try:
            decode_mesh(io.BytesIO(data))
            counts["results"] += 1
        except planefmt.PlnError:
            counts["errors"] += 1
        except Exception as exc:  # noqa: BLE001 - counted: anything outside PlnError
            counts["foreign"] += 1
            where = traceback.extract_tb(exc.__traceback__)[-1]
            key = f"{type(exc).__name__} at {Path(where.filename).name}:{where.lineno}"
            foreign[key] = foreign.get(key, 0) + 1
            if save:
                (save / f"py-foreign-{i}.pln").write_bytes(data)
        took = time.perf_counter() - t0
        counts["slowest_s"] = max(counts["slowest_s"], round(took, 3))
        if took > SLOW_S:
            counts["slow"] += 1
            if save:
                (save / f"py-slow-{i}.pln").write_bytes(data)
    counts["foreign_by_place"] = foreign
    return counts


def run_js(cases: list[bytes], save: Path | None) -> dict:
    blob = b"".join(struct.pack("<I", len(c)) + c for c in cases)
    path = (save or Path("/tmp")) / "js-inputs.bin"
    path.write_bytes(blob)
    proc = subprocess.run(["node", str(ROOT / "fuzz" / "decode_many.mjs"), str(path), str(SLOW_S)],
                          capture_output=True, text=True, cwd=ROOT)
    if proc.returncode != 0:
        return {"crash": proc.returncode, "stderr": proc.stderr[-500:]}
    report = json.loads(proc.stdout)
    if save:
        for i in report.get("foreign_at", []) + report.get("slow_at", []):
            (save / f"js-{i}.pln").write_bytes(cases[i])
    else:
        path.unlink()
    return report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=20_000)
    ap.add_argument("--js-runs", type=int, default=2_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--save", type=Path)
    args = ap.parse_args()
    if args.save:
        args.save.mkdir(parents=True, exist_ok=True)
    cases = inputs(max(args.runs, args.js_runs), args.seed)
    if args.runs:
        print("python decode_mesh:", json.dumps(run_python(cases[:args.runs], args.save)), flush=True)
    if args.js_runs:
        print("js readPln decode:", json.dumps(run_js(cases[:args.js_runs], args.save)), flush=True)


if __name__ == "__main__":
    main()
