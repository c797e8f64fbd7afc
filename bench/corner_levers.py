"""Which coding of a shell walk's explicit corners could halve them (issue 52): the residuals the
encoder writes today against context modelling, a local-frame lattice, tangential slack and other
predictors, in bits per explicit corner, over every bench-corpus mesh that codes as shell walks.

For each mesh (``bench/compare.py``'s ``load``) at Draco-14's certified error on it
(``bench/draco-errors.json``, at least ``MEASURE_RESOLUTION``), the default encoder
(``codec.encode_scene``) writes the file, with ``choosing.encode_shell`` and ``choosing.shell_tree``
wrapped so that every candidate shell's source points are kept; each walk group (kinds 9, 10, 12, 13)
of the file as read back is matched to the candidate with its grid, so that every explicit corner has
its source position (the point the encoder rounded; named corners are taken at their source position).
Over these, with the encoder's own walk, grid and kind:

* (a) ``today``: the residuals the writer codes (its kind and mode, re-derived and checked equal to the
  body's coordinates field), as Brotli-11 bytes of the tables and coordinates fields alone, and as the
  code length of an adaptive binary-arithmetic model without contexts (``adaptive_bits``: one model for
  the three axes, read axis by axis as the field holds them; the magnitude's bit length in unary, each
  decision adaptive, the bit below the leading one adaptive per length, the rest and the sign raw;
  Krichevsky-Trofimov counts; ``bench/corner_coder.py``'s range coder writes these within 0.3 %), plus
  a mode's tables raw; ``grid``: the same
  kind with the tables bit clear (grid values: the baseline of the geometric levers, which do not use
  tables); ``static``: the order-0 empirical entropy per axis, no model cost (not reachable; a floor).
* (b) the same integer residuals under contexts (integer-exact, so every reader reproduces them):
  ``prev`` (axis, length of the corner's earlier axes' residual; for x, the previous corner's),
  ``edge`` (axis, bit length of the gate edge in grid units), ``pred`` (axis, which prediction: none,
  step, parallelogram, reflection, or the count of averaged parallelograms), and ``prev+edge+pred``.
* (c) ``local``: the residual on a cubic lattice of the same step (the same covering radius, so the
  same bound) in each corner's frame (the gate triangle's normal, the gate edge's direction, their
  cross product) from decoded corners; coded closed loop (each corner predicted from the decoded
  corners before it, as a reader would), beside ``global``, the same float predictions on the
  global axes (the like-for-like baseline of the closed-loop variants); ``local ctx`` codes (n, t1, t2)
  with the ``prev`` contexts.
* (d) ``slack``: the local lattice with a wider tangential step where a corner's whole fan is within an
  angle phi of the gate normal (interior manifold corners only; boundary corners keep the cubic step):
  a corner moved by a along the normal and t across it moves the surface of its fan, a graph over the
  tangent plane of Lipschitz constant tan(phi), by at most |a| + |t| tan(phi) (to first order, while
  the moved corner stays in the kernel of its projected link), so steps s_n, s_t with s_n/2 +
  (s_t/sqrt 2) tan(phi) <= e keep the bound e; the best split (s_n = 2e/3) gains log2(0.385 / tan^2 phi)
  bits where that is positive. phi is the fan's on the source with a margin (``SLACK_MARGIN``); the
  reader cannot know it before the fan is decoded, so the corner's class (phi's bucket) is coded,
  its adaptive code length counted in ``slack``. ``--hausdorff`` measures the certified two-sided
  distance of the slack decoding against the source on the first few shells.
* (e) ``multi``: kind 10's averaged parallelograms for every shell (grid values, the same lattice, so
  exact); ``curv``: the gate parallelogram plus the normal part of the opposite corner's own
  parallelogram residual (a surface that bends on bends on), rounded to the grid.

Printed per mesh and per category (medians): explicit corners, file and Draco bytes, and bits per
explicit corner of each; the projected file ratio to Draco-14 of a lever is (file - today's coordinate
bytes + the lever's bytes) / Draco, the lever taken per shell only where smaller (a mode: the encoder
keeps the smaller). Meshes run one at a time in a forked child (``--jobs 1``).

Usage::

    python bench/corner_levers.py --corpus ../shared/bench-corpus --max-triangles 30000 --json out.json
    python bench/corner_levers.py --categories cad --hausdorff 3
"""

from __future__ import annotations

import argparse
import io
import json
import math
import multiprocessing
import os
import statistics
import sys
import warnings

import brotli
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from at_draco import _meshes  # noqa: E402
from compare import MEASURE_RESOLUTION, load  # noqa: E402

