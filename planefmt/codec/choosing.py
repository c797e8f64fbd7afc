"""Choosing the coding of the plane triplets.

The paper's scheme (:func:`_choose`): each candidate coding's planes go through
:func:`planefmt.container.quantize.roundtrip`, are decoded and verified against the tolerance
(:mod:`planefmt.codec.verifying`); a first-order prediction of the vertex displacement skips widths
that cannot pass, the narrowest passing quantized width is found by bisection, then float32, then
float64. The shell scheme (:func:`_choose_shells`) picks by file size among codings whose shells
are correct by construction.
"""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Callable, Sequence
from contextvars import ContextVar
from dataclasses import dataclass, replace

import numpy as np

from .. import progress
from ..container import headers, quantize, records, shellfields, shellwalk
from ..errors import GeometryError, PlnError, PlnWarning
from ..geometry.hausdorff import DEFAULT_MAX_PIECES
from ..geometry.planes import from_triplets, transform_points
from ..geometry.trianglegeom import TriangleIndex
from ..geometry.topology import euler_characteristic, signed_volume
from ..groups.shells import FREE, ShellPlan, decode_shell, encode_shell, plan_shell, rewalked, shell_tree
from ..model import TREE_KINDS, Coding, GroupKind, Mesh, Quantization
from .decoding import EXACT, SHELL_KINDS, _concatenate, plane_error
from .preparing import (LOSSLESS_TOLERANCE, STRUCTURE_TOLERANCE, _Object, _area, _diagonal, _fit_error, _one_shell,
                      structure_problem)
from .strategies import GroupSpec
from .verifying import _Incidences, _decode_object, _measure, _peak, _verify


#: Quantized widths tried for nu and phi.
MIN_BITS, MAX_BITS = 2, 32

#: Refinement budget of a pass/fail verification of a quantized coding in the bisection: a
#: candidate whose bound cannot be certified within it counts as failed. Float64, the last, gets
#: ``DEFAULT_MAX_PIECES`` (plate_holes.STL: certified with 2M pieces in 24 s, not with 200k).
#: plate_holes.STL at 2e-5, 20-bit planes (true error under 2.6e-6): uncertified with 100k
#: pieces in 11.6 s, certified with 400k in 13.8 s; the bisection then stops at 21 bits, not 26.
_VERIFY_PIECES = 500_000

#: If no width passes, the narrowest one left undecided by the budget with a certified lower bound
#: at most this fraction of the target is verified again with ``_RETRY_PIECES``.
#: 1002_tray_bottom.STL at tolerance 1e-4, 22-bit angles (lower bound 7e-7): uncertified with 100k
#: pieces, certified with 2M, both in about 16 s.
_LIKELY_PASS = 0.25

_RETRY_PIECES = DEFAULT_MAX_PIECES

#: Budget of a second verification of float planes, the last coding, when the first ran out of
#: pieces with the lower bound at most ``_LIKELY_PASS`` of the target. ADIS16480.STL at 1e-6 (one
#: BSP group; the source's sliver triangles run along decoded outlines 1e-9 inside their own, and
#: are refined along them until the Lipschitz bound holds): lower bound 5.6e-8, certified with
#: 2.9 million pieces in about 200 s, not with 2 million.
_FINAL_PIECES = 8_000_000


@dataclass(frozen=True)
class _Choice:
    coding: Coding
    quantization: Quantization | None
    meshes: list[Mesh]  # decoded, local coordinates
    bbox: np.ndarray  # world
    diagonal: float
    error_bound: float  # fraction of diagonal
    lossy: bool


#: Set while a version 6 file is encoded: its header holds the h range as two float32 values (spec §5), so
#: the range is chosen as those before any plane is quantized and measured (a context variable, not an
#: argument of every chooser, because only the candidates' range depends on it).
F32_RANGE: ContextVar[bool] = ContextVar("f32_range", default=False)


#: Version 6: the h range of each candidate coding is the one of fewest header bytes (spec §5, r32) that
#: moves no plane by more than the float64 rounding of planes fitted to float32 corners (this fraction of the
#: largest |h|, and at most ``H_RANGE_NOISE_TOLERANCE`` of the tolerance) beyond what the range's float32
#: hull does (headers.short_range); for shells, whose corners are right by construction whatever the planes,
#: also by up to ``H_RANGE_STEP`` of an h step. Verified codings are not widened beforehand: their widths
#: are the narrowest that verify, often at the tolerance's edge (two_objects_inverse_materials.gltf at
#: 3.9e-5: 13 bits verified with its hull, 14 needed with a range 1/64 of a step wider, 351 -> 359 bytes);
#: ``_choose`` tries a shorter range after it has chosen.
H_RANGE_STEP = 2.0 ** -6
H_RANGE_NOISE = 2.0 ** -40
H_RANGE_NOISE_TOLERANCE = 2.0 ** -10
#: Version 6: planes up to which a chosen coding is verified once more with an h range that moves them by
#: up to half the error left (``_choose``): a few header bytes, which count only in small files.
H_RANGE_RETRY_PLANES = 256


