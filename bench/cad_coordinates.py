"""What else a CAD walk's bytes could be coded as: predictors, tables and entropy coders measured
against what version 5.0 writes (issues 30 and 31: CAD at Draco-14's error is 0.72 of Draco-14's bytes,
the targets 0.70 and 0.5).

For each mesh, at draco-14's measured error (``shell_bits.D14_ERROR``), the default encoder
writes the file; its shell walk's fields (``shell_bits.shell_fields``) are then coded otherwise,
each alternative compressed by Brotli at quality 11 as the writer's are (bytes):

* ``coordinates``: the explicit corners' residuals, every x, then y, then z, as zigzag varints,
  with the axis values as indices into each axis's sorted table (``idx``, the *tables* mode) or as
  grid integers (``val``), predicted by kind 9's parallelogram over the parent (``P``), a step from
  the gate corner (``S``, §9.11), kind 10's averaged parallelograms (``M``), a parallelogram in grid
  values mapped to the nearest table index (``P val->idx``), and, per corner and axis, the first of
  P, M, S, and the parallelogram's two other corners that is exact, its choice coded beside
  (``selector``: what a coding that says which predictor to use would pay at best);
* ``tables``: the sorted axis values as gaps (the writer's), and as a mirror (the first half's
  gaps, then the second half's against the first's reversed), for parts symmetric about their middle;
* ``entropy``: the ideal code length of an adaptive model with add-1/2 counts (what an arithmetic
  coder gets within a few bytes), order 0 and order 1 over the previous symbol, for the walk's
  symbols and for the coordinates (values above 62 escaped with an Elias-gamma length), against
  Brotli on the same field;
* ``brotli``: the whole body at Brotli's default window and block against the best of its modes
  (generic, text, font), windows 2^10, 2^16, 2^22 and blocks 2^16, 2^24;
* ``more`` (grid values, Brotli as above): ``written``, the walk's tables and coordinates as the writer
  codes them (in table indices or grid values, whichever it chose), then S, the step from the gate
  corner in grid values, against a corner's chain
  (the step source g of S, its own g2, g3): ``linear`` 2g - g2 and ``reflection`` g + d3, d3 the step
  g2 - g3 reflected about the step g - g2 (exact for a regular polygon: a tessellated circle walked
  round); ``adaptive``, per corner the one of S, P and reflection that was best on its step source
  (a reader knows it: no choice is coded), and ``oracle``, the best of the three at each corner with
  its choice not counted (what no coding of a choice can beat); ``recency``, each axis value coded as
  0 where S is 0, else as its rank among the axis's distinct values used so far (most recent first),
  else S escaped; ``interleaved``, S's x, y, z corner by corner rather than axis by axis;
* ``grid`` (S, grid values): the decoded corners are any grid points within the budget (the
  budget s√3/2 a step s keeps holds for each), so an encoder may choose among 4/3·π·(√3/2)³ ≈ 2.72
  per corner on average:
  ``nearest`` (the writer's), ``chord``, the point whose step from its decoded step source is
  nearest the source's (so that translated copies code alike), ``seen``, a point whose values the
  axis has used already where there is one, and ``seen+chord``.

Usage: ``python bench/cad_coordinates.py [paths relative to the corpus]`` (default: the CAD part of
``shell_bits.D14_ERROR``).
"""

from __future__ import annotations

import collections
import io
import math
import os
import sys

import brotli

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(__file__))
from compare import CORPUS, load  # noqa: E402
from shell_bits import D14_ERROR, shell_fields  # noqa: E402

import planefmt  # noqa: E402
from planefmt import codec  # noqa: E402
from planefmt.container import varint  # noqa: E402
from planefmt.container.shellfields import (_predict, _tree_predictors, code_stream, parallelograms,  # noqa: E402
                                            predict_averaged)


#: A walk's symbols are below 20 (spec §9.13: 5 child lists times 4 corner codes; a root's below 16).
SYMBOLS = 20


def _brotli(data: bytes) -> int:
    return len(brotli.compress(bytes(data), quality=11))


def _coded(residuals: np.ndarray) -> bytes:
    return varint.encode(varint.zigzag(residuals.T))


def adaptive_bytes(symbols: list[int], contexts: list[int], alphabet: int) -> float:
    """The ideal code length (bytes) of ``symbols`` under an adaptive model per context, counts from 1/2."""
    counts: dict[int, collections.Counter] = {}
    totals: dict[int, int] = {}
    bits = 0.0
    for s, c in zip(symbols, contexts):
        seen = counts.setdefault(c, collections.Counter())
        n = totals.get(c, 0)
        bits -= math.log2((seen[s] + 0.5) / (n + 0.5 * alphabet))
        seen[s] += 1
        totals[c] = n + 1
    return bits / 8


def _escaped(values: list[int]) -> tuple[list[int], float]:
    """Values capped at 63 (an escape) and the bytes of Elias-gamma codes for the escaped rest."""
    extra = sum(2 * math.floor(math.log2(x - 62)) + 1 for x in values if x >= 63) / 8
    return [min(x, 63) for x in values], extra