#: Buckets of a residual's magnitude: its bit length, 0 to 53 (spec §9.13: within 2^52).
BUCKETS = 54
#: Starting count of each symbol of an adaptive binary model, against increments of 1 (Krichevsky-Trofimov).
ALPHA = 0.5
#: Context values kept per quantity (bit lengths above are clipped).
CLIP = 12
#: Angle added to a fan's source spread before it sets a tangential step: the decoded fan's normals
#: differ from the source's by the corners' moves over the fan's edges.
SLACK_MARGIN = 0.02
#: Tangential widening classes: tan(phi) at most 2^(-c/2) for class c (class 0: the cubic step).
SLACK_CLASSES = 16


def adaptive_bits(values: np.ndarray, ctx: np.ndarray | None = None) -> float:
    """Code length (bits) of integer ``values`` (any shape, read in C order) under an adaptive binary
    arithmetic model in contexts ``ctx`` (same shape; small non-negative ints), as CABAC binarizes: the
    magnitude's bit length b in unary, each decision "b > j" adaptive per (context, j); the bit below
    the leading one adaptive per (context, b); the sign and the other bits raw."""
    r = np.asarray(values, dtype=np.int64).reshape(-1)
    c = np.zeros(len(r), dtype=np.int64) if ctx is None else np.asarray(ctx, dtype=np.int64).reshape(-1)
    m = np.abs(r)
    b = bitlen_exact(m)
    # Unary decisions j = 0 .. b (the last "no"), except none after the largest length.
    n = np.minimum(b + 1, BUCKETS - 1)
    at = np.repeat(np.arange(len(r)), n)
    j = np.arange(len(at)) - np.repeat(np.cumsum(n) - n, n)
    bits = _kt((j < b[at]).astype(np.int64), c[at] * BUCKETS + j, 2)
    two = b >= 2
    top = (m[two] >> (b[two] - 2)) & 1
    bits += _kt(top, c[two] * BUCKETS + b[two], 2)
    return bits + float((m > 0).sum()) + float(np.maximum(b - 2, 0).sum())


def bitlen_exact(m: np.ndarray) -> np.ndarray:
    """Bit length of each non-negative int64 ``m``."""
    b = np.zeros(m.shape, dtype=np.int64)
    x = m.copy()
    for shift in (32, 16, 8, 4, 2, 1):
        big = x >= (np.int64(1) << shift)
        b[big] += shift
        x[big] >>= shift
    return b + (x > 0)


def _kt(sym: np.ndarray, ctx: np.ndarray, alphabet: int) -> float:
    """Sequential adaptive code length of ``sym`` (< ``alphabet``) in contexts ``ctx``."""
    if not len(sym):
        return 0.0
    key = ctx * alphabet + sym
    seen_sym = _rank(key)
    seen_ctx = _rank(ctx)
    return float(-np.log2((seen_sym + ALPHA) / (seen_ctx + alphabet * ALPHA)).sum())


def _rank(key: np.ndarray) -> np.ndarray:
    """How many earlier entries have each entry's key."""
    order = np.argsort(key, kind="stable")
    k = key[order]
    start = np.r_[0, np.flatnonzero(k[1:] != k[:-1]) + 1]
    first = np.repeat(start, np.diff(np.r_[start, len(k)]))
    out = np.empty(len(key), dtype=np.int64)
    out[order] = np.arange(len(k)) - first
    return out


def static_bits(values: np.ndarray) -> float:
    """Order-0 empirical entropy of each column of ``values`` times its length (no model cost)."""
    total = 0.0
    for col in np.asarray(values).reshape(len(values), -1).T:
        _, n = np.unique(col, return_counts=True)
        p = n / n.sum()
        total += float(-(n * np.log2(p)).sum())
    return total


def bitlen(x: np.ndarray) -> np.ndarray:
    """Bit length of each ``|x|``, clipped to CLIP."""
    return np.minimum(bitlen_exact(np.abs(np.asarray(x, dtype=np.int64))), CLIP)


def prev_contexts(res: np.ndarray) -> np.ndarray:
    """Per (corner, axis) the bit length of the corner's earlier axes' largest residual, for the first
    axis the previous corner's largest (coded corner by corner, axes in turn)."""
    mag = bitlen(res)
    out = np.zeros_like(mag)
    out[1:, 0] = mag[:-1].max(axis=1)
    out[:, 1] = mag[:, 0]
    out[:, 2] = np.maximum(mag[:, 0], mag[:, 1])
    return out


# --------------------------------------------------------------------------------------------------
# Extraction: the file, its walk groups, every explicit corner's source point.


