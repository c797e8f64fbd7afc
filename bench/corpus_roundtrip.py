"""Every corpus file to .pln at each tolerance and back to each output format, checked against its
source (issues 5, 35 and 50).

For each file of ``tests/corpus`` (or the paths given) and each tolerance of ``--tolerances`` (default
1e-6; ``d14`` stands for Draco-14's measured error on the file, see below):

1. ``pln convert --tolerance T SOURCE x.pln`` (the CLI as users run it, in a subprocess with
   ``--timeout`` seconds; with ``--allow-open``, so that closed meshes planes cannot close are stored as
   open surfaces; ``--scheme paper`` with ``--scheme paper``); a refusal fails the file (issue 50 item 7:
   every mesh with triangles converts at every tolerance);
2. ``pln convert -v x.pln x.EXT`` for every format it writes: OBJ, PLY, STL, OFF, GLB, glTF, USDA, USDC
   and USDZ (in this process, through the CLI's ``main``), the error bound it prints kept ("error at most B of the diagonal": the bound ``pln info``
   reports for the .pln file, plus float32 rounding for a float32 output, issue 50 item 5);
3. each output reloaded through the project's readers (trimesh for OBJ, PLY and glTF, pxr for USD) and
   compared with the source (glTF's in metres and Y up, as written). The .pln file's own decoding (flattened) is measured against the source
   once: the certified two-sided Hausdorff distance must be at most the error bound recorded in its
   header. An output with the decoding's triangles and vertex order is then within that bound plus its
   largest vertex displacement from the decoding (corresponding vertices at most d apart put every point
   of the surface within d), which must be at most float32 rounding (1e-7 of the largest coordinate);
   any other output (its vertices welded or split) by its certified distance from the decoding, held to
   the same rounding, or failing that (the measure's budget runs out so close), by its certified
   distance from the source, held to the header's tolerance (``ok*``). For glTF and USD the names of the
   nodes that carry meshes must be the .pln file's, in order;
4. the bound the output's conversion printed must hold for the output: its distance from the source
   (the decoding's certified distance plus the output's from the decoding, by the triangle inequality,
   or where that sum is larger, the output's own certified distance from the source) at most the
   printed bound times the diagonal of the decoding. A bound under 1e-9 of the diagonal (``MEASURE_FLOOR``:
   the measure's own gap; Draco-14's error on an exact cube is 2e-14) is checked to 1e-9, and the row
   says so;
5. what issue 35 asks of every output (items 4-6), the .pln file itself included: it holds no more
   zero-area triangles (no plane, as the .pln encoder measures them, plus those the reader dropped
   because welding equal positions left them a repeated corner) than the source as read; where the
   source is closed as read (every edge of every object shared by two triangles running opposite ways,
   vertices welded by position as read), so is the output, after its float32 rounding; and where the
   source is still closed once welded by position across objects (what trimesh and most tools do on
   load, issue 50 item 6), so is the output welded alike. At the default tolerance (1e-6) only, and
   unless ``--no-reencode``, each output also re-encodes with ``pln convert OUTPUT re.pln`` (in this process, through the CLI's
   ``main``: exit 0).

Over the tolerances of one file, the .pln file must be no larger at a looser tolerance than at a tighter
one (issue 50 item 7).

Draco-14's error (``d14``): the certified Hausdorff distance of DracoPy's 14-bit decoding from the
welded source over its diagonal, as ``bench/at_draco.py`` measures it (at least 1e-12, the measure's
resolution), read from ``--draco-cache``
(``bench/draco-errors.json``, keyed by the path relative to the bench corpus, ``../shared/bench-corpus``,
or else to the repository, and the bits), measured and added there where missing or of another DracoPy version.

A row per file and tolerance: the .pln bytes and encode seconds, whether the source is closed (as read;
``closed+`` once welded too), then ``ok`` or what failed per format (``re.pln``: the .pln file
re-encoded). Exit 1 if anything failed. ``--jobs N`` checks N files at a time.

Usage::

    python bench/corpus_roundtrip.py [--timeout 1200] [--tolerances 1e-6,1e-5,1e-4,d14] [--jobs 1]
        [--allow-open] [--scheme paper] [FILE ...]
"""

from __future__ import annotations