def measure(rel: str) -> dict:
    scene, _, _ = load(os.path.join(CORPUS, rel))
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=D14_ERROR[rel])
    with planefmt.open(io.BytesIO(buf.getvalue())) as r:
        group = next(g for g in r.part_groups() if g.kind in codec.SHELL_KINDS)
    fields = shell_fields(group)
    shell = group.shell
    tri = np.asarray(shell.facets, dtype=np.int64)[:, 1:]
    links = np.asarray(shell.links, dtype=np.int64)
    explicit = np.asarray(shell.explicit, dtype=bool)
    values = np.zeros((len(explicit), 3), dtype=np.int64)
    values[explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    indices, tables = values.copy(), []
    for axis in range(3):
        table, indices[explicit, axis] = np.unique(values[explicit, axis], return_inverse=True)
        tables.append(table)
    _, new, _ = code_stream(tri, links == 0)
    per = np.where(links == 0, 3, 1)
    pair = _tree_predictors(links, tri, explicit, per, new, True)
    step = _tree_predictors(links, tri, explicit, per, new, False)
    averaged = parallelograms(tri, explicit)
    row: dict = dict(mesh=rel, file=len(buf.getvalue()), corners=int(explicit.sum()),
                     body=_brotli(b"".join(fields.values())))
    coordinates = {}
    for space, v in (("idx", indices), ("val", values)):
        p, s = _predict(v, pair), _predict(v, step)
        m = predict_averaged(v, *averaged, p)
        for name, prediction in (("P", p), ("S", s), ("M", m)):
            coordinates[f"{name} {space}"] = _brotli(_coded((v - prediction)[explicit]))
        if space == "idx":
            others = [np.where((t >= 0)[:, None], v[np.maximum(t, 0)], p) for t in (pair[:, 1], pair[:, 2])]
            candidates = np.stack([(v - c)[explicit] for c in (p, m, s, *others)])
            exact = candidates == 0
            choice = np.where(exact.any(axis=0), exact.argmax(axis=0), 0)
            best = np.take_along_axis(candidates, choice[None], axis=0)[0]
            coordinates["selector"] = _brotli(_coded(best)) + _brotli(choice.T.astype(np.uint8).tobytes())
    pv = _predict(values, pair)
    mapped = np.zeros_like(pv)
    for axis, table in enumerate(tables):
        j = np.clip(np.searchsorted(table, pv[:, axis]), 1, max(len(table) - 1, 1))
        lower = np.abs(table[np.minimum(j - 1, len(table) - 1)] - pv[:, axis])
        upper = np.abs(table[np.minimum(j, len(table) - 1)] - pv[:, axis])
        mapped[:, axis] = np.where(lower <= upper, j - 1, j) if len(table) > 1 else 0
    coordinates["P val->idx"] = _brotli(_coded((indices - mapped)[explicit]))
    row["coordinates"] = coordinates
    plain, mirrored = [], []
    for table in tables:
        gaps = np.diff(table) - 1
        half = len(gaps) // 2
        plain.append(varint.encode(gaps))
        mirrored.append(varint.encode(gaps[:half]) + varint.encode(gaps[half:len(gaps) - half])
                        + varint.encode(varint.zigzag(gaps[len(gaps) - half:][::-1] - gaps[:half])))
    row["tables"] = {"gaps": _brotli(b"".join(plain)), "mirror": _brotli(b"".join(mirrored))}
    symbols = np.frombuffer(fields["symbols"], dtype=np.uint8).tolist()
    residuals = [int(x) for x in varint.decode(np.frombuffer(fields["coordinates"], dtype=np.uint8),
                                               3 * row["corners"], "coordinates")[0]]
    capped, extra = _escaped(residuals)
    e = row["corners"]
    row["entropy"] = {
        "symbols brotli": _brotli(fields["symbols"]),
        "symbols order 0": round(adaptive_bytes(symbols, [0] * len(symbols), SYMBOLS)),
        "symbols order 1": round(adaptive_bytes(symbols, [0] + symbols[:-1], SYMBOLS)),
        "coordinates brotli": _brotli(fields["coordinates"]),
        "coordinates order 0": round(adaptive_bytes(capped, [i // e for i in range(len(capped))], 64) + extra),
        "coordinates order 1": round(adaptive_bytes(
            capped, [(i // e) * 64 + (min(capped[i - 1], 3) if i % e else 0) for i in range(len(capped))], 64) + extra)}
    body = b"".join(fields.values())
    sizes = {(mode, window, block): len(brotli.compress(body, quality=11, mode=mode, lgwin=window, lgblock=block))
             for mode in (brotli.MODE_GENERIC, brotli.MODE_TEXT, brotli.MODE_FONT)
             for window in (10, 16, 22) for block in (0, 16, 24)}
    row["brotli"] = {"default": sizes[(brotli.MODE_GENERIC, 22, 0)], "best of modes": min(sizes.values())}
    row["more"] = {"written": _brotli(fields["tables"] + fields["coordinates"]), **more_predictors(values, step, pair)}
    source = np.concatenate([n.mesh.vertices for n in scene.nodes if n.mesh is not None])
    points = np.asarray(shell.origin) + values * float(shell.step)
    row["grid"] = grid_choices(source[cKDTree(source).query(points)[1]], values, step, np.asarray(shell.origin),
                               float(shell.step))
    return row


def _reflection(values: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each corner's chain predictions (linear, reflection) from its step sources ``g`` (-1: none)."""
    g2 = np.where(g >= 0, g[np.maximum(g, 0)], -1)
    g3 = np.where(g2 >= 0, g[np.maximum(g2, 0)], -1)
    a, b, c = (values[np.maximum(x, 0)] for x in (g, g2, g3))
    linear = np.where((g2 >= 0)[:, None], 2 * a - b, a)
    d1, d2 = (b - c).astype(float), (a - b).astype(float)
    dd = (d2 * d2).sum(axis=1)
    t = np.where(dd > 0, 2 * (d1 * d2).sum(axis=1) / np.where(dd > 0, dd, 1), 0.0)
    reflected = np.floor(a + t[:, None] * d2 - d1 + 0.5).astype(np.int64)
    return linear, np.where(((g3 >= 0) & (dd > 0))[:, None], reflected, linear)


def more_predictors(values: np.ndarray, step: np.ndarray, pair: np.ndarray) -> dict[str, int]:
    """Brotli bytes of the coordinates under the chain predictors, choices and codings of ``more``."""
    g = step[:, 0]
    s = values - _predict(values, step)
    p = values - _predict(values, pair)
    linear, reflected = _reflection(values, g)
    r = values - reflected
    out = {"S": _brotli(_coded(s)), "linear": _brotli(_coded(values - linear)), "reflection": _brotli(_coded(r))}
    options = np.stack([s, p, r])
    best = np.abs(options).sum(axis=2).argmin(axis=0)
    adaptive = np.where(g >= 0, best[np.maximum(g, 0)], 0)
    out["adaptive"] = _brotli(_coded(options[adaptive, np.arange(len(values))]))
    out["oracle"] = _brotli(_coded(options[best, np.arange(len(values))]))
    streams = []
    for axis in range(3):
        recent: list[int] = []
        coded = []
        for x, step_residual in zip(values[:, axis].tolist(), s[:, axis].tolist()):
            if step_residual == 0:
                coded.append(0)
            elif x in recent:
                coded.append(1 + 2 * recent.index(x))
            else:
                coded.append(2 + 2 * (2 * step_residual if step_residual >= 0 else -2 * step_residual - 1))
            if x in recent:
                recent.remove(x)
            recent.insert(0, x)
        streams.append(varint.encode(np.array(coded, dtype=np.uint64)))
    out["recency"] = _brotli(b"".join(streams))
    out["interleaved"] = _brotli(varint.encode(varint.zigzag(s.reshape(-1))))
    return out


def grid_choices(source: np.ndarray, values: np.ndarray, step: np.ndarray, origin: np.ndarray,
                 cell: float) -> dict[str, int]:
    """Brotli bytes of S's residuals with the grid points chosen as ``grid`` says (``source``: each
    corner's source vertex; ``values``: the writer's grid points, origin + values * cell)."""
    target = (source - origin) / cell
    budget = math.sqrt(3) / 2
    offsets = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)])
    g = step[:, 0]
    out = {}
    for mode in ("nearest", "chord", "seen", "seen+chord"):
        q = np.zeros_like(values)
        seen: list[set[int]] = [set(), set(), set()]
        for k in range(len(values)):
            cands = np.rint(target[k]).astype(np.int64) + offsets
            cands = cands[np.linalg.norm(cands - target[k], axis=1) <= budget]
            cost = np.linalg.norm(cands - target[k], axis=1) * 1e-3
            if "seen" in mode:
                cost = cost + sum(np.array([v not in seen[a] for v in cands[:, a]]) for a in range(3))
            if "chord" in mode and g[k] >= 0:
                chord = q[g[k]] + np.rint(target[k] - target[g[k]]).astype(np.int64)
                cost = cost + 0.1 * np.abs(cands - chord).sum(axis=1)
            q[k] = cands[np.argmin(cost)]
            for a in range(3):
                seen[a].add(int(q[k, a]))
        out[mode] = _brotli(_coded(q - _predict(q, step)))
        if mode == "nearest":
            out["nearest is the writer's"] = bool(np.array_equal(q, values))
    return out


def main(argv: list[str]) -> int:
    for rel in argv or [m for m in D14_ERROR if m.startswith("cad/")]:
        r = measure(rel)
        print(f"{r['mesh']}: file {r['file']} B, {r['corners']} explicit corners, walk body {r['body']} B", flush=True)
        for part in ("coordinates", "tables", "entropy", "brotli", "more", "grid"):
            print(f"  {part}: " + ", ".join(f"{k} {v}" for k, v in r[part].items()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
