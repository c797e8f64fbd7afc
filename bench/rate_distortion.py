"""Rate–distortion curves of .pln beside Draco: bytes against measured error, a few meshes per corpus category.

For each mesh (the corpus file loaded, flattened and welded as ``bench/compare.py``'s
``load`` does) and each point of two curves:

* Draco: ``DracoPy.encode(v, f, quantization_bits=q, compression_level=10)``
  at q in 8, 10, 11, 12, 14, 16 (``--draco-bits``);
* .pln: ``bench/compare.py``'s ``_pln(T)`` closures, i.e.
  ``planefmt.codec.encode_scene(scene, buf, tolerance=T, compress=True, compact=True)``
  on the source scene, decoded and flattened again, at T in 3e-3, 1e-3, 3e-4,
  1e-4, 3e-5, 1e-5, 1e-6 (``--tolerances``; fractions of the bbox diagonal);

measured: the file's bytes, bits per source triangle, and the error, exactly
as ``bench/compare.py`` measures it: the certified upper bound of the
two-sided Hausdorff distance between decoded and source surface relative to
the source's bbox diagonal (``relative_hausdorff(..., tolerance=MEASURE_GAP,
max_pieces=MEASURE_PIECES)``, ``.upper``). A bound whose budget ran out is
still an upper bound, drawn hollow and marked *uncert.* in the table.

Each point runs in a forked child with a timeout (``--timeout``); a point that
times out or fails is reported as missing, in the figure and the table, not
dropped silently. Meshes run in a process pool (``--jobs``), the largest file first.

Outputs: ``docs/rate_distortion.png`` (one subplot per mesh, log-log, x =
measured relative error, y = bits per source triangle) and
``docs/rate_distortion.md`` (how it was made, the points, and a reading of the
curves at matched error: each curve's cheapest file measured at an error no
larger than e, interpolated linearly in log(bits)–log(error) between measured
points, compared over the range of errors both curves cover).

Usage::

    python bench/rate_distortion.py                        # default meshes -> docs/rate_distortion.{png,md}
    python bench/rate_distortion.py --jobs 2 --timeout 240
    python bench/rate_distortion.py --meshes cad/box.STL,convex/unit_sphere.STL --out /tmp/rd
    python bench/rate_distortion.py --save /tmp/rd.json    # also keep the raw points
    python bench/rate_distortion.py --replot /tmp/rd.json  # redraw from saved points, no measuring
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import math
import multiprocessing
import os
import statistics
import subprocess
import sys
import time
import traceback

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from compare import (CATEGORIES, CORPUS, MEASURE_GAP, MEASURE_PIECES, MEASURE_RESOLUTION,  # noqa: E402
                     _draco, _machine, _pln, load, run_forked)

ROOT = os.path.normpath(os.path.join(HERE, ".."))
DEFAULT_OUT = os.path.join(ROOT, "docs", "rate_distortion")
DEFAULT_MESHES = ("cad/box.STL", "cad/plate_holes.STL", "convex/unit_sphere.STL", "nonconvex_watertight/torus.STL",
                  "open/suzanne.ply", "smooth_dense/bun_zipper.ply", "gltf_scene/CesiumMilkTruck.glb",
                  "usd/UtahTeapot.usd")
DEFAULT_BITS = (8, 10, 11, 12, 14, 16)
DEFAULT_TOLERANCES = (3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6)
DEFAULT_TIMEOUT = 300.0
#: Errors at which the reading compares the two curves (where both cover them).
READ_AT = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6)


# --------------------------------------------------------------------------- measuring

def _point(scene, v, f, codec: str, param: float, conn) -> None:
    """In the forked child: encode, decode, measure one point; send one result dict."""
    try:
        from planefmt.geometry.hausdorff import relative_hausdorff

        encode, decode = _draco(int(param)) if codec == "draco" else _pln(param)
        t0 = time.perf_counter()
        data = encode(scene, v, f)
        t1 = time.perf_counter()
        dv, df = decode(data)
        t2 = time.perf_counter()
        r = relative_hausdorff((v, f), (dv, df), tolerance=MEASURE_GAP, max_pieces=MEASURE_PIECES)
        conn.send({"bytes": len(data), "error": float(r.upper), "lower": float(r.lower),
                   "certified": bool(r.certified), "encode": t1 - t0, "decode": t2 - t1,
                   "measure": time.perf_counter() - t2})
    except Exception as exc:  # noqa: BLE001 - a failure is a result, reported as a missing point
        conn.send({"failed": f"{type(exc).__name__}: {str(exc).splitlines()[0][:120] if str(exc) else ''}",
                   "trace": traceback.format_exc(limit=-4)})
    finally:
        conn.close()


def measure_point(scene, v, f, codec: str, param: float, timeout: float) -> dict:
    """One point in a forked child (the mesh already loaded in the parent), killed after ``timeout`` s;
    the same machinery as ``compare.measure``."""
    return run_forked(_point, (scene, v, f, codec, param), timeout)


def measure_mesh(rel: str, bits: tuple[int, ...], tolerances: tuple[float, ...], timeout: float) -> dict:
    """Every point of one mesh: ``{"mesh", "triangles", "draco": [...], "pln": [...]}``."""
    row: dict = {"mesh": rel, "triangles": 0, "draco": [], "pln": []}
    try:
        scene, v, f = load(os.path.join(CORPUS, rel))
    except Exception as exc:  # noqa: BLE001
        row["failed"] = f"load: {type(exc).__name__}: {exc}"
        print(f"{rel}: {row['failed']}", file=sys.stderr, flush=True)
        return row
    row["triangles"] = int(len(f))
    for codec, params in (("draco", bits), ("pln", tolerances)):
        for p in params:
            r = measure_point(scene, v, f, codec, p, timeout)
            r["param"] = p
            row[codec].append(r)
            status = r["failed"] if "failed" in r else (
                f"{r['bytes']} B, error {r['error']:.3g}{'' if r['certified'] else ' (uncert.)'}")
            print(f"{rel} {_label(codec, p)}: {status} ({r['wall']:.1f} s)", file=sys.stderr, flush=True)
    return row


# --------------------------------------------------------------------------- curves and reading

def _label(codec: str, p: float) -> str:
    return f"q{int(p)}" if codec == "draco" else f"{p:.0e}".replace("e-0", "e-")


def points(row: dict, codec: str) -> list[tuple[float, float, dict]]:
    """(error, bits per triangle, result) of the measured points, in parameter order."""
    tri = max(row["triangles"], 1)
    return [(max(r["error"], MEASURE_RESOLUTION), 8 * r["bytes"] / tri, r) for r in row[codec] if "failed" not in r]


def frontier(pts: list[tuple[float, float, dict]]) -> list[tuple[float, float]]:
    """The cheapest file measured at an error no larger than e, as (error, bits) corners, error ascending:
    the points no other point beats on both error and bits."""
    out: list[tuple[float, float]] = []
    for e, b, _ in sorted(pts, key=lambda x: (x[0], x[1])):
        if not out or b < out[-1][1]:
            out.append((e, b))
    return out


def interp(front: list[tuple[float, float]], e: float) -> float | None:
    """Bits at error e on a frontier, linear in log–log between its corners; None outside its error range."""
    if not front or e < front[0][0] * (1 - 1e-9) or e > front[-1][0] * (1 + 1e-9):
        return None
    if len(front) == 1:
        return front[0][1]
    for (e0, b0), (e1, b1) in zip(front, front[1:]):
        if e0 * (1 - 1e-9) <= e <= e1 * (1 + 1e-9):
            if e1 == e0:
                return min(b0, b1)
            t = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(b0) + min(max(t, 0.0), 1.0) * (math.log(b1) - math.log(b0)))
    return None


def reading(row: dict) -> dict:
    """pln bits / Draco bits at matched error over the errors both frontiers cover."""
    fd, fp = frontier(points(row, "draco")), frontier(points(row, "pln"))
    out: dict = {"draco_range": (fd[0][0], fd[-1][0]) if fd else None,
                 "pln_range": (fp[0][0], fp[-1][0]) if fp else None, "at": [], "overlap": None}
    if not fd or not fp:
        return out
    lo, hi = max(fd[0][0], fp[0][0]), min(fd[-1][0], fp[-1][0])
    if lo > hi:
        return out
    out["overlap"] = (lo, hi)
    grid = np.geomspace(lo, hi, 200) if hi > lo else np.array([lo])
    ratios = [(float(e), interp(fp, e) / interp(fd, e)) for e in grid]
    out["min"] = min(ratios, key=lambda x: x[1])
    out["max"] = max(ratios, key=lambda x: x[1])
    out["below"] = [e for e, r in ratios if r < 1]
    for e in READ_AT:
        if lo * (1 - 1e-9) <= e <= hi * (1 + 1e-9):
            out["at"].append((e, interp(fp, e), interp(fd, e)))
    return out


# --------------------------------------------------------------------------- outputs

def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def commit_id() -> str:
    """Short HEAD, with ``-dirty`` if the library or converters differ from it."""
    head = _git("rev-parse", "--short", "HEAD")
    dirty = _git("status", "--porcelain", "--", "planefmt", "converters", "bench")
    return head + ("-dirty" if dirty and dirty != "?" else "")


def plot(rows: list[dict], path: str, caption: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    n = len(rows)
    cols = min(4, n)
    nrows = math.ceil(n / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 4.1 * nrows + 0.6), squeeze=False)
    style = {"draco": dict(color="tab:blue", marker="s", label="Draco (q bits)"),
             "pln": dict(color="tab:red", marker="o", label=".pln (tolerance)")}
    for ax, row in zip(axes.flat, rows):
        name = row["mesh"]
        ax.set_title(f"{name}\n{row['triangles']:,} triangles", fontsize=9.5)
        missing = []
        for codec in ("draco", "pln"):
            pts = points(row, codec)
            s = style[codec]
            if pts:
                xs, ys = [p[0] for p in pts], [p[1] for p in pts]
                ax.plot(xs, ys, "-", color=s["color"], lw=1.2, alpha=0.8)
                cert = [p for p in pts if p[2]["certified"]]
                unc = [p for p in pts if not p[2]["certified"]]
                ax.plot([p[0] for p in cert], [p[1] for p in cert], s["marker"], color=s["color"], ms=4.5,
                        label=s["label"])
                if unc:
                    ax.plot([p[0] for p in unc], [p[1] for p in unc], s["marker"], mfc="none", color=s["color"],
                            ms=6, label=s["label"] + ", uncertified")
                for e, b, r in pts:
                    ax.annotate(_label(codec, r["param"]), (e, b), textcoords="offset points",
                                xytext=(4, 3) if codec == "draco" else (4, -9), fontsize=6.5, color=s["color"],
                                alpha=0.65)
            missing += [f"{'Draco ' if codec == 'draco' else '.pln '}{_label(codec, r['param'])}: {_why(r)}"
                        for r in row[codec] if "failed" in r]
        if row.get("failed"):
            missing.append(row["failed"][:60])
        if missing:
            ax.text(0.02, 0.02, "missing: " + ", ".join(missing), transform=ax.transAxes, fontsize=6.5,
                    color="0.25", va="bottom", wrap=True)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.margins(x=0.12, y=0.12)
        ax.autoscale_view()
        ax.grid(True, which="major", lw=0.5, alpha=0.5)
        ax.grid(True, which="minor", lw=0.3, alpha=0.25)
        lo, hi = ax.get_ylim()
        subs = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0) if hi / lo < 4 else (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)
        ax.yaxis.set_major_locator(ticker.LogLocator(base=10, subs=subs))
        ax.yaxis.set_major_formatter(ticker.FuncFormatter(lambda y, _: f"{y:g}"))
        ax.yaxis.set_minor_formatter(ticker.NullFormatter())
        ax.tick_params(labelsize=8)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("measured error (Hausdorff upper bound / bbox diagonal)", fontsize=8.5)
    for ax in axes[:, 0]:
        ax.set_ylabel("bits per source triangle", fontsize=8.5)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    seen = dict(zip(labels, handles))
    for ax in axes.flat[:n]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    fig.legend(list(seen.values()), list(seen.keys()), loc="upper center", ncol=len(seen), fontsize=9,
               frameon=False, bbox_to_anchor=(0.5, 0.995))
    fig.text(0.5, 0.005, caption, ha="center", va="bottom", fontsize=8, color="0.3")
    fig.tight_layout(rect=(0, 0.03, 1, 0.965))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _why(r: dict) -> str:
    """A failed point's reason, short: timeout, or the exception's type."""
    return "timeout" if r["failed"].startswith("timeout") else r["failed"].split(":")[0]


def _where(r: dict) -> str:
    """The innermost frame of a failed point's traceback, ``file:line in function``, or ''."""
    import re

    frames = re.findall(r'File "([^"]+)", line (\d+), in (\S+)', r.get("trace", ""))
    if not frames:
        return ""
    f, line, fn = frames[-1]
    return f"{os.path.relpath(f, ROOT) if f.startswith(ROOT) else f}:{line} in {fn}"