def _candidates(coding: Coding | None, bits: int | tuple[int, int, int] | None, table: np.ndarray,
                radius: float, allowance: float = 0.0, widen: float = 0.0) -> list[tuple[Coding, Quantization | None]]:
    """Codings to try, cheapest first; forced ones alone. ``allowance``: the error the file may have, in
    model units (bounds the planes' moves onto a version 6 h range's ends); ``widen``: the fraction of an h
    step by which a version 6 h range may move planes further for fewer header bytes."""
    h_min, h_max = float(table[:, 2].min()), float(table[:, 2].max())
    short = F32_RANGE.get()
    hull = headers.f32_range(h_min, h_max) if short else (h_min, h_max)
    span = hull[1] - hull[0]
    noise = min(H_RANGE_NOISE * max(abs(h_min), abs(h_max)), H_RANGE_NOISE_TOLERANCE * allowance)

    def ranged(b_nu: int, b_phi: int, b_h: int) -> Quantization:
        if not short:
            return Quantization(b_nu, b_phi, b_h, h_min, h_max)
        levels = (1 << b_h) - 1
        room = noise + widen * span / (2 * levels)
        return Quantization(b_nu, b_phi, b_h, *headers.short_range(h_min, h_max, levels, room))

    if bits is not None:
        widths = (bits,) * 3 if isinstance(bits, int) else tuple(bits)
        if len(widths) != 3 or not all(isinstance(b, (int, np.integer)) for b in widths):
            raise PlnError(f"bits must be an int or three ints, not {bits!r}", code="UNSUPPORTED_CODING")
        q = ranged(*(int(b) for b in widths))
        quantize.check_quantization(q)
        return [(Coding.QUANTIZED, q)]
    if coding is not None and not Coding(coding).quantized:
        return [(Coding(coding), None)]
    out: list[tuple[Coding, Quantization | None]] = []
    for b in range(MIN_BITS, MAX_BITS + 1):
        # nu and phi get equal widths (equal steps on the equator). h's half step is kept at half
        # the displacement an angle half step causes at the far end of the model: the angles
        # cost two widths, h one, so this split minimises bits for a given error.
        target = 0.5 * Quantization(b, b, 1, 0.0, 0.0).steps()[0] * max(radius, 1e-300)
        bits_h = 1 if span <= 0 else min(MAX_BITS, max(1, math.ceil(math.log2(span / target + 1))))
        out.append((Coding.QUANTIZED, ranged(b, b, bits_h)))
    if coding is None:
        out += [(Coding.FLOAT32, None), (Coding.FLOAT64, None)]
    return out


