""".pln against Draco, GLB and PLY on the corpus: bytes, error, speed and memory, measured in one run.

For every corpus mesh (the scene flattened to world coordinates, vertices
merged by exact position) and every codec:

* ``draco-11``, ``draco-14``: DracoPy (Google's Draco), quantization 11 and
  14 bits, compression level 10 (its smallest);
* ``glb`` (trimesh's binary glTF), ``ply`` (binary PLY, trimesh) and
  ``ply.gz`` (that PLY through gzip level 9): float32 positions, lossless up
  to float32 rounding; the PLY holds the mesh's face colours where it has some, as
  ``pln convert`` writes a PLY (the .pln holds them too: issue 30 asks for it to be smaller
  than the gzip'd PLY of the same mesh), the other peers its geometry alone;
* ``pln@T``: ``planefmt.codec.encode_scene`` at tolerance T (fraction of the
  bbox diagonal), the whole file with its chunks and object records, as
  ``pln convert`` writes it with its default scheme (convex bodies of up to
  256 planes as convex groups, everything else as one shell group per object,
  a shell walk of kind 9 or 10 where smaller: spec/pln.md §9.10 to §9.14; a
  group that repeats an earlier one as a copy, §9.15; bit-packed or predicted
  plane codes,
  varint group bodies and chunk heads, ``--compact``),
  payloads deflated where that saves bytes (spec §6, ``--compress``); the
  codec picks its coding (quantized or float planes). The source scene is
  encoded (nodes keep their transforms) and the decoded scene flattened again.
* ``pln@d14``, ``pln@d11``: the same at a tolerance per mesh, draco-14's
  (draco-11's) measured error on that mesh (at least the measure's
  resolution, below): what planes cost at an error no larger than Draco's.
  At these lossy tolerances the encoder drops the corners that carry no
  shape (inside one plane, on a straight crease), which Draco keeps;
  ``pln@d14 kept`` is pln@d14 with every corner kept (``keep_corners``).

Measured per codec: file bytes; bits per source triangle; the error, the
certified upper bound of the two-sided Hausdorff distance between the
decoded and the source surface (``planefmt.geometry.hausdorff.relative_hausdorff``,
stopping once its bounds are 1e-7 apart, relative to the source's bbox
diagonal), the same measure for every codec; encode and decode wall time,
each the least of up to ``REPEATS`` runs of the same call within
``REPEAT_BUDGET`` seconds (as timeit takes the least: the other runs measure
the machine, not the codec; a single run of a millisecond codec in a fresh
process also pays its first page faults), the same rule for every codec;
peak memory, the rise of the resident set above its level when the
measurement started (``VmHWM`` reset through ``/proc/self/clear_refs``), of
encode and decode. Each measurement runs in a forked child, so one codec's
memory is not another's and a timeout (``--timeout``) can stop it; a codec
that fails or times out is reported as such, never dropped. For ``pln@d14``
the report also splits the file's bytes into plane table, part groups and
the rest (``pln_parts``), with the coding the encoder chose, beside what
Draco spends on the mesh's connectivity (``draco_connectivity``: its file at
1-bit quantization) and the *floor* that gives: the pln@d14 file with its
part groups no dearer than that.

The summary gives, per corpus category, the median of ``pln@T`` bytes over
``draco-14`` bytes (over the meshes both encoded), how often pln is the
smaller of the two, and how often its measured error is no larger. Errors
below ``MEASURE_RESOLUTION`` (1e-12 of the diagonal) are float64 rounding,
not coding: a lossless float32 copy of a mesh (the glb and ply rows) measures
about 2e-14 against its source, so two such errors count as equal, and
``pln@d14`` is asked for at least that resolution.

Usage::

    python bench/compare.py                               # whole corpus -> docs/benchmarks.md
    python bench/compare.py --categories cad,convex       # some categories
    python bench/compare.py --tolerances 1e-6,1e-5 --out -   # print instead of writing
    python bench/compare.py --jobs 2                      # two meshes at a time (times of a loaded machine)
    python bench/compare.py --corpus ../shared/bench-corpus --out -   # the broader benchmark corpus
"""