def _encode_with_sources(scene, tolerance: float):
    """The file of ``scene`` at ``tolerance`` and the (shell tree, source points) of every candidate."""
    from planefmt import codec
    from planefmt.codec import choosing

    seen, last = [], {}
    encode_shell, shell_tree = choosing.encode_shell, choosing.shell_tree

    def enc(plan, omega, h, budget):
        last["points"] = plan.points
        return encode_shell(plan, omega, h, budget)

    def tree(shell, walk=None):
        t, source = shell_tree(shell, walk)
        seen.append((t, last["points"][source]))
        return t, source

    choosing.encode_shell, choosing.shell_tree = enc, tree
    try:
        buf = io.BytesIO()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            codec.encode_scene(scene, buf, tolerance=tolerance)
    finally:
        choosing.encode_shell, choosing.shell_tree = encode_shell, shell_tree
    return buf.getvalue(), seen


def _sources(shell, seen) -> np.ndarray | None:
    for t, points in reversed(seen):
        if (len(t.explicit) == len(shell.explicit) and t.step == shell.step
                and np.array_equal(np.asarray(t.origin), np.asarray(shell.origin))
                and np.array_equal(np.asarray(t.grid).reshape(-1, 3), np.asarray(shell.grid).reshape(-1, 3))
                and np.array_equal(np.asarray(t.facets)[:, 1:], np.asarray(shell.facets)[:, 1:])):
            return points
    return None