def _choose(objects: Sequence[_Object], tolerance: float, coding: Coding | None,
            bits: int | tuple[int, int, int] | None, watertight: bool = True) -> _Choice:
    """Pick the cheapest coding whose decoded surfaces meet the tolerance; verify it.

    Without ``watertight``, closed objects whose float64 decoding fails a
    solid's checks (closed, Euler characteristic, volume) are held to an
    open surface's checks when nothing else passes.
    """
    forced = coding is not None or bits is not None
    simplified = any(o.simplified for o in objects)
    offsets = np.cumsum([0] + [len(o.triplets) for o in objects])
    spans = list(zip(offsets[:-1], offsets[1:]))
    table = np.concatenate([o.triplets for o in objects])
    diag_src = _diagonal(np.concatenate([transform_points(o.vertices, o.world) for o in objects]))
    scale = [float(np.linalg.norm(o.world[:3, :3], 2)) for o in objects]
    radius = max(float(np.linalg.norm(o.vertices, axis=1).max()) for o in objects)

    base = [_decode_object(o.triplets, o, EXACT) for o in objects]
    base_meshes = [_concatenate(d) for d in base]
    if simplified:
        # The tolerance bounds what the coding adds to the simplified planes' own error.
        base_err = [_measure(m, o, tolerance * diag_src) for m, o in zip(base_meshes, objects)]
        extra = max(base_err)
    else:
        # Lossless: what float64 planes lose is the polygon fit; measured with the chosen coding.
        base_err = [(o.fit + o.mended) * s for o, s in zip(objects, scale)]
        extra = 0.0

    def limit(meshes: list[Mesh]) -> tuple[float, np.ndarray]:
        world = np.concatenate([transform_points(m.vertices, o.world) for m, o in zip(meshes, objects)])
        return extra + tolerance * min(diag_src, _diagonal(world)), world

    allowance, _ = limit(base_meshes)
    if not forced and max(base_err) > allowance:
        raise _fit_error(max(base_err) / diag_src, tolerance)

    # Lossless keeps the volume to STRUCTURE_TOLERANCE; a lossy tolerance lets it move with the surface.
    band = tolerance if tolerance > LOSSLESS_TOLERANCE else 0.0

    # Lower bounds (fractions of the bound) of quantized candidates whose verification ran out of pieces.
    undecided: dict[int, float] = {}
    # Why the float64 planes, the finest coding, failed: the reason given when nothing passes.
    why: list[str] = []

    def named(k: int) -> str:
        return f"object {k}" + (f" ({objects[k].name!r})" if objects[k].name else "")

    tried = [0]

    def attempt(cod: Coding, q: Quantization | None, pieces: int | None = None, key: int = -1) -> _Choice | None:
        """The choice of this coding if its decoding keeps the structure and verifies; None if not."""
        # How many codings a search verifies is not known beforehand: a count, not a fraction.
        progress.report("verifying codings", tried[0])
        tried[0] += 1
        if cod == Coding.FLOAT64:
            decoded = base
        else:
            rt = quantize.roundtrip(table, cod, q)
            try:
                error = plane_error(cod, q, tolerance, diag_src)
                decoded = [_decode_object(rt[a:b], o, error) for (a, b), o in zip(spans, objects)]
            except GeometryError:
                # Coarse planes can lose a face or the solid altogether: not this coding.
                if forced:
                    raise
                return None
        meshes = base_meshes if decoded is base else [_concatenate(d) for d in decoded]
        if not forced and not simplified:
            problems = [(k, structure_problem(m, o, band * diag_src / sc))
                        for k, (m, o, sc) in enumerate(zip(meshes, objects, scale))]
            problems = [(k, p) for k, p in problems if p is not None]
            if problems:
                if cod == Coding.FLOAT64:
                    why[:] = [f"{named(k)}: {p}" for k, p in problems[:1]]
                return None
        bound, world = limit(meshes)
        if forced:
            errors = [_measure(m, o, bound) for m, o in zip(meshes, objects)]
        else:
            # Float64 is the finest coding, with no next one to certify sooner: it gets the full budget.
            if pieces is None:
                pieces = DEFAULT_MAX_PIECES if cod == Coding.FLOAT64 else _VERIFY_PIECES
            checks = [_verify(m, o, bound, pieces, d) for m, o, d in zip(meshes, objects, decoded)]
            errors = [c[0] for c in checks]
            if max(errors) > bound:
                if all(c[1] <= bound for c in checks):
                    undecided[key] = max(c[1] for c in checks) / bound
                if cod == Coding.FLOAT64:
                    k = max(range(len(checks)), key=lambda i: checks[i][1])
                    far = checks[k][1] > bound
                    why[:] = [f"{named(k)}: " + (f"decodes {checks[k][1] / diag_src:.2g} of the diagonal from its "
                                                 f"source" if far else
                                                 f"its distance is not certified within {pieces:,} pieces")]
                return None
        diagonal = _diagonal(world)
        error_bound = max(errors) / diagonal
        return _Choice(coding=cod, quantization=q, meshes=meshes,
                       bbox=np.stack([world.min(axis=0), world.max(axis=0)]), diagonal=diagonal,
                       error_bound=error_bound, lossy=simplified or error_bound > tolerance)

    def shorter(best: _Choice) -> _Choice:
        """``best`` with an h range of fewer header bytes (spec §5) where one that moves the planes by at most
        half the error it leaves verifies too: small files (Cube.gltf, whose planes' h are 1 +- 1.2e-7 from its
        float32 corners, 82 -> 76 bytes)."""
        q = best.quantization
        room = 0.5 * (limit(best.meshes)[0] - best.error_bound * best.diagonal) / max(max(scale), 1e-300)
        if not F32_RANGE.get() or room <= 0 or len(table) > H_RANGE_RETRY_PLANES:
            return best
        h = headers.short_range(float(table[:, 2].min()), float(table[:, 2].max()), (1 << q.bits_h) - 1, room)
        if headers.r32_size(h) >= headers.r32_size((q.h_min, q.h_max)):
            return best
        return attempt(Coding.QUANTIZED, replace(q, h_min=h[0], h_max=h[1])) or best

    candidates = _candidates(coding, bits, table, radius, tolerance * diag_src)
    if forced:
        return attempt(*candidates[0])
    # Half the room for the prediction: the certified bound the verification needs comes quickly
    # only with a margin between the true error and the target.
    room = 0.5 * (allowance - extra)
    own = [0.0 if simplified else e for e in base_err]
    widths = [q for cod, q in candidates if cod == Coding.QUANTIZED]

    incidences = [_Incidences.of(d, o) for d, o in zip(base, objects)]

    def moved(q: Quantization) -> list[tuple[np.ndarray, float]]:
        rt = quantize.roundtrip(table, Coding.QUANTIZED, q)
        return [inc.moved(rt[a:b]) for inc, (a, b) in zip(incidences, spans)]

    admitted = [i for i, q in enumerate(widths)
                if max(e + s * max(_peak(np.linalg.norm(m - inc.vertices, axis=1)), floor)
                       for e, s, (m, floor), inc in zip(own, scale, moved(q), incidences)) <= room]
    # Where nearly parallel planes meet, a vertex slides far along the surface for a small turn of
    # the planes; its distance from the surface is what the error sees (plate_holes.STL at 2e-5:
    # 6.7e-4 of the diagonal moved, 2.5e-5 off the surface, 17 bits). Narrower widths than the
    # displacement admits are admitted by that distance, down to the first that fails it.
    indexes = None
    for i in range(min(admitted, default=len(widths)) - 1, -1, -1):
        indexes = indexes or [TriangleIndex(o.vertices, o.faces) for o in objects]
        if max(e + s * max(_peak(ix.query(m)[0]), floor)
               for e, s, (m, floor), ix in zip(own, scale, moved(widths[i]), indexes)) > room:
            break
        admitted.append(i)
    quantized = [widths[i] for i in sorted(set(admitted))]
    # The narrowest widths that pass, by bisection: finer planes decode closer to the source (the
    # search assumes so; whatever it picks is verified like any other).
    lo, hi, best = 0, len(quantized) - 1, None
    failed: set[Quantization] = set()
    while lo <= hi:
        mid = (lo + hi) // 2
        found = attempt(Coding.QUANTIZED, quantized[mid], key=mid)
        if found is None:
            failed.add(quantized[mid])
            lo = mid + 1
        else:
            best, hi = found, mid - 1
    if best is not None:
        # The screen's margin and the bisection are conservative: narrower widths than the best
        # found often verify as well (plate_holes.STL at 3.7e-5: 17 bits where the bisection stops at
        # 19, 3,053 -> 2,706 bytes). Each is tried in turn down to the first that fails; one the
        # bisection saw fail is not tried again.
        i = widths.index(best.quantization)
        while i > 0 and widths[i - 1] not in failed:
            found = attempt(Coding.QUANTIZED, widths[i - 1])
            if found is None:
                break
            best, i = found, i - 1
        return shorter(best)
    # A width whose bound merely ran out of pieces, its lower bound far under the target, gets one
    # more try with a larger budget before the float codings (1002_tray_bottom.STL at 1e-4).
    # Not when lossless: there the float64 fallback is as small as it gets near the finest widths,
    # and the retry cost 1002_tray_bottom.STL 302 s instead of 108 s.
    likely = sorted(k for k, ratio in undecided.items() if ratio <= _LIKELY_PASS)
    if likely and tolerance > LOSSLESS_TOLERANCE:
        found = attempt(Coding.QUANTIZED, quantized[likely[0]], pieces=_RETRY_PIECES)
        if found is not None:
            return found
    for cod, q in candidates:
        if cod in (Coding.FLOAT32, Coding.FLOAT64):
            found = attempt(cod, q, key=-2 if cod == Coding.FLOAT64 else -1)
            if found is None and cod == Coding.FLOAT64 and undecided.get(-2, 1.0) <= _LIKELY_PASS:
                found = attempt(cod, q, pieces=_FINAL_PIECES)
            if found is not None:
                return found
    # Closed objects whose float64 decoding is no solid: what watertight=False would store open.
    opened = [k for k, (m, o) in enumerate(zip(base_meshes, objects))
              if o.closed and structure_problem(m, o) is not None]
    if not watertight:
        # Only when the solid cannot be had: coarser widths that open a solid that finer ones keep
        # closed would otherwise win.
        if opened:
            found = _choose([replace(o, closed=False) if k in opened else o for k, o in enumerate(objects)],
                            tolerance, coding, bits)
            for k in opened:
                warnings.warn(f"{named(k)} is closed but no coding keeps it a closed solid: stored as an open surface "
                              f"(distance and area kept, not watertight), marked lossy", PlnWarning, stacklevel=4)
            return replace(found, lossy=True)
    hint = ""
    if watertight and opened:
        hint = "; watertight=False (pln convert --allow-open) would store it as an open surface"
    raise GeometryError(f"no triplet coding meets the tolerance {tolerance:g} (two-sided Hausdorff distance; "
                        f"closed sources must also decode closed, with their volume and Euler characteristic, "
                        f"open ones with their area, within {STRUCTURE_TOLERANCE:g})"
                        + (f"; with float64 planes {why[0]}" if why else "") + hint, code="TOLERANCE_NOT_MET")