import argparse
import contextlib
import glob
import io
import json
import multiprocessing
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CORPUS = os.path.join(ROOT, "tests", "corpus")
BENCH_CORPUS = os.path.join(ROOT, "..", "shared", "bench-corpus")
DRACO_CACHE = os.path.join(HERE, "draco-errors.json")
FORMATS = ("obj", "ply", "stl", "off", "glb", "gltf", "usda", "usdc", "usdz")
SCENES = ("glb", "gltf", "usda", "usdc", "usdz")
#: The CLI's default tolerance: the one issue 35's re-encoding check runs at.
DEFAULT_TOLERANCE = 1e-6
#: Rounding of float32 outputs, relative to the largest coordinate.
FLOAT32_ROUNDING = 1e-7
#: The least distance, as a fraction of the diagonal, a check asks a certified measure to show: under it
#: (a Draco-14 error of 2e-14 on an exact cube) refinement cannot separate the distance from rounding and
#: runs to its budget (gigabytes); planefmt.geometry.hausdorff's own default gap.
MEASURE_FLOOR = 1e-9
#: Budget of each certified measure (the decoding against the source, a re-indexed output against the decoding).
DECODING_PIECES = 8_000_000
PLN = [sys.executable, "-m", "planefmt_converters.cli"]
#: The CLI's exit code after Ctrl-C or SIGTERM.
INTERRUPTED = 130
#: The bound a conversion prints: ``-v``'s summary line.
PRINTED_BOUND = re.compile(r"error at most ([0-9.e+-]+) of the diagonal")
DRACO_BITS = 14


def corpus_files() -> list[str]:
    return sorted(f for f in glob.glob(os.path.join(CORPUS, "*", "*")) if not f.endswith((".md", ".bin")))


def label(path: str) -> str:
    """``path`` relative to the corpus, the bench corpus (``bench:``) or the repository."""
    full = os.path.abspath(path)
    for root, prefix in ((CORPUS, ""), (BENCH_CORPUS, "bench:")):
        root = os.path.abspath(root)
        if full.startswith(root + os.sep):
            return prefix + os.path.relpath(full, root)
    return os.path.relpath(full, ROOT)


def _draco_key(path: str) -> str:
    """The cache's key of ``path``: relative to the bench corpus (as ``bench/at_draco.py`` keys it), else to
    the repository (``tests/corpus/...``), and the bits."""
    full = os.path.abspath(path)
    bench = os.path.abspath(BENCH_CORPUS)
    rel = os.path.relpath(full, bench if full.startswith(bench + os.sep) else ROOT)
    return f"{rel}@{DRACO_BITS}"


def draco_error(path: str, cache_path: str) -> float:
    """Draco-14's measured error on ``path`` (fraction of the diagonal), from the cache or measured into it."""
    sys.path.insert(0, HERE)
    from at_draco import _draco, _dracopy

    cache = json.load(open(cache_path)) if os.path.exists(cache_path) else {}
    key = _draco_key(path)
    if key not in cache or cache[key].get("dracopy") != _dracopy():
        cache = json.load(open(cache_path)) if os.path.exists(cache_path) else {}
        cache[key] = _draco(path, DRACO_BITS)
        with open(cache_path, "w") as fh:
            json.dump(cache, fh, indent=0, sort_keys=True)
    return float(cache[key]["error"])