def _e(x: float) -> str:
    return f"{x:.2g}"


def report(rows: list[dict], meta: dict) -> str:
    lines = ["# Rate–distortion: .pln beside Draco", "",
             f"![rate–distortion plots]({meta['png']})", "",
             f"Generated by `{meta['command']}` on planefmt commit `{meta['commit']}`, {meta['date']}, "
             f"in {meta['wall'] / 60:.1f} min wall time; `bench/rate_distortion.py`'s docstring says what is "
             "measured and how.", "", meta["machine"], "",
             "Each point: one file, its bytes as *bits per source triangle* (8 × bytes / triangles of the source "
             "mesh, flattened and welded), and its *measured error*, the certified upper bound of the two-sided "
             "Hausdorff distance between decoded and source surface over the source's bbox diagonal, measured as "
             "`bench/compare.py` measures it (stop gap 1e-7 of the diagonal). Draco: quantization q bits, "
             "compression level 10. .pln: `encode_scene(tolerance=T, compress=True, compact=True)`. "
             "*uncert.*: the measure's budget ran out before certifying (still an upper bound, drawn hollow). "
             f"Each point had {meta['timeout']:g} s (encode, decode and measure); a point that ran out of time "
             "or failed is listed, not dropped.", ""]
    lines += ["## Reading at matched error", "",
              "For each curve, the cheapest file measured at an error no larger than e (its lower frontier), "
              "**interpolated** linearly in log(bits)–log(error) between measured points, never extrapolated: "
              "the ratios below are pln bits / Draco bits at the same error, over the range of errors both "
              "curves reach; they are interpolations between measured files, not measurements of files at "
              "those errors. Below 1: .pln is the smaller.", ""]
    lines += ["| mesh | triangles | Draco error range | .pln error range | compared over | .pln / Draco at "
              + ", ".join(_e(e) for e in READ_AT) + " | least ratio (at error) | largest ratio (at error) |",
              "|---|---|---|---|---|---|---|---|"]
    readings = {}
    for row in rows:
        rd = reading(row)
        readings[row["mesh"]] = rd
        rng = (lambda r: f"{_e(r[0])} – {_e(r[1])}" if r else "–")
        at = ", ".join(f"{_e(e)}: {p / d:.2f}" for e, p, d in rd["at"]) or "–"
        least = f"{rd['min'][1]:.2f} ({_e(rd['min'][0])})" if rd.get("min") else "–"
        most = f"{rd['max'][1]:.2f} ({_e(rd['max'][0])})" if rd.get("max") else "–"
        lines.append(f"| {row['mesh']} | {row['triangles']:,} | {rng(rd['draco_range'])} | "
                     f"{rng(rd['pln_range'])} | {rng(rd['overlap'])} | {at} | {least} | {most} |")
    lines += ["", "Per mesh, in words (from the same interpolation):", ""]
    for row in rows:
        lines.append("- " + _sentence(row, readings[row["mesh"]]))
    lines += [""] + overall(rows, readings)
    if meta.get("note"):
        lines += ["", meta["note"]]
    lines += ["", "## Points", "",
              "Bytes, bits per source triangle, measured error; encode / decode / measure seconds.", ""]
    for row in rows:
        lines += [f"### {row['mesh']} ({row['triangles']:,} triangles)", ""]
        if row.get("failed"):
            lines += [f"Not measured: {row['failed']}", ""]
            continue
        lines += ["| codec | setting | bytes | bits/triangle | error | seconds (enc / dec / measure) |",
                  "|---|---|---|---|---|---|"]
        for codec, name in (("draco", "Draco"), ("pln", ".pln")):
            for r in row[codec]:
                setting = f"q={int(r['param'])}" if codec == "draco" else f"T={r['param']:g}"
                if "failed" in r:
                    at = f" (at `{_where(r)}`)" if _where(r) else ""
                    lines.append(f"| {name} | {setting} | missing: {r['failed']}{at} | | | "
                                 f"{r['wall']:.1f} wall |")
                    continue
                lines.append(f"| {name} | {setting} | {r['bytes']:,} | {8 * r['bytes'] / row['triangles']:.2f} | "
                             f"{r['error']:.3g}{'' if r['certified'] else ' (uncert.)'} | "
                             f"{r['encode']:.2f} / {r['decode']:.2f} / {r['measure']:.1f} |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _sentence(row: dict, rd: dict) -> str:
    name = f"**{row['mesh']}**"
    if row.get("failed"):
        return f"{name}: not measured ({row['failed']})."
    if rd["overlap"] is None:
        return f"{name}: the curves share no error range; no comparison at matched error."
    lo, hi = rd["overlap"]
    mn, mx = rd["min"], rd["max"]
    parts = [f"{name}: over errors {_e(lo)} – {_e(hi)}"]
    if mx[1] < 1:
        parts.append(f".pln lies below Draco throughout, {1 - mx[1]:.0%} – {1 - mn[1]:.0%} fewer bits "
                     f"(ratio {mn[1]:.2f} at {_e(mn[0])} to {mx[1]:.2f} at {_e(mx[0])})")
    elif mn[1] >= 1:
        parts.append(f".pln lies above Draco throughout, ×{mn[1]:.2f} (at {_e(mn[0])}) to ×{mx[1]:.2f} "
                     f"(at {_e(mx[0])}) Draco's bits")
    else:
        below = rd["below"]
        parts.append(f".pln lies below Draco for errors {_e(min(below))} – {_e(max(below))} (down to "
                     f"{mn[1]:.2f}× Draco's bits at {_e(mn[0])}) and above elsewhere (up to {mx[1]:.2f}× at "
                     f"{_e(mx[0])})")
    dr, pr = rd["draco_range"], rd["pln_range"]
    if pr[0] < dr[0] * 0.999:
        finest = max(int(r["param"]) for r in row["draco"] if "failed" not in r)
        parts.append(f"; below {_e(dr[0])}, Draco's finest measured point (q{finest}), only .pln was measured "
                     f"(down to {_e(pr[0])}): no comparison there")
    if dr[1] > pr[1] * 1.001:
        worst = max(points(row, "pln"), key=lambda x: x[0])[2]["param"]
        parts.append(f"; only Draco reaches errors above {_e(pr[1])} (up to {_e(dr[1])}): .pln's largest "
                     f"measured error is {_e(pr[1])} (tolerance {worst:g})")
    missing = [f"{'Draco ' if c == 'draco' else '.pln '}{_label(c, r['param'])} ({_why(r)})"
               for c in ("draco", "pln") for r in row[c] if "failed" in r]
    if missing:
        parts.append(f"; missing points: {', '.join(missing)}")
    return parts[0] + ", " + "".join(parts[1:]) + "."


def overall(rows: list[dict], readings: dict) -> list[str]:
    """A paragraph over all meshes, from the same interpolation."""
    done = [r for r in rows if readings[r["mesh"]].get("overlap")]
    if not done:
        return []
    below = [r["mesh"] for r in done if readings[r["mesh"]]["min"][1] < 1]
    all_below = [r["mesh"] for r in done if readings[r["mesh"]]["max"][1] < 1]
    finer = [r["mesh"] for r in done
             if readings[r["mesh"]]["at"] and readings[r["mesh"]]["at"][-1][1] / readings[r["mesh"]]["at"][-1][2]
             < readings[r["mesh"]]["at"][0][1] / readings[r["mesh"]]["at"][0][2]]
    out = [f"Over the {len(done)} meshes compared: .pln lies below Draco somewhere on {len(below)} "
           f"({', '.join(below) or 'none'}), below throughout on {len(all_below)}, and above throughout on "
           f"{len(done) - len(below)}."]
    for e in READ_AT:
        ratios = sorted(p / d for r in done for ee, p, d in readings[r["mesh"]]["at"] if ee == e)
        if len(ratios) >= 2:
            mid = statistics.median(ratios)
            out.append(f"At error {_e(e)}: .pln / Draco from {ratios[0]:.2f} to {ratios[-1]:.2f}, "
                       f"median {mid:.2f} over {len(ratios)} meshes.")
    out.append(f"On {len(finer)} of {len(done)} meshes the ratio at the finest compared error of the list above is "
               "smaller than at the coarsest: .pln gains on Draco as the error shrinks.")
    return [" ".join(out)]


# --------------------------------------------------------------------------- main

def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=",".join(DEFAULT_MESHES),
                    help="comma-separated corpus paths (folder/file); default: " + ",".join(DEFAULT_MESHES))
    ap.add_argument("--draco-bits", default=",".join(map(str, DEFAULT_BITS)), help="Draco quantization bits")
    ap.add_argument("--tolerances", default=",".join(f"{t:g}" for t in DEFAULT_TOLERANCES), help="pln tolerances")
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, help="seconds per point (default 300)")
    ap.add_argument("--jobs", type=int, default=1, help="meshes measured at once (default 1)")
    ap.add_argument("--out", default=DEFAULT_OUT, help="output stem: writes STEM.png and STEM.md")
    ap.add_argument("--save", help="also write the raw points as JSON here")
    ap.add_argument("--replot", help="redraw from JSON written by --save instead of measuring")
    ap.add_argument("--note", help="a paragraph added under the reading")
    args = ap.parse_args(argv)

    if args.replot:
        with open(args.replot) as fh:
            saved = json.load(fh)
        rows, meta = saved["rows"], saved["meta"]
        if args.note:
            meta["note"] = args.note
    else:
        meshes = [m for m in args.meshes.split(",") if m]
        bad = [m for m in meshes if m.split("/")[0] not in CATEGORIES or not os.path.exists(os.path.join(CORPUS, m))]
        if bad:
            ap.error(f"not corpus files: {', '.join(bad)}")
        bits = tuple(int(b) for b in args.draco_bits.split(","))
        tolerances = tuple(float(t) for t in args.tolerances.split(","))
        # Imported once here, so every forked measurement starts with them loaded.
        import DracoPy  # noqa: F401

        import planefmt.codec  # noqa: F401
        import planefmt.geometry.hausdorff  # noqa: F401
        import planefmt_converters.registry  # noqa: F401
        command = "python bench/rate_distortion.py" + "".join(
            f" {flag} {val}" for flag, val, default in (
                ("--meshes", args.meshes, ",".join(DEFAULT_MESHES)),
                ("--draco-bits", args.draco_bits, ",".join(map(str, DEFAULT_BITS))),
                ("--tolerances", args.tolerances, ",".join(f"{t:g}" for t in DEFAULT_TOLERANCES)),
                ("--timeout", f"{args.timeout:g}", f"{DEFAULT_TIMEOUT:g}"),
                ("--jobs", str(args.jobs), "1")) if val != default)
        commit = commit_id()
        t0 = time.perf_counter()
        if args.jobs == 1:
            rows = [measure_mesh(m, bits, tolerances, args.timeout) for m in meshes]
        else:
            ctx = multiprocessing.get_context("fork")
            with concurrent.futures.ProcessPoolExecutor(args.jobs, mp_context=ctx) as pool:
                order = sorted(range(len(meshes)), key=lambda i: -os.path.getsize(os.path.join(CORPUS, meshes[i])))
                futures = {i: pool.submit(measure_mesh, meshes[i], bits, tolerances, args.timeout) for i in order}
                rows = [futures[i].result() for i in range(len(meshes))]
        meta = {"command": command, "commit": commit, "date": time.strftime("%Y-%m-%d"),
                "wall": time.perf_counter() - t0, "timeout": args.timeout, "machine": _machine(args.jobs),
                "note": args.note}
        if args.save:
            with open(args.save, "w") as fh:
                json.dump({"rows": rows, "meta": meta}, fh, indent=1)
    meta["png"] = os.path.basename(args.out) + ".png"
    caption = (f"planefmt {meta['commit']} · {meta['date']} · bench/rate_distortion.py · error: certified two-sided "
               "Hausdorff upper bound / source bbox diagonal · bits: file bytes × 8 / source triangles")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    plot(rows, args.out + ".png", caption)
    with open(args.out + ".md", "w") as fh:
        fh.write(report(rows, meta))
    print(f"wrote {args.out}.png, {args.out}.md ({meta['wall']:.0f} s measuring)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