#: Plane widths (nu and phi; h follows) a shell scheme's coding is chosen among, by file size: every
#: width is correct (a corner its planes cannot name within the budget is explicit), so the choice
#: is one of bytes only. Steps of 4 bits: where named corners won on the corpus (20mm-xyz-cube,
#: not_convex at 1e-6 and draco-14's error) they won at 24 bits, and neighbouring widths differed by
#: 1-2% (bench widths printed per trial); half the trials of steps of 2.
SHELL_WIDTHS = tuple(range(8, 33, 4))

#: Plane widths stop once a file with planes is this many times the smallest so far: over the corpus at
#: 1e-6, Draco-14's error and 1e-4, a width whose planes won did so as the first width written (against
#: the planeless shells: not_convex.obj at 1e-6, 0.95; 20mm-xyz-cube.stl at 1e-4, 0.99), and after a
#: width at 1.25 or more none came under 1.01 (20mm-xyz-cube.stl at 1e-6: 1.51, then 1.01 and 1.04);
#: CAD parts, whose planes lost at 1.1 to 4.3, then try one width, not four or five (encodes 40 % shorter).
#: Judged on the trials' estimated sizes (``SHELL_ESTIMATE_APART``).
SHELL_WIDTH_STOP = 1.25

#: Candidates whose deflated files are within this ratio of the smallest (the best ``SHELL_RANK_TOP``)
#: are written again with Brotli, the file's coder, which decides between them.
SHELL_RANK_CLOSE = 1.03
SHELL_RANK_TOP = 2

#: Trials are sized by an estimate (segments at encoding.ESTIMATE_QUALITY), whose ratios between candidates
#: were within 2 % of the written sizes' (nine bench-corpus meshes at 1e-6, 1e-4 and Draco-14's error); the
#: candidates ranked by ``SHELL_RANK_CLOSE`` are ranked on those. Of the closest few, one whose estimate is
#: more than this ratio under the others' is taken as it is; nearer ones are written to decide.
SHELL_ESTIMATE_APART = 1.03