from __future__ import annotations

import argparse
import concurrent.futures
import gzip
import io
import math
import multiprocessing
import os
import platform
import statistics
import sys
import time
import traceback
import warnings
from importlib import metadata

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
#: The test corpus in the repository (37 meshes, tests/corpus/SOURCES.md); ``--corpus`` names another
#: folder of the same categories, such as the broader benchmark corpus (bench/bench-corpus-SOURCES.md).
CORPUS = os.path.join(HERE, "..", "tests", "corpus")
#: Files beside a mesh that are parts of it (a .gltf's buffers and images), not meshes of their own.
SIDECARS = (".md", ".bin", ".png", ".jpg", ".jpeg")
DEFAULT_OUT = os.path.join(HERE, "..", "docs", "benchmarks.md")
#: Corpus folders and the category each reports under.
CATEGORIES = {"cad": "CAD", "convex": "convex", "nonconvex_watertight": "non-convex watertight", "open": "open",
              "smooth_dense": "smooth dense", "gltf_scene": "scenes", "usd": "scenes"}
DEFAULT_TOLERANCES = (1e-6, 1e-5, 1e-4)
DEFAULT_TIMEOUT = 1800.0
#: Stop gap of the Hausdorff measure, relative to the diagonal.
MEASURE_GAP = 1e-7
MEASURE_PIECES = 2_000_000
#: Errors below this fraction of the diagonal are rounding of the measure itself (see the docstring).
MEASURE_RESOLUTION = 1e-12
#: Runs of each encode and decode, the least time reported, while their total stays within the budget.
REPEATS = 5
REPEAT_BUDGET = 2.0


def timed(call):
    """``(least seconds, result)`` over up to :data:`REPEATS` runs of ``call()`` within :data:`REPEAT_BUDGET`."""
    times = []
    while True:
        t = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - t)
        if len(times) >= REPEATS or sum(times) >= REPEAT_BUDGET:
            return min(times), result


def no_larger(error: float, than: float) -> bool:
    """Whether a measured error is no larger than another, up to the measure's resolution."""
    return error <= max(than, MEASURE_RESOLUTION)


def load(path: str):
    """The corpus file as a scene and as one world-space mesh ``(vertices, faces)``, welded."""
    from planefmt.geometry.polygonize import weld
    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene, _ = registry.read(path)
    mesh = flatten(scene)
    v, f = weld(mesh.vertices, mesh.faces)
    return scene, v, f


def _peak_reset() -> int:
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
    return _status("VmRSS")


def _status(key: str) -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    return 0


def _draco(bits: int):
    def encode(scene, v, f):
        import DracoPy

        return DracoPy.encode(v, f, quantization_bits=bits, compression_level=10)

    def decode(data):
        import DracoPy

        m = DracoPy.decode(data)
        return np.asarray(m.points, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)

    return encode, decode


_coloured: list = [None, None]  # the last scene face_colours() was asked about, and its answer


def face_colours(scene) -> np.ndarray | None:
    """The face colours of ``scene`` flattened (None without), in the order of :func:`load`'s welded
    faces (welding keeps it); made once per scene, before the PLY peers' timed encodes ask for them."""
    from planefmt_converters.assemble import flatten

    if _coloured[0] is not scene:
        _coloured[:] = [scene, flatten(scene).face_colours]
    return _coloured[1]


def _trimesh_format(kind: str, compress: bool = False, colours: bool = False):
    def encode(scene, v, f):
        import trimesh

        data = trimesh.Trimesh(v, f, face_colors=face_colours(scene) if colours else None,
                               process=False).export(file_type=kind)
        return gzip.compress(data, 9) if compress else data

    def decode(data):
        import trimesh

        raw = gzip.decompress(data) if compress else data
        m = trimesh.load(io.BytesIO(raw), file_type=kind, force="mesh", process=False)
        return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)

    return encode, decode


def _pln(tolerance: float, keep_corners: bool = False):
    def encode(scene, v, f):
        from planefmt import codec

        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=tolerance, compress=True, compact=True, keep_corners=keep_corners)
        return buf.getvalue()

    def decode(data):
        from planefmt import codec
        from planefmt_converters.assemble import flatten

        mesh = flatten(codec.decode_scene(io.BytesIO(data)))
        return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)

    return encode, decode


