"""Convex decoding cost on adversarial plane sets: does any family grow faster than m log m?

For each family of hostile convex groups and m = 1,000 to 30,000
planes (the reader's default allows 2^24 references per group), times
``planefmt.geometry.halfspace.intersect`` (best of 3, one thread) and prints the time
per plane and the growth from one size to the next, beside m log m's own
growth. A ``GeometryError`` (empty, unbounded) is a
valid outcome: what matters is that it comes as fast.

Families:

* ``sphere``: m planes tangent to the unit sphere, every one a face;
* ``clones``: the six cube planes repeated m/6 times, each copy moved by up
  to 1e-12 (clusters of near-identical planes);
* ``cone``: m - 1 planes through one apex, tangent to a cone, plus a base:
  one vertex on m - 1 planes;
* ``redundant``: the cube and m - 6 far planes that bound nothing;
* ``slab``: normals within 1e-7 rad of +-z plus four side planes: a thin,
  nearly degenerate solid;
* ``empty``: the sphere family with one plane cutting everything away.

Measured 2026-12-01 (x86_64, 2 cores, scipy 1.17.1), before and after the decoder moved
to joggled Qhull ("QJ") with vertices solved from the planes (planefmt.geometry.halfspace): the cone
took 0.05 s at m = 1,000 and 6.6 s at 10,000 (Qhull's coplanar-facet merging, O(k^2) in
the planes through one point); now 0.02 s and 0.3 s, and every family grows like m log m.
Still open: at m = 100,000 the cone's apex is left known only from nearly dependent plane
triples, the decoder falls back to Qhull's merging ("Qt"), and that takes minutes; the
default sizes stop at 30,000.

Usage: ``python bench/bench_hostile_decode.py [--max 30000]``
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time

import numpy as np

from planefmt.errors import GeometryError
from planefmt.geometry.halfspace import intersect


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1)[:, None]


def sphere(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return _unit(rng.normal(size=(m, 3))), np.ones(m)


def clones(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    base = np.vstack([np.eye(3), -np.eye(3)])
    omega = _unit(np.tile(base, (m // 6 + 1, 1))[:m] + rng.uniform(-1e-12, 1e-12, (m, 3)))
    return omega, np.ones(m) + rng.uniform(-1e-12, 1e-12, m)


def cone(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    angle = np.linspace(0, 2 * math.pi, m - 1, endpoint=False)
    side = _unit(np.column_stack([np.cos(angle), np.sin(angle), np.full(m - 1, 0.5)]))
    apex = np.array([0.0, 0.0, 1.0])
    return np.vstack([side, [[0, 0, -1.0]]]), np.concatenate([side @ apex, [0.0]])


def redundant(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    omega = np.vstack([np.eye(3), -np.eye(3), _unit(rng.normal(size=(m - 6, 3)))])
    return omega, np.concatenate([np.ones(6), rng.uniform(10, 1000, m - 6)])


def slab(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    k = m - 4
    tilt = rng.uniform(-1e-7, 1e-7, (k, 2))
    sign = np.where(np.arange(k) % 2, 1.0, -1.0)
    omega = _unit(np.column_stack([tilt, sign]))
    sides = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0.0]])
    return np.vstack([omega, sides]), np.concatenate([np.full(k, 1e-3), np.ones(4)])


def empty(m: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    omega, h = sphere(m - 1, rng)
    return np.vstack([omega, omega[:1]]), np.concatenate([h, [-5.0]])  # also omega_0 . x <= -5


FAMILIES = {"sphere": sphere, "clones": clones, "cone": cone, "redundant": redundant, "slab": slab,
            "empty": empty}


def timed(omega: np.ndarray, h: np.ndarray) -> tuple[float, str]:
    best, outcome = math.inf, ""
    for _ in range(3):
        t0 = time.perf_counter()
        try:
            p = intersect(omega, h)
            outcome = f"{len(p.vertices)} vertices"
        except GeometryError as exc:
            outcome = exc.code
        best = min(best, time.perf_counter() - t0)
    return best, outcome


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max", type=int, default=30_000)
    args = ap.parse_args()
    sizes = [m for m in (1_000, 3_000, 10_000, 30_000, 100_000) if m <= args.max]
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}; best of 3")
    print(f"{'family':<10} {'planes':>8} {'seconds':>9} {'us/plane':>9} {'growth':>7} {'m log m':>8}  outcome")
    worst = 0.0
    for name, make in FAMILIES.items():
        previous = None
        for m in sizes:
            omega, h = make(m, np.random.default_rng(m))
            t, outcome = timed(omega, h)
            growth = mlogm = ""
            if previous is not None:
                ratio = t / previous[1]
                expected = (m * math.log(m)) / (previous[0] * math.log(previous[0]))
                worst = max(worst, ratio / expected)
                growth, mlogm = f"{ratio:.1f}x", f"{expected:.1f}x"
            print(f"{name:<10} {m:>8} {t:>9.4f} {1e6 * t / m:>9.2f} {growth:>7} {mlogm:>8}  {outcome}")
            previous = (m, t)
    print(f"largest growth relative to m log m: {worst:.2f} (1 = m log m; 10 would be a quadratic step)")


if __name__ == "__main__":
    main()