class Walk:
    """One walk group's explicit corners as the encoder codes them."""

    def __init__(self, kind, shell, src: np.ndarray):
        from planefmt.container import shellwalk
        from planefmt.container.shellfields import _tree_predictors, code_stream, parallelograms

        self.kind, self.shell = kind, shell
        self.explicit = np.asarray(shell.explicit, dtype=bool)
        fc = np.asarray(shell.facets, dtype=np.int64)
        self.tri, self.links = fc[:, 1:], np.asarray(shell.links, dtype=np.int64)
        v = len(self.explicit)
        self.step, self.origin = float(shell.step), np.asarray(shell.origin, dtype=np.float64)
        self.values = np.zeros((v, 3), dtype=np.int64)
        self.values[self.explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
        self.src = np.asarray(src, dtype=np.float64)
        fields = shellwalk.shell_walk_fields(shell, None, kind)
        self.fields = fields
        self.mode = fields["mode"][0]
        root = self.links == 0
        self.per = np.where(root, 3, 1)
        _, self.new, _ = code_stream(self.tri, root)
        creator = np.repeat(np.arange(len(self.tri)), self.per)[self.new]
        self.attached = self.links[creator] != 0
        self.gate = self.tri[creator, :2]
        link = self.links[creator]
        parent, edge = creator - (link - 1) // 3 - 1, (link - 1) % 3
        self.opposite = np.where(self.attached, self.tri[np.maximum(parent, 0), (edge + 2) % 3], -1)
        self.terms = {m: _tree_predictors(self.links, self.tri, self.explicit, self.per, self.new, bool(m & 1),
                                          kind == shellwalk.GroupKind.SHELL_WALK_LATER) for m in (0, 1)}
        self.pstart, self.pterms = parallelograms(self.tri, self.explicit)

    def residuals(self, mode: int, kind=None) -> tuple[np.ndarray, np.ndarray]:
        """The integer residuals (E, 3) of ``kind`` (default the group's) in ``mode``, and each explicit
        corner's prediction type (0 none, 1 step, 2 parallelogram, 3 reflection, 3 + n for n averaged)."""
        from planefmt.container import shellwalk
        from planefmt.container.shellfields import _predict, predict_averaged, predict_reflected

        kind = self.kind if kind is None else kind
        v = self.values
        if mode & shellwalk.MODE_TABLES:
            v = v.copy()
            for axis in range(3):
                _, v[self.explicit, axis] = np.unique(self.values[self.explicit, axis], return_inverse=True)
        terms = self.terms[mode & 1]
        pred = _predict(v, terms)
        ptype = np.where(terms[:, 0] < 0, 0, np.where(terms[:, 1] >= 0, 2, 1))
        if kind == shellwalk.GroupKind.SHELL_WALK_MULTI:
            pred = predict_averaged(v, self.pstart, self.pterms, pred)
            n = np.diff(self.pstart)
            ptype = np.where(n > 0, 3 + n, ptype)
        elif kind == shellwalk.GroupKind.SHELL_WALK_REFLECT:
            turned = predict_reflected(v, terms[:, 0], pred)
            ptype = np.where((turned != pred).any(axis=1), 3, ptype)
            pred = turned
        return (v - pred)[self.explicit], ptype[self.explicit]

    def edge_ctx(self) -> np.ndarray:
        """Bit length of each explicit corner's gate edge in grid units (0 without an explicit gate)."""
        a, b = self.gate[:, 0], self.gate[:, 1]
        ok = self.attached & self.explicit[a] & self.explicit[b]
        d = np.abs(self.values[a] - self.values[b]).max(axis=1)
        return np.where(ok, bitlen(d), 0)[self.explicit]


# --------------------------------------------------------------------------------------------------
# Closed-loop codings: each explicit corner predicted from the decoded corners before it.


def _fan_tan(w: Walk) -> tuple[np.ndarray, np.ndarray]:
    """Per corner: tan of the largest angle between its gate triangle's normal and the normals of
    every triangle around it, on the source plus SLACK_MARGIN (inf for corners on a boundary or a
    non-manifold edge, or without a gate), and the distance from the corner to its link's edges
    projected on the gate plane (0 likewise)."""
    p, tri = w.src, w.tri
    v = len(p)
    nrm = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    a, b, o = w.gate[:, 0], w.gate[:, 1], np.maximum(w.opposite, 0)
    # The frame's normal: the parent triangle's (i1, i0, o), known before k.
    g = np.cross(p[a] - p[b], p[o] - p[b])
    g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
    corner = tri.reshape(-1)
    tid = np.repeat(np.arange(len(tri)), 3)
    cos = np.einsum("ij,ij->i", nrm[tid], g[corner])
    worst = np.ones(v)
    np.minimum.at(worst, corner, cos)
    # Closed manifold fan: every directed edge out of the corner has its twin.
    e0, e1 = tri.reshape(-1), tri[:, [1, 2, 0]].reshape(-1)
    key = e0 * v + e1
    twin = np.isin(e1 * v + e0, key)
    closed = np.ones(v, dtype=bool)
    np.logical_and.at(closed, e0, twin)
    np.logical_and.at(closed, e1, twin)
    _, count = np.unique(key, return_counts=True)
    if (count > 1).any():
        bad = np.unique(key[np.isin(key, _[count > 1])] // v)
        closed[bad] = False
    ang = np.arccos(np.clip(worst, -1, 1)) + SLACK_MARGIN
    tan = np.where(closed & w.attached & (ang < math.pi / 2 - 1e-3), np.tan(np.minimum(ang, 1.5)), np.inf)
    # Kernel distance: each triangle's far edge (not through the corner) projected on the gate plane.
    far = {0: (1, 2), 1: (2, 0), 2: (0, 1)}
    dist = np.full(v, np.inf)
    for s, (i, j) in far.items():
        k = tri[:, s]
        n = g[k]
        q0, q1, x = p[tri[:, i]], p[tri[:, j]], p[k]
        proj = lambda y: y - np.einsum("ij,ij->i", y - x, n)[:, None] * n  # noqa: E731
        u0, u1 = proj(q0) - x, proj(q1) - x
        e = u1 - u0
        t = np.clip(-np.einsum("ij,ij->i", u0, e) / np.maximum(np.einsum("ij,ij->i", e, e), 1e-300), 0, 1)
        d = np.linalg.norm(u0 + t[:, None] * e, axis=1)
        np.minimum.at(dist, k, d)
    return tan, np.where(np.isfinite(tan), dist, 0.0)


def closed_loop(w: Walk, frame: str, predictor: str = "kind", slack: bool = False, bcc: bool = False) -> dict:
    """Residuals (E, 3) of every explicit corner coded closed loop on a lattice of the encoder's step,
    in the global axes (``frame`` "global") or the corner's gate frame ("local", normal last), with
    ``slack`` a wider tangential step where the corner's fan allows; the decoded points; the slack
    classes. ``bcc``: the body-centred cubic lattice of the same covering radius e (cell 4e/sqrt 5: the
    thinnest lattice covering of space), global axes; ``classes`` then says which of its two cubic
    cosets each corner is on."""
    from planefmt.container import shellwalk

    s = w.step
    eps = s * math.sqrt(3.0) / 2.0
    v = len(w.explicit)
    dec = w.src.copy()
    dec_l = dec.tolist()
    src_l = w.src.tolist()
    terms = w.terms[w.mode & 1].tolist()
    multi = w.kind == shellwalk.GroupKind.SHELL_WALK_MULTI or predictor == "multi"
    reflect = w.kind == shellwalk.GroupKind.SHELL_WALK_REFLECT and predictor == "kind"
    pstart, pterms = w.pstart.tolist(), w.pterms.tolist()
    gate, opp, att = w.gate.tolist(), w.opposite.tolist(), w.attached.tolist()
    explicit = w.explicit.tolist()
    step_src = [t[0] for t in terms]
    if slack:
        tan, room = _fan_tan(w)
        tan, room = tan.tolist(), room.tolist()
    out, classes = [], []
    bend = [None] * v  # each corner's parallelogram residual (decoded - gate parallelogram), for "curv"

    def add(x, y, sign=1.0):
        return [x[0] + sign * y[0], x[1] + sign * y[1], x[2] + sign * y[2]]

    for k in range(v):
        if not explicit[k]:
            continue
        p_, a_, b_ = terms[k]
        pred = [0.0, 0.0, 0.0] if p_ < 0 else list(dec_l[p_])
        if a_ >= 0:
            pred = add(add(pred, dec_l[a_]), dec_l[b_], -1.0)
        if p_ < 0:
            pred = [w.origin[0], w.origin[1], w.origin[2]]
        if multi and pstart[k + 1] > pstart[k]:
            acc = [0.0, 0.0, 0.0]
            for a, b, c in pterms[pstart[k]:pstart[k + 1]]:
                acc = add(acc, add(add(dec_l[a], dec_l[b]), dec_l[c], -1.0))
            n = pstart[k + 1] - pstart[k]
            pred = [acc[0] / n, acc[1] / n, acc[2] / n]
        elif reflect and p_ >= 0 and step_src[p_] >= 0 and step_src[step_src[p_]] >= 0:
            a, b, c = p_, step_src[p_], step_src[step_src[p_]]
            d1 = add(dec_l[b], dec_l[c], -1.0)
            d2 = add(dec_l[a], dec_l[b], -1.0)
            dd = d2[0] ** 2 + d2[1] ** 2 + d2[2] ** 2
            if dd > 0:
                f = 2 * (d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]) / dd
                pred = [dec_l[a][i] + f * d2[i] - d1[i] for i in range(3)]
        g0, g1, o = gate[k][0], gate[k][1], opp[k]
        have_gate = att[k] and o >= 0
        if predictor == "curv" and have_gate and bend[o] is not None and explicit[g0] and explicit[g1] and explicit[o]:
            par = add(add(dec_l[g0], dec_l[g1]), dec_l[o], -1.0)
            nx = _normal(dec_l[g1], dec_l[g0], par)
            if nx is not None:
                bo = bend[o]
                h = bo[0] * nx[0] + bo[1] * nx[1] + bo[2] * nx[2]
                pred = [par[i] + h * nx[i] for i in range(3)]
        if frame == "local" and have_gate:
            e1 = add(dec_l[g0], dec_l[g1], -1.0)
            ln = math.sqrt(e1[0] ** 2 + e1[1] ** 2 + e1[2] ** 2)
            nx = _normal(dec_l[g1], dec_l[g0], dec_l[o])
            if ln > 0 and nx is not None:
                e1 = [e1[0] / ln, e1[1] / ln, e1[2] / ln]
                e2 = [nx[1] * e1[2] - nx[2] * e1[1], nx[2] * e1[0] - nx[0] * e1[2], nx[0] * e1[1] - nx[1] * e1[0]]
                axes = (e1, e2, nx)
            else:
                axes = None
        else:
            axes = None
        d = add(src_l[k], pred, -1.0)
        steps = (s, s, s)
        cls = 0
        if slack and axes is not None and math.isfinite(tan[k]):
            t = max(tan[k], 1e-9)
            # s_n = 2e/3, s_t = sqrt2 * (2e/3) / tan: wider than s only where tan < sqrt2 * (2e/3) / s.
            st = math.sqrt(2.0) * (2.0 * eps / 3.0) / t
            # Classes quantize tan up to powers of 2^(1/2): the reader's steps.
            c = min(SLACK_CLASSES - 1, max(0, int(math.floor(-2.0 * math.log2(t)))))
            tq = 2.0 ** (-c / 2.0)
            st = math.sqrt(2.0) * (2.0 * eps / 3.0) / tq
            sn = 2.0 * eps / 3.0
            if sn * st * st > s ** 3 and st / math.sqrt(2.0) <= 0.5 * room[k]:
                steps, cls = (st, st, sn), c + 1
        classes.append(cls)
        if bcc:
            cell = 4.0 * eps / math.sqrt(5.0)
            dl = d if axes is None else [d[0] * ax[0] + d[1] * ax[1] + d[2] * ax[2] for ax in axes]
            q0 = [round(dl[i] / cell) for i in range(3)]
            q1 = [math.floor(dl[i] / cell) for i in range(3)]
            e0 = sum((dl[i] - q0[i] * cell) ** 2 for i in range(3))
            e1 = sum((dl[i] - (q1[i] + 0.5) * cell) ** 2 for i in range(3))
            cls = int(e1 < e0)
            classes[-1] = cls
            q = q1 if cls else q0
            back = [(q[i] + 0.5 * cls) * cell for i in range(3)]
            if axes is not None:
                back = [sum(back[j] * axes[j][i] for j in range(3)) for i in range(3)]
        elif axes is None:
            q = [round(d[i] / steps[i]) for i in range(3)]
            back = [q[i] * steps[i] for i in range(3)]
        else:
            q = [round((d[0] * ax[0] + d[1] * ax[1] + d[2] * ax[2]) / st_) for ax, st_ in zip(axes, steps)]
            back = [sum(q[j] * steps[j] * axes[j][i] for j in range(3)) for i in range(3)]
        out.append(q)
        dec_l[k] = add(pred, back)
        if have_gate and explicit[g0] and explicit[g1] and explicit[o]:
            par = add(add(dec_l[g0], dec_l[g1]), dec_l[o], -1.0)
            bend[k] = add(dec_l[k], par, -1.0)
    return {"res": np.array(out, dtype=np.int64).reshape(-1, 3), "decoded": np.array(dec_l),
            "classes": np.array(classes, dtype=np.int64)}


def _normal(a, b, c):
    """Unit normal of triangle (a, b, c) (counter-clockwise), None if degenerate."""
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    ln = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
    return None if ln == 0 else [n[0] / ln, n[1] / ln, n[2] / ln]


# --------------------------------------------------------------------------------------------------


def measure(path: str, tolerance: float, hausdorff: int = 0) -> dict:
    """Every coding's bits of one mesh's walk groups (see the module docstring)."""
    import planefmt
    from planefmt.container import shellwalk

    scene, _, _ = load(path)
    data, seen = _encode_with_sources(scene, tolerance)
    with planefmt.open(io.BytesIO(data)) as r:
        groups = [g for g in r.part_groups() if g.kind in shellwalk.WALK_KINDS]
    row = {"file": len(data), "walks": 0, "unmatched": 0, "E": 0, "bits": {}, "bytes": {}, "kinds": {}}
    bits, nbytes = row["bits"], row["bytes"]

    def put(name, b, shell_bytes=None):
        bits[name] = bits.get(name, 0.0) + b
        # Per shell, a mode: the smaller of today's Brotli bytes and this coding's.
        nbytes[name] = nbytes.get(name, 0.0) + min(b / 8.0, today) if shell_bytes is None else \
            nbytes.get(name, 0.0) + shell_bytes

    checked = 0
    for g in groups:
        shell = g.shell
        if not np.asarray(shell.explicit).any():
            continue
        src = _sources(shell, seen)
        if src is None:
            row["unmatched"] += 1
            continue
        w = Walk(g.kind, shell, src)
        res, ptype = w.residuals(w.mode)
        from planefmt.container import varint
        if varint.encode(varint.zigzag(res.T)) != w.fields["coordinates"]:
            raise RuntimeError(f"{path}: re-derived residuals differ from the body's")
        e = len(res)
        row["walks"] += 1
        row["E"] += e
        row["kinds"][f"{int(g.kind)}/{w.mode}"] = row["kinds"].get(f"{int(g.kind)}/{w.mode}", 0) + 1
        today = len(brotli.compress(w.fields["tables"] + w.fields["coordinates"], quality=11))
        put("today brotli", 8.0 * today, today)
        # The models code the residuals; a mode with tables keeps them as the writer stores them.
        tables = 8.0 * len(w.fields["tables"])
        put("today", adaptive_bits(res.T) + tables)
        put("static", static_bits(res) + tables)
        grid_res, grid_type = w.residuals(w.mode & 1)
        put("grid", adaptive_bits(grid_res.T))
        put("grid brotli", 8.0 * len(brotli.compress(varint.encode(varint.zigzag(grid_res.T)), quality=11)))
        prev = prev_contexts(res)
        edge = w.edge_ctx()
        ax = np.arange(3)[None, :]
        put("prev", adaptive_bits(res, prev * 3 + ax) + tables)
        put("edge", adaptive_bits(res, edge[:, None] * 3 + ax) + tables)
        put("pred", adaptive_bits(res, np.minimum(ptype, 7)[:, None] * 3 + ax) + tables)
        put("prev+edge+pred", adaptive_bits(res, ((np.minimum(ptype, 7)[:, None] * (CLIP + 1) + edge[:, None])
                                                   * (CLIP + 1) + prev) * 3 + ax) + tables)
        glob = closed_loop(w, "global")
        loc = closed_loop(w, "local")
        put("global", adaptive_bits(glob["res"].T))
        put("local", adaptive_bits(loc["res"].T))
        put("local ctx", adaptive_bits(loc["res"], prev_contexts(loc["res"]) * 3 + ax))
        sl = closed_loop(w, "local", slack=True)
        put("slack", adaptive_bits(sl["res"].T) + _kt(sl["classes"], np.zeros(e, dtype=np.int64), SLACK_CLASSES + 1))
        put("slack free", adaptive_bits(sl["res"].T))
        bc = closed_loop(w, "global", bcc=True)
        put("bcc", adaptive_bits(bc["res"].T) + _kt(bc["classes"], np.zeros(e, dtype=np.int64), 2))
        lb = closed_loop(w, "local", bcc=True)
        put("local bcc ctx", adaptive_bits(lb["res"], prev_contexts(lb["res"]) * 3 + ax)
            + _kt(lb["classes"], np.zeros(e, dtype=np.int64), 2))
        put("local brotli", 8.0 * len(brotli.compress(varint.encode(varint.zigzag(loc["res"].T)), quality=11)))
        put("slack ctx", adaptive_bits(sl["res"], prev_contexts(sl["res"]) * 3 + ax)
            + _kt(sl["classes"], np.zeros(e, dtype=np.int64), SLACK_CLASSES + 1))
        row["slack corners"] = row.get("slack corners", 0) + int((sl["classes"] > 0).sum())
        multi_res, _ = w.residuals(w.mode & 1, shellwalk.GroupKind.SHELL_WALK_MULTI)
        put("multi", adaptive_bits(multi_res.T))
        curv = closed_loop(w, "global", predictor="curv")
        put("curv", adaptive_bits(curv["res"].T))
        lc = closed_loop(w, "local", predictor="curv")
        put("local+curv ctx", adaptive_bits(lc["res"], prev_contexts(lc["res"]) * 3 + ax))
        # Normal component alone: what a coder that spent nothing on tangents (a remesher's one scalar per
        # vertex) would pay on this lattice.
        put("normal only", adaptive_bits(loc["res"][:, 2]))
        if checked < hausdorff:
            row.setdefault("hausdorff", []).append(_bound(w, sl["decoded"], glob["decoded"]))
            checked += 1
    return row


def _bound(w: Walk, slack: np.ndarray, cubic: np.ndarray) -> dict:
    """Certified two-sided Hausdorff distance of the slack and cubic decodings against the source
    (the walk's triangles, named corners at their source), over the covering radius e."""
    from planefmt.geometry.hausdorff import hausdorff

    eps = w.step * math.sqrt(3.0) / 2.0
    out = {"e": eps}
    for name, pts in (("slack", slack), ("cubic", cubic)):
        r = hausdorff(w.src, w.tri, pts, w.tri, target=None, tolerance=0.01 * eps)
        out[name] = float(r.upper) / eps
    out["largest corner move / e slack"] = float(np.linalg.norm(slack - w.src, axis=1).max()) / eps
    return out


def _in_child(fn, args, timeout: float) -> dict:
    with multiprocessing.get_context("fork").Pool(1) as pool:
        try:
            return pool.apply_async(fn, args).get(timeout)
        except multiprocessing.TimeoutError:
            return {"failed": f"timeout after {timeout:g} s"}
        except Exception as err:  # noqa: BLE001 - a row reports any failure
            return {"failed": f"{type(err).__name__}: {str(err)[:200]}"}


#: Columns printed, in order.
COLUMNS = ("today brotli", "today", "static", "grid", "prev", "edge", "pred", "prev+edge+pred", "global",
           "local", "local ctx", "slack", "slack free", "slack ctx", "bcc", "local bcc ctx", "local brotli", "multi", "curv", "local+curv ctx", "normal only")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--corpus", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "bench-corpus"))
    ap.add_argument("--categories", help="comma-separated folders of the corpus (default: all)")
    ap.add_argument("--max-triangles", type=int, default=30000)
    ap.add_argument("--cache", default=os.path.join(os.path.dirname(__file__), "draco-errors.json"))
    ap.add_argument("--hausdorff", type=int, default=0, help="shells per mesh whose slack decoding is measured")
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--jobs", type=int, default=1, help="meshes at once (1: one at a time)")
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--summary", help="print the summary of rows kept by --json, measuring nothing")
    ap.add_argument("meshes", nargs="*", help="paths relative to the corpus (default: all)")
    args = ap.parse_args(argv)
    if args.summary:
        summarize(json.load(open(args.summary)))
        return 0
    cache = json.load(open(args.cache))
    paths = [os.path.join(args.corpus, m) for m in args.meshes] or \
        _meshes(args.corpus, args.categories.split(",") if args.categories else None)
    rows = []
    for path in paths:
        rel = os.path.relpath(path, args.corpus)
        d = cache.get(f"{rel}@14")
        if d is None or "failed" in d or (args.max_triangles and d["triangles"] > args.max_triangles):
            continue
        r = _in_child(measure, (path, max(d["error"], MEASURE_RESOLUTION), args.hausdorff), args.timeout)
        r.update(mesh=rel, category=rel.split(os.sep)[0], draco=d["draco"], triangles=d["triangles"])
        rows.append(r)
        if "failed" in r or not r.get("E"):
            print(f"{rel}: {r.get('failed', 'no explicit corners in walks')}", flush=True)
            continue
        e = r["E"]
        print(f"{rel}: {e} explicit corners, file {r['file']} B, draco {r['draco']} B; bits/corner "
              + " ".join(f"{k} {r['bits'][k] / e:.2f}" for k in COLUMNS)
              + f"; slack corners {r.get('slack corners', 0)}"
              + (f"; hausdorff {r['hausdorff']}" if "hausdorff" in r else ""), flush=True)
    summarize(rows)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


#: The codings a reader could follow as measured (not ``static``, a floor; not ``slack free``, whose
#: classes a reader cannot know; not ``normal only``, which drops the tangents): "best realizable" is
#: the smallest of them per mesh.
REALIZABLE = ("today", "prev", "edge", "pred", "prev+edge+pred", "local", "local ctx", "slack", "slack ctx", "bcc",
              "local bcc ctx", "local brotli", "multi", "curv", "local+curv ctx")

#: Issue 52's targets at Draco-14's error: median .pln / Draco-14 per category.
TARGETS = {"cad": 0.5, "convex": 0.4, "all": 0.6}


def summarize(rows: list[dict]) -> None:
    """Per category medians of bits per explicit corner, of projected ratios to Draco-14, of the share
    of the file today's coordinates take, and of the bits per corner the category's target leaves them."""
    ok = [r for r in rows if r.get("E")]
    cats = sorted({r["category"] for r in ok}) + ["all"]
    print("\nmedian bits per explicit corner (meshes with walk corners):")
    print("| category | meshes | " + " | ".join(COLUMNS) + " |")
    for c in cats:
        sel = [r for r in ok if c in ("all", r["category"])]
        print(f"| {c} | {len(sel)} | " + " | ".join(
            f"{statistics.median(r['bits'][k] / r['E'] for r in sel):.2f}" for k in COLUMNS) + " |")
    print("\nmedian per mesh of each coding's bits per corner minus grid's (the same lattice's, no tables):")
    print("| category | meshes | " + " | ".join(COLUMNS) + " |")
    for c in cats:
        sel = [r for r in ok if c in ("all", r["category"])]
        print(f"| {c} | {len(sel)} | " + " | ".join(
            f"{statistics.median((r['bits'][k] - r['bits']['grid']) / r['E'] for r in sel):+.2f}" for k in COLUMNS) + " |")
    print("\nmedian projected .pln / Draco-14 (file - today's coordinate bytes + the coding's, per shell the smaller):")
    print("| category | meshes | file today | " + " | ".join(COLUMNS[1:]) + " | best realizable |")
    allrows = [r for r in rows if "file" in r]
    for c in sorted({r["category"] for r in allrows}) + ["all"]:
        sel = [r for r in allrows if c in ("all", r["category"])]

        def ratio(r, k):
            if not r.get("E"):
                return r["file"] / r["draco"]
            return (r["file"] - r["bytes"]["today brotli"] + r["bytes"][k]) / r["draco"]
        print(f"| {c} | {len(sel)} | {statistics.median(r['file'] / r['draco'] for r in sel):.3f} | " + " | ".join(
            f"{statistics.median(ratio(r, k) for r in sel):.3f}" for k in COLUMNS[1:]) + " | "
            + f"{statistics.median(min(ratio(r, k) for k in REALIZABLE) for r in sel):.3f} |")
    print("\ntoday's coordinates (Brotli-11, tables and coordinates fields alone) as a share of the file, and the "
          "bits per explicit corner the target leaves them (target x Draco - the rest of the file; negative: "
          "the rest alone is over the target), medians over meshes with walk corners:")
    print("| category | meshes | target | coordinates / file | bits per corner today | bits per corner at target |")
    for c in cats:
        sel = [r for r in ok if c in ("all", r["category"])]
        t = TARGETS.get(c, 0.7)
        share = statistics.median(r["bytes"]["today brotli"] / r["file"] for r in sel)
        now = statistics.median(r["bits"]["today brotli"] / r["E"] for r in sel)
        need = statistics.median(8.0 * (t * r["draco"] - (r["file"] - r["bytes"]["today brotli"])) / r["E"]
                                 for r in sel)
        print(f"| {c} | {len(sel)} | {t} | {share:.2f} | {now:.1f} | {need:.1f} |")


if __name__ == "__main__":
    sys.exit(main())