def codecs(tolerances: tuple[float, ...]) -> dict:
    table = {"draco-11": _draco(11), "draco-14": _draco(14), "glb": _trimesh_format("glb"),
             "ply": _trimesh_format("ply", colours=True), "ply.gz": _trimesh_format("ply", compress=True, colours=True)}
    for t in tolerances:
        table[f"pln@{t:g}"] = _pln(t)
    return table


#: The pln codec whose tolerance is draco-14's measured error on the mesh.
MATCHED = "pln@d14"
#: The same with every corner of the source kept (``keep_corners``): what dropping the corners that carry no
#: shape (planefmt.geometry.redundant) takes off, reported beside, as Draco keeps every corner.
KEPT = "pln@d14 kept"
#: Each pln codec whose tolerance is a Draco codec's measured error, with that codec.
MATCHES = {MATCHED: "draco-14", "pln@d11": "draco-11", KEPT: "draco-14"}
#: Issue 31's targets: median pln@d14 / draco-14 bytes per category, at most.
TARGETS = {"CAD": 0.5, "convex": 0.4, "non-convex watertight": 1.0, "open": 1.0, "scenes": 1.0,
           "smooth dense": 1.3, "all": 0.8}


def _measure(path: str, name: str, tolerances: tuple[float, ...], matched: float | None, conn) -> None:
    """In the child: load, encode, decode, measure; send one result dict."""
    try:
        from planefmt.geometry.hausdorff import relative_hausdorff

        scene, v, f = load(path)
        if name in MATCHES:
            if matched is None:
                raise RuntimeError(f"{MATCHES[name]} gave no measured error to match")
            encode, decode = _pln(max(matched, MEASURE_RESOLUTION), keep_corners=name == KEPT)
        else:
            encode, decode = codecs(tolerances)[name]
        face_colours(scene)  # outside the timed encode, as the welding of v and f is
        base = _peak_reset()
        encode_time, data = timed(lambda: encode(scene, v, f))
        decode_time, (dv, df) = timed(lambda: decode(data))
        peak = _status("VmHWM") - base
        r = relative_hausdorff((v, f), (dv, df), tolerance=MEASURE_GAP, max_pieces=MEASURE_PIECES)
        conn.send({"bytes": len(data), "encode": encode_time, "decode": decode_time, "peak": peak,
                   "error": r.upper, "certified": r.certified, "triangles": len(f),
                   **({"parts": pln_parts(data)} if name.startswith("pln") else {}),
                   **({"connectivity": draco_connectivity(v, f)} if name == "draco-14" else {})})
    except Exception as exc:  # noqa: BLE001 - a codec's failure is a result of the bench, reported in its row
        conn.send({"failed": f"{type(exc).__name__}: {str(exc).splitlines()[0][:120] if str(exc) else ''}",
                   "trace": traceback.format_exc(limit=3)})
    finally:
        conn.close()


def draco_connectivity(v: np.ndarray, f: np.ndarray) -> int:
    """Bytes of Draco's file for the mesh at 1-bit quantization: its connectivity coding and about
    nothing of the positions, an estimate of what Draco spends on connectivity alone."""
    import DracoPy

    return len(DracoPy.encode(v, f, quantization_bits=1, compression_level=10))


def pln_parts(data: bytes) -> dict:
    """Where a .pln file's bytes go: plane table, part groups and the rest, each with its chunk framing."""
    from planefmt.container import reader

    with reader.Reader(io.BytesIO(data)) as r:
        for _ in r:
            pass
        q, coding = r.header.quantization, r.header.coding
    widths = f" {q.bits_nu}/{q.bits_phi}/{q.bits_h}" if coding.quantized else ""
    planes, groups = r.chunk_stats["PLNS"], r.chunk_stats["GRUP"]
    return {"planes": planes, "groups": groups, "rest": len(data) - planes - groups,
            "plane_count": r.plane_count, "group_count": r.group_count, "coding": coding.name.lower() + widths}