#: Times the corner budget is quartered when a decoding misses a lossless volume or area.
_SHELL_TIGHTENINGS = 6


#: The shell layouts the encoder chooses among (``bench/shell_bits.py`` measures version 3.2's alone
#: by setting it to ``(GroupKind.SHELL,)``).
SHELL_LAYOUTS = SHELL_KINDS


def _shell_plans(obj: _Object) -> dict[int, ShellPlan]:
    """The :class:`ShellPlan` of each shell group of ``obj`` (by position), from its exact planes."""
    plans = {}
    for k, g in enumerate(obj.groups):
        if g.kind != GroupKind.SHELL:
            continue
        fp = obj.face_plane[g.faces]
        # References are in the object's first-use order, not sorted.
        by_value = np.argsort(g.refs)
        at = np.minimum(np.searchsorted(g.refs[by_value], fp), len(g.refs) - 1)
        local = np.where((fp >= 0) & (g.refs[by_value][at] == fp), by_value[at], FREE)
        omega, _ = from_triplets(obj.triplets[g.refs])
        plans[k] = plan_shell(obj.vertices, obj.faces[g.faces], local, omega,
                              None if obj.walk_plane is None else obj.walk_plane[g.faces], obj.walk_defer)
    return plans


def _shells_for(obj: _Object, plans: dict[int, ShellPlan], planes: np.ndarray,
                budget: float) -> tuple[_Object, float]:
    """``obj`` with its shell groups' corners named or made explicit for the coded ``planes`` (the
    object's triplets as a reader decodes them) within ``budget`` (model units), and the largest
    displacement of a decoded corner from its source vertex (model units), measured on the decoding."""
    groups = list(obj.groups)
    moved = 0.0
    for k, plan in plans.items():
        g = groups[k]
        omega, h = from_triplets(planes[g.refs])
        shell = encode_shell(plan, omega, h, budget)
        # Whichever layout deflates smaller. Of the two trees, parallelograms predict smooth and regular
        # surfaces better (King_geom.usd's coordinates 39.2 kB -> 24.9 kB at draco-14's error), steps
        # from a neighbour flat CAD faces (box.STL 7.5 kB against 10.0 kB). Kind 6 is packed only for a
        # soup (a root for every other triangle or more, each paying a link and three codes): on every
        # connected corpus mesh a tree is the smaller (bench/shell_bits.py).
        # A shell walk (kind 9) is a tree whose coordinates are kind 7's or kind 8's (or indices into
        # tables) and whose connectivity took 40-69 % of theirs, the file 0.58-0.97 of theirs, on the
        # twelve corpus meshes of bench/shell_bits.py: where it may be written, no tree is made to
        # be outbid.
        # A walk is sized here as the first walk kind allowed (kind 9), its mode as deflate ranks them:
        # _walk_kinds codes the kept shells in whichever kind and mode Brotli finds smaller, and the trials
        # of the codings not kept do not pay for it.
        options = []
        trees = [layout for layout in TREE_KINDS if layout in SHELL_LAYOUTS]
        walks = [layout for layout in trees if layout in shellwalk.WALK_KINDS]
        if trees:
            tree, source = shell_tree(shell, plan.walk)
            if walks:
                trees = walks[:1]
                bodies = {trees[0]: shellwalk.shell_walk_body(tree, trees[0], decide=False)}
            else:
                bodies = shellfields.shell_tree_bodies(tree)
            options += [(layout, tree, plan.points[source], bodies[layout]) for layout in trees]
        if GroupKind.SHELL in SHELL_LAYOUTS and (not trees or 2 * int((tree.links == 0).sum()) >= len(tree.links)):
            options.append((GroupKind.SHELL, shell, plan.points, shellwalk.shell_kind_data(GroupKind.SHELL, shell)))
        kind, shell, points, _ = options[0] if len(options) == 1 else \
            min(options, key=lambda c: len(records.pack(c[3], True, records.SHELL_TREE_LEVEL)[1]))
        # A tree's named corners are solved with their planes in ascending order of reference, which the
        # writer renumbers (``reordered_tree``): every order of the three is measured, so the bound
        # holds for the one written.
        orders = itertools.permutations(range(3)) if kind in TREE_KINDS and not shell.explicit.all() \
            else [(0, 1, 2)]
        for order in orders:
            vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)[:, list(order)]
            decoded, _ = decode_shell(omega, h, replace(shell, vertex_planes=vp))
            moved = max(moved, float(np.linalg.norm(decoded - points, axis=1).max(initial=0.0)))
        groups[k] = replace(g, kind=kind, shell=shell)
    return replace(obj, groups=tuple(groups)), moved


def _shell_extent(plans: dict[int, ShellPlan]) -> tuple[float, int]:
    """The half perimeters of the source triangles of an object's shells, summed (model units), and
    their count: what bounds the area and volume their corners' moves change."""
    half, count = 0.0, 0
    for plan in plans.values():
        p = plan.points[np.asarray(plan.facets, dtype=np.int64)[:, 1:]]
        half += float(np.linalg.norm(p - p[:, [1, 2, 0]], axis=2).sum()) / 2.0
        count += len(plan.facets)
    return half, count