def _convert(src: str, dst: str, timeout: float, options: tuple[str, ...] = ()) -> tuple[str | None, str]:
    """Run ``pln convert``: the last stderr line if it failed, and its stderr."""
    try:
        run = subprocess.run(PLN + ["convert", *options, src, dst], capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"timeout after {timeout:g} s", ""
    if run.returncode != 0:
        return (run.stderr.strip().splitlines() or [f"exit {run.returncode}"])[-1][:160], run.stderr
    return None, run.stderr


def _read(path: str):
    """``(scene, triangles the reader dropped as degenerate)`` of a mesh file."""
    from planefmt_converters import registry

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene, notes = registry.read(path)
    degenerate = [int(n.split()[0]) for n in notes if n.endswith(" degenerate faces")]
    return scene, sum(degenerate)


def _zero_area(mesh, degenerate: int) -> int:
    from planefmt_converters.assemble import with_area

    return degenerate + int(len(mesh.faces) - np.count_nonzero(with_area(mesh.vertices, mesh.faces)))


def _closed(mesh) -> bool:
    from planefmt.geometry.topology import is_closed_manifold

    return is_closed_manifold(mesh.faces, len(mesh.vertices))


def _closed_welded(mesh) -> bool:
    """Closed once every vertex is welded by position, across objects too (as trimesh loads a file)."""
    from planefmt.geometry.polygonize import weld
    from planefmt.geometry.topology import is_closed_manifold

    v, f = weld(mesh.vertices, mesh.faces)
    return is_closed_manifold(f, len(v))


def _in_process(args: list[str]) -> tuple[str | None, str]:
    """``pln ARGS`` through the CLI's ``main`` in this process: the last stderr line if it did not exit
    0, and its stderr."""
    from planefmt_converters.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(args)
    if code == INTERRUPTED:
        # The CLI turns Ctrl-C and SIGTERM into this exit code: they stop the run, not fail a file.
        raise KeyboardInterrupt
    if code == 0:
        return None, err.getvalue()
    return f"exit {code}: " + ((err.getvalue().strip().splitlines() or [""])[-1][:140]), err.getvalue()


def _reencodes(path: str, work: str) -> str | None:
    """``pln convert PATH re.pln`` at the default tolerance; the error line if it did not exit 0."""
    failed, _ = _in_process(["convert", "--force", path, os.path.join(work, "re.pln")])
    return None if failed is None else "re-encoding " + failed


def _issue35(out: str, back, degenerate: int, source: dict, work: str, reencode: bool) -> str | None:
    """What ``out`` (read back as the flattened ``back``) fails of issue 35's items 4-6 and issue 50's
    item 6, or None."""
    mesh_zero = _zero_area(back, degenerate)
    if mesh_zero > source["zero"]:
        return f"{mesh_zero} zero-area triangles (source: {source['zero']})"
    if source["closed"] and not _closed(back):
        return "open where the source is closed"
    if source["welded"] and not _closed_welded(back):
        return "open once welded by position, where the source is closed so"
    return _reencodes(out, work) if reencode else None


def _source(path: str) -> dict:
    """What every tolerance's check of ``path`` compares with: the source as read, flattened."""
    from planefmt_converters.assemble import flatten

    read, degenerate = _read(path)
    mesh = flatten(read)
    closed = _closed(mesh)
    return {"read": read, "mesh": mesh, "zero": _zero_area(mesh, degenerate), "closed": closed,
            "welded": closed and _closed_welded(mesh)}


def _printed_bound(stderr: str) -> float | None:
    found = PRINTED_BOUND.search(stderr)
    return float(found.group(1)) if found else None


def _within_bound(printed: float | None, to_decoding: float, decoding: float, diag: float, back, src) -> str | None:
    """Whether an output (read back as ``back``, ``to_decoding`` at most from the decoding, itself at most
    ``decoding`` from the source) lies within the bound its conversion printed, of ``diag`` (at least
    :data:`MEASURE_FLOOR`)."""
    from planefmt.geometry.hausdorff import hausdorff

    if printed is None:
        return "no error bound printed"
    allowed = max(printed, MEASURE_FLOOR) * diag
    if to_decoding + decoding <= allowed:
        return None
    r = hausdorff(back.vertices, back.faces, src.vertices, src.faces, target=allowed, max_pieces=DECODING_PIECES)
    if r.certified and r.upper <= allowed:
        return None
    return f"{r.lower / diag:.3g}..{r.upper / diag:.3g} of the diagonal from the source, over its printed bound {printed:g}"


def check(path: str, timeout: float, work: str, tolerance: float = DEFAULT_TOLERANCE, allow_open: bool = False,
          scheme: str = "shell", source: dict | None = None, reencode: bool = True) -> tuple[str, list[str], int | None]:
    """The row of one file at one tolerance, its failures and the .pln file's bytes (None if not written)."""
    import planefmt
    from planefmt.geometry.hausdorff import hausdorff
    from planefmt.model import Units
    from planefmt_converters.assemble import flatten, in_metres, reoriented

    source = source or _source(path)
    read = source["read"]
    pln = os.path.join(work, os.path.basename(path) + ".pln")
    t = time.perf_counter()
    failed, _ = _convert(path, pln, timeout, (("--allow-open",) if allow_open else ())
                         + ("--scheme", scheme, "--tolerance", repr(tolerance), "--force"))
    seconds = time.perf_counter() - t
    state = "closed+" if source["welded"] else "closed" if source["closed"] else "open"
    head = f"| {label(path)} | {tolerance:.3g} | {state} |"
    if failed:
        return f"{head} – | {seconds:.0f} | " + " | ".join("–" for _ in FORMATS) + f" | – | {failed} |", [failed], None
    size = os.path.getsize(pln)
    decoded, _ = _read(pln)
    with planefmt.open(pln) as f:
        bound, header_tolerance = f.header.error_bound, f.header.tolerance
    names = [n.name for n in decoded.nodes if n.mesh is not None]
    dec = flatten(decoded)
    v, faces = source["mesh"].vertices, source["mesh"].faces
    diag = float(np.linalg.norm(np.ptp(v[np.unique(faces)], axis=0)))
    # The header's bound is relative to the decoded scene's diagonal (spec §5); two certified measures of
    # one distance differ by their rounding margins (planefmt.geometry.hausdorff: 64 eps of the magnitude).
    box = float(np.linalg.norm(np.ptp(dec.vertices[np.unique(dec.faces)], axis=0)))
    margin = 128.0 * np.finfo(np.float64).eps * (float(np.abs(v).max()) + diag)
    limit = max(bound * box + margin, MEASURE_FLOOR * diag)
    floored = limit > bound * box + margin
    r = hausdorff(dec.vertices, dec.faces, v, faces, target=limit, max_pieces=DECODING_PIECES)
    if not (r.certified and r.upper <= limit):
        why = (f"decoding {r.lower / diag:.2g}..{r.upper / diag:.2g} from the source, header bound {bound:.2g}"
               + ("" if r.certified else f" (not certified within {DECODING_PIECES:,} pieces)"))
        return f"{head} {size:,} | {seconds:.0f} | " + " | ".join("–" for _ in FORMATS) + \
            f" | – | {why} |", [why], size
    decoding = r.upper
    reencode = reencode and tolerance == DEFAULT_TOLERANCE
    cells, problems, loose = [], [], []
    for ext in FORMATS:
        out = os.path.join(work, os.path.basename(path) + "." + ext)
        why, said = _in_process(["convert", "-v", "--force", pln, out])
        if why is None:
            again, dropped = _read(out)
            back = flatten(again)
            # A format with units and an up axis of its own (glTF: metres, Y up) holds the decoding
            # scaled and turned into them: distances there are ``k`` times the source's.
            metres = in_metres if again.units == Units.METRE else (lambda scene: scene)
            dec, src = (flatten(decoded), source["mesh"]) if again.up_axis is None else (
                flatten(reoriented(metres(decoded), again.up_axis)),
                flatten(reoriented(metres(read), again.up_axis)))
            k = (float(np.linalg.norm(np.ptp(dec.vertices[np.unique(dec.faces)], axis=0))) / box) if box > 0 else 1.0
            near = FLOAT32_ROUNDING * float(np.abs(src.vertices).max())
            if back.vertices.shape == dec.vertices.shape and np.array_equal(back.faces, dec.faces):
                moved = float(np.linalg.norm(back.vertices - dec.vertices, axis=1).max(initial=0.0))
                if moved > near:
                    why = f"vertices moved {moved / (k * diag):.2g} of the diagonal from the decoding"
            else:
                # Re-indexed (welded or split vertices): its distance from the decoding, certified.
                q = hausdorff(back.vertices, back.faces, dec.vertices, dec.faces, target=near,
                              max_pieces=DECODING_PIECES)
                moved = q.upper
                if not (q.certified and q.upper <= near):
                    moved = np.inf
                    # Not shown within float32 rounding of the decoding: then held to what the header
                    # promises, the requested tolerance, against the source itself.
                    allowed = max(header_tolerance, MEASURE_FLOOR) * k * box
                    s = hausdorff(back.vertices, back.faces, src.vertices, src.faces, target=allowed,
                                  max_pieces=DECODING_PIECES)
                    if s.certified and s.upper <= allowed:
                        loose.append(ext)
                    else:
                        d = k * diag
                        why = (f"{q.lower / d:.2g}..{q.upper / d:.2g} of the diagonal from the decoding, "
                               f"over float32 rounding {near / d:.2g}, and {s.lower / d:.2g}.."
                               f"{s.upper / d:.2g} from the source, over the tolerance {header_tolerance:g}")
            if why is None and ext in SCENES and [n.name for n in again.nodes if n.mesh is not None] != names:
                why = "node names differ"
            why = why or _within_bound(_printed_bound(said), moved, k * decoding, k * box, back, src)
            why = why or _issue35(out, back, dropped, source, work, reencode)
        cells.append(("ok*" if ext in loose else "ok") if why is None else f"FAIL: {why}")
        if why is not None:
            problems.append(f"{ext}: {why}")
    again = _issue35(pln, flatten(decoded), 0, source, work, reencode)
    if again:
        problems.append(f"re.pln: {again}")
    note = f"bounds under {MEASURE_FLOOR:g} measured to {MEASURE_FLOOR:g}" if floored else ""
    return (f"{head} {size:,} | {seconds:.0f} | " + " | ".join(cells)
            + f" | {'ok' if again is None else 'FAIL: ' + again} | {note} |"), problems, size


def tolerances_of(path: str, spec: list[str], draco_cache: str) -> list[float]:
    """The tolerances ``spec`` names for ``path``, tightest first (``d14``: Draco-14's measured error)."""
    sys.path.insert(0, HERE)
    from compare import MEASURE_RESOLUTION

    out = {max(draco_error(path, draco_cache), MEASURE_RESOLUTION) if t == "d14" else float(t) for t in spec}
    return sorted(out)


def check_file(path: str, timeout: float, spec: list[str], allow_open: bool, scheme: str,
               draco_cache: str, reencode: bool = True) -> tuple[list[str], list[str]]:
    """The rows of one file at every tolerance, and its failures, sizes that grow as the tolerance
    loosens among them."""
    rows, problems, sizes = [], [], []
    with tempfile.TemporaryDirectory() as work:
        try:
            tolerances = tolerances_of(path, spec, draco_cache)
        except Exception as err:  # noqa: BLE001 - Draco or the reader refusing the file is a row, not the run's end
            return [f"| {label(path)} | – | – | – | – | " + " | ".join("–" for _ in FORMATS)
                    + f" | – | Draco-14's error not measured: {err} |"], [str(err)]
        source = _source(path)
        for tolerance in tolerances:
            row, failed, size = check(path, timeout, work, tolerance, allow_open, scheme, source, reencode)
            rows.append(row)
            problems += [f"{tolerance:g}: {p}" for p in failed]
            sizes.append((tolerance, size))
    written = [(t, s) for t, s in sizes if s is not None]
    for (t0, s0), (t1, s1) in zip(written, written[1:]):
        if s1 > s0:
            problems.append(f"{s1:,} B at {t1:.3g}, larger than {s0:,} B at {t0:.3g}")
    return rows, problems


def _check_file(job: tuple) -> tuple[str, list[str], list[str]]:
    return (job[0], *check_file(*job))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per conversion (default 1200)")
    ap.add_argument("--tolerances", default="1e-6",
                    help="comma-separated tolerances, d14 for Draco-14's measured error (default 1e-6)")
    ap.add_argument("--draco-cache", default=DRACO_CACHE, help="Draco-14's errors by file (default bench/draco-errors.json)")
    ap.add_argument("--jobs", type=int, default=1, help="files checked at a time (default 1)")
    ap.add_argument("--allow-open", action="store_true", help="pass --allow-open to the conversion to .pln")
    ap.add_argument("--no-reencode", action="store_true", help="skip issue 35's re-encoding of every output")
    ap.add_argument("--scheme", choices=("shell", "paper"), default="shell", help="the conversion to .pln's scheme")
    args = ap.parse_args(argv)
    spec = args.tolerances.split(",")
    files = args.files or corpus_files()
    print("| file | tolerance | source | .pln B | encode s | " + " | ".join(FORMATS) + " | re.pln | failure |")
    print("|---|---:|---|---:|---:|" + "---|" * len(FORMATS) + "---|---|")
    failures, growing = [], 0
    jobs = [(path, args.timeout, spec, args.allow_open, args.scheme, args.draco_cache, not args.no_reencode)
            for path in files]
    with multiprocessing.get_context("fork").Pool(args.jobs) if args.jobs > 1 else contextlib.nullcontext() as pool:
        results = pool.imap(_check_file, jobs) if pool is not None else map(_check_file, jobs)
        for path, rows, problems in results:
            for row in rows:
                print(row, flush=True)
            if problems:
                failures.append((label(path), problems))
                growing += any(" larger than " in p for p in problems)
    print(f"\n{len(failures)} of {len(files)} files failed ({growing} of them larger at a looser tolerance); "
          "ok*: not certified within float32 rounding of the decoding, but within the header's tolerance of the source")
    for name, problems in failures:
        for p in problems:
            print(f"- {name}: {p}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