def measure(path: str, name: str, tolerances: tuple[float, ...], timeout: float,
            matched: float | None = None) -> dict:
    return run_forked(_measure, (path, name, tolerances, matched), timeout)


def run_forked(target, args: tuple, timeout: float) -> dict:
    """``target(*args, conn)`` in a forked child that sends one result dict on ``conn``, killed after
    ``timeout`` seconds; the dict, with its ``wall`` seconds (a ``failed`` reason where it gave none)."""
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=target, args=(*args, child))
    t = time.perf_counter()
    proc.start()
    child.close()
    result = {"failed": f"timeout after {timeout:g} s"}
    if parent.poll(timeout):
        try:
            result = parent.recv()
        except EOFError:
            result = {"failed": "the measuring process died"}
    if proc.is_alive():
        proc.kill()
    proc.join()
    result["wall"] = time.perf_counter() - t
    return result


def corpus_files(categories: list[str], corpus: str = CORPUS) -> list[tuple[str, str]]:
    """``(folder, path)`` of each mesh of the corpus's category folders, sorted; a mesh with sidecar
    files (the benchmark corpus's .gltf with its buffers and images) sits in a sub-folder of its own."""
    out = []
    for folder in categories:
        d = os.path.join(corpus, folder)
        for name in sorted(os.listdir(d)):
            path = os.path.join(d, name)
            inner = [os.path.join(path, n) for n in sorted(os.listdir(path))] if os.path.isdir(path) else [path]
            out += [(folder, p) for p in inner if os.path.isfile(p) and not p.lower().endswith(SIDECARS)]
    return out


def target_ratio(row: dict, key: str = MATCHED, peer: str = "draco-14") -> float:
    """``key`` bytes / ``peer`` bytes on one mesh; infinite where pln failed or measured a larger error."""
    pln, draco = row[key], row[peer]
    if "failed" in pln:
        return math.inf
    if "failed" in draco:
        return 0.0
    return pln["bytes"] / draco["bytes"] if no_larger(pln["error"], draco["error"]) else math.inf


def _fmt_err(r: dict) -> str:
    if "failed" in r:
        return "–"
    return f"{r['error']:.2g}" + ("" if r["certified"] else " (uncert.)")