def _named_corners(obj: _Object, plans: dict[int, ShellPlan], planes: np.ndarray, budget: float) -> int:
    """How many corners of ``obj``'s shells the coded ``planes`` name within ``budget`` (model units)."""
    count = 0
    for k, plan in plans.items():
        omega, h = from_triplets(planes[obj.groups[k].refs])
        count += int((~encode_shell(plan, omega, h, budget).explicit).sum())
    return count


def _planeless(obj: _Object) -> _Object | None:
    """``obj`` with its shells stripped of their planes (convex groups keep theirs), or None where that
    changes it (colours that ride on planes)."""
    if obj.face_colours is not None and (obj.face_colours != obj.face_colours[0]).any():
        return None
    # A group keeps one reference (spec §9: m >= 1), which its free triangles take their colour from;
    # the table keeps only those planes and the convex groups' (CAD/box.STL at draco-14's error: 2.4 kB
    # of 14 kB were planes nothing referred to). Beside convex groups too: a closed bolt in an open part
    # (kuka_kr10r1100sixx_link_2.stl at Draco-14's error) no longer makes its shell name corners by 10 kB
    # of planes for 2.5 kB of coordinates they save.
    shell = [g.kind == GroupKind.SHELL for g in obj.groups]
    keep = np.unique(np.concatenate([g.refs[:1] if s else g.refs for g, s in zip(obj.groups, shell)]))
    fp = obj.face_plane
    face_plane = None if fp is None else np.where(np.isin(fp, keep), np.searchsorted(keep, fp), -1)
    return replace(obj, triplets=obj.triplets[keep], face_plane=face_plane,
                   plane_colours=None if obj.plane_colours is None else obj.plane_colours[keep],
                   groups=tuple(replace(g, refs=np.searchsorted(keep, g.refs[:1]), bounding=g.bounding[:1]) if s
                                else replace(g, refs=np.searchsorted(keep, g.refs))
                                for g, s in zip(obj.groups, shell)))


#: Faces a plane must hold for a planeless shell's walk to keep them together (more than this many).
#: Flat faces walked whole and the facets of curved ones walked as one surface (a cylinder round, not
#: facet by facet) code CAD corners in fewer bytes: at draco-14's error, plate_holes.STL 1,484 B -> 1,061,
#: octagonal_pocket.stl 3,237 -> 2,848, 1002_tray_bottom.STL 3,147 -> 2,812; box.STL 7,844 -> 7,972,
#: whose walk then names more corners by escapes, keeps the walk without planes. Every plane kept
#: together (0 here): 1,318, 3,160, 3,040; thresholds 12 to 64 within 1 % of 24 over the eight CAD parts.
WALK_PLANE_FACES = 24


def _walking_planes(freed: _Object, face_plane: np.ndarray | None) -> _Object | None:
    """``freed`` (a :func:`_planeless` object) with its walk keeping together the faces of each plane of
    ``face_plane`` (the object's before freeing) that holds more than :data:`WALK_PLANE_FACES`
    faces; None where none does (the walk would be ``freed``'s)."""
    if face_plane is None:
        return None
    _, inverse, counts = np.unique(face_plane, return_inverse=True, return_counts=True)
    large = (counts[inverse] > WALK_PLANE_FACES) & (face_plane >= 0)
    if not large.any():
        return None
    return replace(freed, walk_plane=np.where(large, face_plane, FREE))


def _as_shells(obj: _Object) -> _Object:
    """``obj`` with its convex groups turned into (one) shell over their planes."""
    groups = [GroupSpec(GroupKind.SHELL, g.refs, np.zeros(len(g.refs), dtype=bool), faces=g.faces)
              if g.kind == GroupKind.CONVEX else g for g in obj.groups]
    return replace(obj, groups=tuple(_one_shell(groups)))


def _convex_part(obj: _Object) -> _Object:
    """The object reduced to its convex groups and their source faces, for the paper's verification."""
    groups = tuple(g for g in obj.groups if g.kind == GroupKind.CONVEX)
    faces = obj.faces[np.concatenate([g.faces for g in groups])]
    # Each group's faces renumbered into the reduced list: left as they were, they would index the
    # whole object's faces (CesiumMilkTruck.glb at 1e-3: out of range; in range, the wrong body).
    ends = np.cumsum([len(g.faces) for g in groups])
    groups = tuple(replace(g, faces=np.arange(end - len(g.faces), end)) for g, end in zip(groups, ends))
    planes = np.unique(np.concatenate([g.refs for g in groups]))
    omega, h = from_triplets(obj.triplets[planes])
    used = np.unique(faces)
    fit = float(np.abs(omega @ obj.vertices[used].T - h[:, None]).min(axis=0).max(initial=0.0))
    return replace(obj, faces=faces, groups=groups, fit=fit, closed=True,
                   volume=signed_volume(obj.vertices, faces), euler=euler_characteristic(faces),
                   area=_area(obj.vertices, faces), rim=0.0)


