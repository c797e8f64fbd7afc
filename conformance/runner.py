"""The conformance runner: every manifest case through an implementation's command, compared.

``python -m conformance [--impl CMD] [--level container|geometry]``; the
contract between runner and implementation is in README.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEFAULT_IMPL = f"{shlex.quote(sys.executable)} -m conformance.adapter"

#: Exact fields of a valid file's result; "planes" and "findings" have rules of their own.
EXACT = ("objects", "groups", "colours")

#: spec/pln.md §12.3: a validator that cannot decode a group's kind says so; never wrong to report.
NOT_CHECKED = "GEOMETRY_NOT_CHECKED"

#: the outcome of a case the implementation declined under --skip-kinds
SKIPPED = "skipped"


@dataclass(frozen=True)
class Case:
    path: str  # relative to the suite's folder
    expected: str  # "ok" or error codes joined by "|"
    level: str  # "container" or "geometry"
    description: str


@dataclass(frozen=True)
class Outcome:
    exit_code: int
    result: dict | None  # the implementation's JSON, None if it printed none
    stderr: str


def load_manifest(root: Path = HERE) -> list[Case]:
    lines = (root / "manifest.tsv").read_text(encoding="utf-8").splitlines()
    return [Case(*line.split("\t")) for line in lines[1:] if line]


def run(impl: str, file: Path, timeout: float) -> Outcome:
    """Run ``impl FILE`` and parse the single JSON object it prints."""
    # The suite's parent folder goes on PYTHONPATH so that the default "python -m
    # conformance.adapter" resolves from any working directory.
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(HERE.parent),
                                                                      os.environ.get("PYTHONPATH")])))
    try:
        proc = subprocess.run([*shlex.split(impl), str(file)], capture_output=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return Outcome(-1, None, f"no answer within {timeout:g} s")
    try:
        result = json.loads(proc.stdout)
    except ValueError:
        result = None
    if not isinstance(result, dict):
        result = None
    return Outcome(proc.returncode, result, proc.stderr.decode("utf-8", "replace"))


def check(case: Case, expected: dict, got: Outcome, level: str, skip_kinds: frozenset[int] = frozenset()) -> str | None:
    """None if the implementation's outcome conforms, SKIPPED if it declined a kind of skip_kinds
    (--skip-kinds), else why not, in one line."""
    if got.result is None:
        tail = got.stderr.strip().splitlines()[-1:] or [""]
        return f"no JSON object on stdout (exit {got.exit_code}) {tail[0]}".rstrip()
    if "error" not in expected:
        if got.exit_code != 0 or "error" in got.result:
            return f"rejected a valid file: {got.result.get('error')} (exit {got.exit_code})"
        try:
            return compare_valid(expected, got.result, level, skip_kinds)
        except (AttributeError, KeyError, TypeError) as exc:  # a field of the wrong JSON type
            return f"malformed result ({type(exc).__name__}: {exc})"
    codes = [expected["error"], *expected.get("also", [])]
    if got.exit_code == 0:
        if case.level == "geometry" and level == "container":
            return None  # a reader that does not decode geometry cannot see this defect
        if case.level == "geometry" and skip_kinds and NOT_CHECKED in got.result.get("findings", []):
            return SKIPPED  # it said it could not decode a group, where the defect may lie
        return f"accepted an invalid file (expected {' or '.join(codes)})"
    if got.result.get("error") not in codes:
        return f"error {got.result.get('error')}, expected {' or '.join(codes)}"
    return None


def compare_valid(want: dict, got: dict, level: str, skip_kinds: frozenset[int] = frozenset()) -> str | None:
    for key in want["header"]:
        if got.get("header", {}).get(key, "missing") != want["header"][key]:
            return f"header.{key}: {got.get('header', {}).get(key, 'missing')!r}, expected {want['header'][key]!r}"
    problem = _compare_planes(want, got.get("planes"))
    if problem:
        return problem
    for key in EXACT:
        if got.get(key) != want[key]:
            return f"{key}: {json.dumps(got.get(key))[:200]}, expected {json.dumps(want[key])[:200]}"
    # Only the cases with mETA chunks (spec §10.3) expect metadata: older results do not list it.
    if "metadata" in want and got.get("metadata") != want["metadata"]:
        return f"metadata: {json.dumps(got.get('metadata'))[:200]}, expected {json.dumps(want['metadata'])[:200]}"
    found, required = set(got.get("findings", [])), set(want["findings"])
    if not required <= found or not found <= required | set(want["findings_optional"]) | {NOT_CHECKED}:
        return f"findings {sorted(found)}, expected {sorted(required)} (optional {want['findings_optional']})"
    geometry = got.get("geometry")
    declined = {k for k, g in enumerate(want["groups"]) if g["kind"] in skip_kinds}
    if geometry is None:
        if level == "geometry" and want["geometry"] is not None:
            return SKIPPED if declined else "no geometry"
        return None
    return _compare_geometry(want["geometry"], geometry, declined)


def _compare_planes(want: dict, got) -> str | None:
    """Float codings are bit-exact (spec §7.2); dequantized values may differ in the last bits
    (an FMA or another evaluation order of the §7.3 formula), so they get 1e-12 of the range."""
    if not isinstance(got, list) or len(got) != len(want["planes"]):
        return f"planes: {len(got) if isinstance(got, list) else got!r} triplets, expected {len(want['planes'])}"
    h = want["header"]
    tol = [0.0, 0.0, 0.0]
    if h["coding"] == 2:
        tol = [1e-12, 1e-12, 1e-12 * max(1.0, *map(abs, h["h_range"]))]
    for i, (g, w) in enumerate(zip(got, want["planes"])):
        if len(g) != 3 or any(not abs(a - b) <= t for a, b, t in zip(g, w, tol)):
            return f"plane {i}: {g}, expected {w}"
    return None


def _compare_geometry(want: dict, got: dict, declined: set[int] = frozenset()) -> str | None:
    """Lengths within tolerance x D, areas x D^2, volumes x D^3, D the expected bbox diagonal.
    Groups in declined (of a --skip-kinds kind) may be null; the world box is then not compared."""
    rel = want["tolerance"]

    def close(a, b, scale: float) -> bool:
        if isinstance(b, list):
            return isinstance(a, list) and len(a) == len(b) and all(close(x, y, scale) for x, y in zip(a, b))
        return isinstance(a, (int, float)) and abs(a - b) <= rel * scale

    def diagonal(bbox) -> float:
        return math.dist(bbox[0], bbox[1])

    groups = got.get("groups")
    partial = isinstance(groups, list) and any(groups[k] is None for k in declined if k < len(groups))
    if want["world_bbox"] is not None and not partial and not close(got.get("world_bbox"), want["world_bbox"],
                                                    diagonal(want["world_bbox"])):
        return f"geometry.world_bbox: {got.get('world_bbox')}, expected {want['world_bbox']}"
    if not isinstance(groups, list) or len(groups) != len(want["groups"]):
        return f"geometry.groups: {len(groups) if isinstance(groups, list) else groups!r}, " \
               f"expected {len(want['groups'])} entries"
    for k, (g, w) in enumerate(zip(groups, want["groups"])):
        if g is None and w is not None and k in declined:
            continue
        if w is None or g is None:
            if g is not w:
                return f"geometry of group {k}: {'none' if g is None else 'given'}, expected " \
                       f"{'none (skipped kind)' if w is None else 'a summary'}"
            continue
        d = diagonal(w["bbox"])
        for key, scale in (("bbox", d), ("area", d * d), ("area_vector", d * d), ("volume", d ** 3)):
            if w[key] is not None and not close(g.get(key), w[key], scale):
                return f"geometry of group {k}: {key} {g.get(key)}, expected {w[key]} (tolerance {rel:g} relative)"
        for key in ("vertices", "triangles"):
            if w[key] is not None and g.get(key) != w[key]:
                return f"geometry of group {k}: {key} {g.get(key)}, expected {w[key]}"
    return None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m conformance", description=__doc__.splitlines()[0])
    parser.add_argument("--impl", default=DEFAULT_IMPL,
                        help="command that is given one .pln file (default: planefmt's adapter)")
    parser.add_argument("--level", choices=("container", "geometry"), default="container",
                        help="geometry: also require geometry of valid files and geometry errors")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="cases run in parallel")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds allowed per case")
    parser.add_argument("--skip-kinds", default="", metavar="K,K",
                        help="group kinds the implementation does not decode: at --level geometry it may give no "
                             "summary for their groups (and report GEOMETRY_NOT_CHECKED); those cases count as skipped")
    args = parser.parse_args(argv)
    skip_kinds = frozenset(int(k) for k in args.skip_kinds.split(",") if k.strip())

    cases = load_manifest()

    def one(case: Case) -> str | None:
        expected = json.loads((HERE / case.path).with_suffix(".json").read_text(encoding="utf-8"))
        return check(case, expected, run(args.impl, HERE / case.path, args.timeout), args.level, skip_kinds)

    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        problems = list(pool.map(one, cases))
    skipped = [c for c, p in zip(cases, problems) if p == SKIPPED]
    failed = [(c, p) for c, p in zip(cases, problems) if p is not None and p != SKIPPED]
    for c in skipped:
        print(f"SKIP {c.path}: a group of a kind in --skip-kinds")
    for c, p in failed:
        print(f"FAIL {c.path}: {p}")
    print(f"{len(cases) - len(failed) - len(skipped)} passed, " + (f"{len(skipped)} skipped, " if skipped else "")
          + f"{len(failed)} failed")
    return 1 if failed else 0