def report(rows: list[dict], names: list[str], tolerances: tuple[float, ...], args) -> str:
    lines = ["# planefmt against Draco, GLB and PLY", "",
             "Generated by `python bench/compare.py" + (f" --categories {args.categories}" if args.categories else "")
             + (f" --tolerances {args.tolerances}" if args.tolerances else "")
             + (f" --jobs {args.jobs}" if args.jobs != 1 else "")
             + (f" --timeout {args.timeout:g}" if args.timeout != DEFAULT_TIMEOUT else "") + "`; the script's docstring says "
             "what is measured and how.", "", _machine(args.jobs), ""] + ([args.note, ""] if args.note else [])
    lines += ["## Summary per category", "",
              "Median of pln bytes / draco-14 bytes over the meshes both encoded; *smaller*: meshes where the pln "
              "file is the smaller; *error ≤*: meshes where pln's measured error is no larger than draco-14's.", ""]
    keys = [f"pln@{t:g}" for t in tolerances] + [MATCHED]
    head = "| category | meshes | " + " | ".join(f"{k} median ratio | smaller | error ≤" for k in keys)
    lines += [head + " |", "|" + "---|" * (2 + 3 * len(keys))]
    cats = list(dict.fromkeys(r["category"] for r in rows))
    for cat in cats + ["all"]:
        mine = [r for r in rows if cat in ("all", r["category"])]
        cells = [cat, str(len(mine))]
        for key in keys:
            both = [r for r in mine if "failed" not in r[key] and "failed" not in r["draco-14"]]
            ratios = [r[key]["bytes"] / r["draco-14"]["bytes"] for r in both]
            cells.append(f"{statistics.median(ratios):.2f}" if ratios else "–")
            cells.append(f"{sum(x < 1 for x in ratios)}/{len(mine)}")
            cells.append(f"{sum(no_larger(r[key]['error'], r['draco-14']['error']) for r in both)}/{len(mine)}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "A codec that failed or ran out of time counts against it in *smaller* and *error ≤* "
              f"(the denominators are all meshes). {MATCHED}: pln at draco-14's measured error as its "
              "tolerance, mesh by mesh.", ""]
    # pln at 1e-4 against draco-11, whose measured errors on the corpus lie above 1e-4.
    points = [(MATCHED, "draco-14")] + [(f"pln@{t:g}", "draco-11") for t in tolerances if t == 1e-4] + \
        [(k, p) for k, p in MATCHES.items() if k != MATCHED and k in names]
    lines += ["## Targets against Draco at no larger error", "",
              "Median over all meshes of the category of pln bytes / Draco bytes, where a mesh on which pln "
              "failed or measured a larger error than the Draco file it is compared with counts as infinitely "
              f"large; the targets (issue 31) are for {MATCHED} / draco-14, the other columns the same measure at "
              f"other operating points (pln@d11: pln at draco-11's measured error; {KEPT}: {MATCHED} with every "
              "source corner kept, as Draco keeps them).", "",
              "| category | meshes | target | " + " | ".join(f"{k} / {p}" for k, p in points) + " | target met |",
              "|" + "---|" * (4 + len(points))]
    for cat in cats + ["all"]:
        mine = [r for r in rows if cat in ("all", r["category"])]
        medians = [statistics.median([target_ratio(r, k, p) for r in mine]) if mine else math.inf for k, p in points]
        target = TARGETS.get(cat, math.inf)
        lines.append(f"| {cat} | {len(mine)} | {target:.1f} | " + " | ".join(f"{m:.2f}" for m in medians)
                     + f" | {'yes' if medians[0] <= target else 'no'} |")
    lines.append("")
    lines += ["## Bytes and measured error per mesh", "",
              "Bytes (bits per source triangle) and the certified Hausdorff upper bound relative to the bbox "
              "diagonal; *uncert.*: the bound's budget ran out, the value is still an upper bound.", ""]
    lines += ["| mesh | triangles | " + " | ".join(names) + " |", "|" + "---|" * (2 + len(names))]
    for r in rows:
        cells = [f"{r['category']}/{r['file']}", str(r["triangles"])]
        for n in names:
            c = r[n]
            cells.append(f"{c['failed'][:60]}" if "failed" in c else
                         f"{c['bytes']:,} ({8 * c['bytes'] / max(r['triangles'], 1):.1f}) {_fmt_err(c)}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", f"## Where {MATCHED}'s bytes go", "",
              "Bytes of the plane table (`PLNS` chunks), of the part groups (`GRUP` chunks: references, roles, "
              "trees or cells) and of the rest (signature, header, objects, index, end), each with its chunk "
              "framing; bits per plane of the plane table; the coding (widths of ν, φ, h) the encoder chose. "
              "*Draco connectivity*: Draco's file at 1-bit quantization (`draco_connectivity`), about what Draco "
              "spends on connectivity alone; *floor*: plane table + rest + the smaller of part groups and Draco "
              f"connectivity, over draco-14 bytes: what {MATCHED} would weigh with its planes coded as they are and "
              "its part groups no dearer than Draco's connectivity (an estimate, not a measurement of a pln file); "
              "*plane table alone*: plane table over draco-14 bytes, under which no coding of part groups can take "
              f"{MATCHED} while its planes are coded as they are.",
              "",
              "| mesh | bytes | planes | plane table | bits per plane | coding | part groups | rest | "
              "Draco connectivity | floor | plane table alone |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    floors: dict[str, list[float]] = {}
    alone: dict[str, list[float]] = {}
    for r in rows:
        c, d = r[MATCHED], r["draco-14"]
        if "parts" not in c:
            # No file to split: as in the target, a pln@d14 that failed counts as infinitely large.
            floors.setdefault(r["category"], []).append(math.inf)
            alone.setdefault(r["category"], []).append(math.inf)
            continue
        p = c["parts"]
        conn, floor, table = "–", "–", "–"
        if "connectivity" in d:
            ratio = (p["planes"] + p["rest"] + min(p["groups"], d["connectivity"])) / d["bytes"]
            fair = no_larger(c["error"], d["error"])
            floors.setdefault(r["category"], []).append(ratio if fair else math.inf)
            alone.setdefault(r["category"], []).append(p["planes"] / d["bytes"] if fair else math.inf)
            conn, floor, table = f"{d['connectivity']:,}", f"{ratio:.2f}", f"{p['planes'] / d['bytes']:.2f}"
        lines.append(f"| {r['category']}/{r['file']} | {c['bytes']:,} | {p['plane_count']:,} | {p['planes']:,} | "
                     f"{8 * p['planes'] / max(p['plane_count'], 1):.1f} | {p['coding']} | "
                     f"{p['groups']:,} ({p['group_count']}) | {p['rest']:,} | {conn} | {floor} | {table} |")
    if floors:
        lines += ["", f"Median per category (a mesh on which {MATCHED} failed or measured a larger error than "
                  "draco-14 counts as infinite, as in the target), floor: " + "; ".join(
                      f"{cat} {statistics.median(v):.2f}" for cat, v in floors.items())
                  + "; plane table alone: " + "; ".join(f"{cat} {statistics.median(v):.2f}" for cat, v in alone.items())
                  + "."]
    lines += speed_summary(rows, names)
    lines += ["", "## Speed and memory per mesh", "",
              f"Encode / decode wall time in ms (the least of up to {REPEATS} runs within {REPEAT_BUDGET:g} s, every "
              "codec alike), and peak memory (MB above the start of the measurement).", ""]
    lines += ["| mesh | " + " | ".join(names) + " |", "|" + "---|" * (1 + len(names))]
    for r in rows:
        cells = [f"{r['category']}/{r['file']}"]
        for n in names:
            c = r[n]
            cells.append("–" if "failed" in c else
                         f"{1e3 * c['encode']:.0f} / {1e3 * c['decode']:.0f}, {c['peak'] / 2**20:.0f} MB")
        lines.append("| " + " | ".join(cells) + " |")
    failures = [(r, n) for r in rows for n in names if "failed" in r[n]]
    if failures:
        lines += ["", "## Failures", ""]
        lines += [f"- {r['category']}/{r['file']}, {n}: {r[n]['failed']}" for r, n in failures]
    return "\n".join(lines) + "\n"


def speed_summary(rows: list[dict], names: list[str], peer: str = "draco-14", least: int = 1000) -> list[str]:
    """Issue 30's speed figures per pln column: the slowest encode and decode, the largest peak memory,
    and against ``peer`` measured in the same run, over the meshes of ``least`` triangles or more,
    the geometric mean of decode speed (output triangles per second) and the median of encode
    speed (input triangles per second) as ratios."""
    lines = ["", "## Speed against Draco", "",
             f"Over the {sum(1 for r in rows if r[peer].get('triangles', 0) >= least)} meshes of {least:,} triangles "
             f"or more: pln's speed / {peer}'s (same triangles, so the ratio of {peer}'s time to pln's), the "
             "geometric mean for decoding and the median for encoding; and over every mesh, the slowest "
             "encode and decode and the largest peak memory. A failed run counts as zero speed.", "",
             "| codec | decode speed ratio (geo. mean) | encode speed ratio (median) | slowest encode s | "
             "slowest decode s | largest peak MB |", "|---|---|---|---|---|---|"]
    for n in names:
        if not n.startswith("pln"):
            continue
        both = [(r[n], r[peer]) for r in rows if "failed" not in r[peer] and r[peer]["triangles"] >= least]
        decode = [max(d["decode"], 1e-6) / max(c["decode"], 1e-6) if "failed" not in c else 0.0 for c, d in both]
        encode = [max(d["encode"], 1e-6) / max(c["encode"], 1e-6) if "failed" not in c else 0.0 for c, d in both]
        ok = [r[n] for r in rows if "failed" not in r[n]]
        geo = math.exp(statistics.fmean(math.log(x) for x in decode)) if decode and min(decode) > 0 else 0.0
        lines.append(f"| {n} | {geo:.3f} | {statistics.median(encode) if encode else 0.0:.4f} | "
                     + (f"{max(c['encode'] for c in ok):.2f} | {max(c['decode'] for c in ok):.3f} | "
                        f"{max(c['peak'] for c in ok) / 2**20:.0f} |" if len(ok) == len(rows) else
                        f"failed on {len(rows) - len(ok)} | – | – |"))
    return lines


def _machine(jobs: int = 1) -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    versions = ", ".join(f"{p} {_version(p)}" for p in ("planefmt", "DracoPy", "trimesh", "numpy", "scipy"))
    return (f"Machine: {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, {platform.system()}; "
            f"{versions}; run {time.strftime('%Y-%m-%d')}, "
            + ("one measurement at a time." if jobs == 1 else f"{jobs} meshes measured at once."))


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "?"


def measure_file(folder: str, path: str, names: list[str], tolerances: tuple[float, ...], timeout: float) -> dict:
    """One corpus file's row: every codec measured in turn (each Draco codec before the pln codec that
    matches its error, :data:`MATCHES`)."""
    row = {"category": CATEGORIES[folder], "file": os.path.basename(path), "triangles": 0}
    for n in names:
        peer = row.get(MATCHES.get(n, ""), {})
        r = measure(path, n, tolerances, timeout, None if "failed" in peer else peer.get("error"))
        row[n] = r
        row["triangles"] = max(row["triangles"], r.get("triangles", 0))
        status = r["failed"] if "failed" in r else f"{r['bytes']} B, error {r['error']:.2g}"
        print(f"{folder}/{os.path.basename(path)} {n}: {status} ({r['wall']:.1f} s)", file=sys.stderr, flush=True)
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", help="comma-separated corpus folders (default: all): " + ", ".join(CATEGORIES))
    ap.add_argument("--tolerances", help="comma-separated pln tolerances (default 1e-6,1e-5,1e-4)")
    # ADIS16480.STL's pln@d14 (encode, decode, certified measure) took about 900 s on a 2-core EPYC.
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, help="seconds per measurement (default 1800)")
    ap.add_argument("--jobs", type=int, default=1,
                    help="meshes measured at once (default 1; more load the machine, so times rise)")
    ap.add_argument("--out", default=DEFAULT_OUT, help="markdown file to write, - for stdout")
    ap.add_argument("--note", help="a paragraph on the run's conditions, printed under the machine line")
    ap.add_argument("--corpus", default=CORPUS,
                    help="folder of category folders (default: tests/corpus; e.g. ../shared/bench-corpus)")
    args = ap.parse_args(argv)
    folders = args.categories.split(",") if args.categories else list(CATEGORIES)
    unknown = [c for c in folders if c not in CATEGORIES]
    if unknown:
        ap.error(f"unknown categories: {', '.join(unknown)}")
    tolerances = tuple(float(t) for t in args.tolerances.split(",")) if args.tolerances else DEFAULT_TOLERANCES
    names = list(codecs(tolerances)) + list(MATCHES)
    # Imported once here, so that every forked measurement starts with them loaded.
    import DracoPy  # noqa: F401
    import trimesh  # noqa: F401

    import planefmt.codec  # noqa: F401
    import planefmt.geometry.hausdorff  # noqa: F401
    import planefmt_converters.registry  # noqa: F401
    files = corpus_files(folders, args.corpus)
    if args.jobs == 1:
        rows = [measure_file(folder, path, names, tolerances, args.timeout) for folder, path in files]
    else:
        # Meshes in worker processes (not daemonic, so their measurements can fork), the largest
        # files first: the slow ones do not start last. Rows stay in corpus order.
        ctx = multiprocessing.get_context("fork")
        with concurrent.futures.ProcessPoolExecutor(args.jobs, mp_context=ctx) as pool:
            order = sorted(range(len(files)), key=lambda i: -os.path.getsize(files[i][1]))
            futures = {i: pool.submit(measure_file, *files[i], names, tolerances, args.timeout) for i in order}
            rows = [futures[i].result() for i in range(len(files))]
    text = report(rows, names, tolerances, args)
    if args.out == "-":
        sys.stdout.write(text)
    else:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as fh:
            fh.write(text)
        print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