def _choose_shells(objects: list[_Object], tolerance: float, coding: Coding | None,
                   bits: int | tuple[int, int, int] | None,
                   size: Callable[..., int]) -> tuple[list[_Object], _Choice]:
    """The objects of the shell scheme with their shells built, and the coding, smallest file first.

    Convex groups are verified as the paper's scheme verifies them (certified
    Hausdorff distance on their bodies alone), which fixes the coding; with
    none, every width of :data:`SHELL_WIDTHS` is tried and the smallest file
    kept. A shell's error holds by construction: decoded and source
    triangles correspond one to one, so the two-sided Hausdorff distance is at
    most the largest corner displacement, measured on the decoding. A
    decoding that misses a lossless volume or area (the Euler characteristic
    and closedness are the source's by construction) is made again with a
    quarter of the budget.
    """
    forced = coding is not None or bits is not None
    scale = [float(np.linalg.norm(o.world[:3, :3], 2)) for o in objects]
    diag_src = _diagonal(np.concatenate([transform_points(o.vertices, o.world) for o in objects]))
    convex_error = 0.0
    convex = False  # convex groups kept, their coding chosen
    candidates: list[tuple[Coding, Quantization | None]] = []
    if any(g.kind == GroupKind.CONVEX for o in objects for g in o.groups):
        parts = [_convex_part(o) for o in objects if any(g.kind == GroupKind.CONVEX for g in o.groups)]
        try:
            c = _choose(parts, tolerance, coding, bits)
        except GeometryError:
            if forced:
                raise
            objects = [_as_shells(o) for o in objects]
        else:
            candidates = [(c.coding, c.quantization)]
            convex_error = c.error_bound * c.diagonal
            convex = True
    if not candidates:
        table = np.concatenate([o.triplets for o in objects])
        radius = max(float(np.linalg.norm(o.vertices, axis=1).max()) for o in objects)
        every = _candidates(coding, bits, table, radius, tolerance * diag_src, H_RANGE_STEP)
        candidates = every if forced else \
            [(cod, q) for cod, q in every if cod == Coding.QUANTIZED and q.bits_nu in SHELL_WIDTHS]
    band = tolerance if tolerance > LOSSLESS_TOLERANCE else 0.0
    best: tuple[int, list[_Object], _Choice] | None = None
    why = ""
    # Planes that name no corner within the budget only cost bytes: the same shells without them
    # (every corner explicit, every triangle free) compete too, where colours do not ride on them.
    freed = [_planeless(o) for o in objects]
    variants = [(objects, candidates)]
    if not forced and all(f is not None for f in freed):
        variants.append((freed, candidates[:1]))
        # The same, walked a large plane at a time, where that makes another walk.
        walked = [_walking_planes(f, o.face_plane) for f, o in zip(freed, objects)]
        if any(w is not None for w in walked):
            variants.append(([f if w is None else w for f, w in zip(freed, walked)], candidates[:1]))
            # And walked with each other large plane left until the walk has run out, so that the fillets
            # and holes around a plane are walked before the next plane (groups.shells.spanning_walk): at
            # 3e-5, box.STL 7,852 B -> 6,064, ADIS16480.STL 5,168 -> 4,952, pins.glb 2,418 -> 2,274;
            # angle_block.STL, featuretype.STL and octagonal_pocket.stl 1-2 % larger, which keep another.
            variants.append(([f if w is None else replace(w, walk_defer=True) for f, w in zip(freed, walked)],
                             candidates[:1]))
    # The planeless variant first: a width whose planes name no corner only adds a plane table and face
    # references to it, and is passed over unwritten.
    trials = [(objs, cod, q) for objs, cands in variants[::-1] for cod, q in cands]
    plans = {id(objs): [_shell_plans(o) for o in objs] for objs, _ in variants[:2]}
    # The walked variants are the freed objects with another walk: their plans are the freed ones walked
    # again (sorting the triangles and numbering the corners is most of a plan's cost).
    for objs, _ in variants[2:]:
        plans[id(objs)] = [pf if o.walk_plane is None else
                           {k: rewalked(plan, o.walk_plane[o.groups[k].faces], o.walk_defer) for k, plan in pf.items()}
                           for o, pf in zip(objs, plans[id(freed)])]
    named_before = -1
    tried: list[tuple[int, list[_Object], _Choice]] = []
    for k, (objs, cod, q) in enumerate(trials):
        progress.report("choosing a coding", k, len(trials))
        offsets = np.cumsum([0] + [len(o.triplets) for o in objs])
        rt = quantize.roundtrip(np.concatenate([o.triplets for o in objs]), cod, q)
        budget = tolerance * diag_src / (1.0 + 2.0 * tolerance)
        # A smaller budget names fewer corners: none named at the first budget, none after tightening.
        if len(variants) > 1 and objs is objects and not sum(
                _named_corners(o, pl, rt[a:b], budget / sc - o.mended)
                for o, pl, a, b, sc in zip(objs, plans[id(objs)], offsets[:-1], offsets[1:], scale)):
            continue
        for _ in range(_SHELL_TIGHTENINGS):
            if any(budget / sc <= o.mended for o, sc in zip(objs, scale)):
                why = "the corners dropped took the whole budget"
                continue
            # Dropped corners moved an object's source by up to its ``mended``: its corners get the rest.
            built, moved = zip(*(_shells_for(o, pl, rt[a:b], budget / sc - o.mended)
                                 for o, pl, a, b, sc in zip(objs, plans[id(objs)], offsets[:-1], offsets[1:], scale)))
            error = plane_error(cod, q, tolerance, diag_src)
            meshes = [_concatenate(_decode_object(rt[a:b], o, error))
                      for o, a, b in zip(built, offsets[:-1], offsets[1:])]
            # Shells alone keep the source's indexed topology by construction: corners may still land on one
            # point, and volume or area move as far as the corners did, at every tolerance (a scene of tiny
            # open meshes: a move within 1e-6 of the scene's diagonal changes a mesh's area by far more
            # than 1e-6 of it).
            # Beside convex groups (a closed bolt in an open part), the shells' triangles still move only
            # as far as their corners: their share of the change is allowed on top of the groups' own
            # (kuka_kr10r1100sixx_link_2.stl at Draco-14's error: its planeless coding, 20 kB, was refused
            # for an area off by what its corners' moves allow, and 33 kB of planes written instead).
            problems = [structure_problem(m, o, band * diag_src / sc, topology=not shells_only,
                                          moved=mv, joins=True,
                                          moved_extent=None if shells_only else _shell_extent(pl))
                        for m, o, sc, mv, pl in zip(meshes, built, scale, moved, plans[id(objs)])
                        for shells_only in [all(g.kind in SHELL_KINDS for g in o.groups)]]
            problems = [p for p in problems if p is not None]
            if not problems:
                break
            why = problems[0]
            budget /= 4.0
        else:
            continue
        world = np.concatenate([transform_points(m.vertices, o.world) for m, o in zip(meshes, built)])
        diagonal = _diagonal(world)
        err = max([convex_error] + [(d + o.mended) * sc for d, o, sc in zip(moved, built, scale)])
        bound = err / diagonal if diagonal > 0 else 0.0
        choice = _Choice(coding=cod, quantization=q, meshes=meshes,
                         bbox=np.stack([world.min(axis=0), world.max(axis=0)]), diagonal=diagonal,
                         error_bound=bound, lossy=any(o.simplified for o in objects) or bound > tolerance)
        n = size(list(built), choice, estimate=True)
        tried.append((n, list(built), choice))
        if best is None or n < best[0]:
            best = (n, list(built), choice)
        named = sum(int((~np.asarray(g.shell.explicit)).sum()) for o in built for g in o.groups if g.shell is not None)
        if len(variants) > 1 and objs is objects and n >= SHELL_WIDTH_STOP * best[0]:
            break
        if len(variants) > 1 and objs is objects and named and named == named_before:
            # Finer planes named no more corners, as written (SHELL_WIDTHS ascend): from here only the
            # table grows (not_convex.obj at 2e-5: 44 corners from 24 bits on, the best file at 24).
            break
        named_before = named
    if best is None and convex:
        # Convex groups whose corners no longer meet the bodies they touched: every body a shell.
        return _choose_shells([_as_shells(o) for o in objects], tolerance, coding, bits, size)
    if best is None:
        raise GeometryError(f"no coding keeps the source's structure with corners within the tolerance "
                            f"{tolerance:g}: {why}", code="TOLERANCE_NOT_MET")
    close = sorted((t for t in tried if t[0] <= SHELL_RANK_CLOSE * best[0]), key=lambda t: t[0])[:SHELL_RANK_TOP]
    walked = [([_walk_kinds(o) for o in objs], choice) for _, objs, choice in close]
    chosen = _smaller(walked, size)
    if convex and not forced and any(len({g.kind == GroupKind.CONVEX for g in o.groups}) == 2 for o in objects):
        # Convex groups beside shells fix the file's coding at the width their verification chose; their
        # bodies as shells may be coded with a coarser one, or none: the smaller file is kept (car.glb at
        # 4e-5: ten boxes as convex groups at 15 bits, 3,424 bytes; every body a shell, 2,853).
        try:
            shells = _choose_shells([_as_shells(o) for o in objects], tolerance, coding, bits, size)
        except GeometryError:
            return chosen
        chosen = _smaller([chosen, shells], size)
    return chosen


