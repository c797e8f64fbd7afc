"""Several threads reading one file through separate readers see the same records (issue 7)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

import planefmt
from planefmt.model import Coding, GroupKind, Header, Quantization


def test_parallel_readers_agree(tmp_path):
    rng = np.random.default_rng(3)
    path = tmp_path / "many.pln"
    q = Quantization(13, 14, 15, -5.0, 5.0)
    with planefmt.Writer(path, Header(coding=Coding.QUANTIZED, quantization=q), compress=True) as w:
        for k in range(40):
            o = w.add_object(f"o{k}")
            t = np.column_stack([rng.uniform(0, 3.1, 3000), rng.uniform(0, 6.2, 3000), rng.uniform(-5, 5, 3000)])
            first = w.add_planes(t)
            w.add_group(o, GroupKind.CONVEX, np.arange(first, first + 3000, 7))

    def digest(k: int) -> tuple:
        with planefmt.open(path) as r:
            groups = list(r.part_groups())
            direct = r.group(k % len(groups))
        return (tuple(g.planes.tobytes() for g in groups), direct.planes.tobytes())

    with ThreadPoolExecutor(8) as pool:
        results = list(pool.map(digest, range(32)))
    full = {r[0] for r in results}
    assert len(full) == 1
    groups = results[0][0]
    assert all(direct == groups[k % len(groups)] for k, (_, direct) in enumerate(results))