def _smaller(options: list[tuple[list[_Object], _Choice]],
             size: Callable[..., int]) -> tuple[list[_Object], _Choice]:
    """Of candidate files, the smaller as written: by their estimated sizes where those are more than
    :data:`SHELL_ESTIMATE_APART` apart, else by their sizes as written."""
    if len(options) == 1:
        return options[0]
    estimates = [size(*w, brotli=True, estimate=True) for w in options]
    if max(estimates) > SHELL_ESTIMATE_APART * min(estimates):
        return options[int(np.argmin(estimates))]
    return min(options, key=lambda w: size(*w, brotli=True))


def _walk_kinds(obj: _Object) -> _Object:
    """``obj`` with each shell walk in whichever allowed walk kind and mode codes it smallest (spec §9.13,
    §9.14, §9.16: kind 10 is kind 9 with its corners predicted by averaged parallelograms, smaller on
    irregular surfaces, ballA.off's coordinates 4 % at draco-14's error, larger on regular tessellations
    whose single parallelograms repeat exactly, torus.STL and capsule.obj; kind 12 predicts them by
    turning the last step, smaller where a walk goes round tubes, quadknot.obj's 33 %, larger on CAD
    parts and scans). The corners are the same in every kind, so the bound measured holds."""
    walks = tuple(layout for layout in shellwalk.WALK_KINDS if layout in SHELL_LAYOUTS)
    return replace(obj, groups=tuple(replace(g, kind=shellwalk.shell_walk_choice(g.shell, walks)[0])
                                     if g.kind in walks else g for g in obj.groups))
