"""bench/corner_levers.py's measures and bench/corner_coder.py's prototype range coder: the walk's
residuals it re-derives are the ones the writer codes, its code-length model counts what a real
adaptive coder writes, and the coder decodes what it coded."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

from corpus import CORPUS

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bench"))
import corner_coder  # noqa: E402
import corner_levers  # noqa: E402


def _residuals(seed: int, count: int, scale: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.rint(rng.laplace(0.0, scale, size=(count, 3))).astype(np.int64)


def test_bit_lengths_are_exact_up_to_2_52():
    rng = np.random.default_rng(3)
    values = np.r_[0, 1, 2, 3, (1 << 52) - 1, 1 << 52, rng.integers(0, 1 << 52, 200)]
    assert corner_levers.bitlen_exact(values).tolist() == [int(v).bit_length() for v in values.tolist()]


@pytest.mark.parametrize("contexts", [False, True])
def test_range_coder_decodes_what_it_coded(contexts):
    res = np.r_[_residuals(1, 500, 20.0), [[0, 0, 0], [(1 << 52), -(1 << 52), 1], [-1, 2, -3]]]
    data = corner_coder.encode(res, contexts)
    assert np.array_equal(corner_coder.decode(data, len(res), contexts), res)


def test_model_counts_what_the_range_coder_writes():
    res = _residuals(2, 3000, 30.0)
    ax = np.arange(3)[None, :]
    model = corner_levers.adaptive_bits(res, np.zeros(res.shape, dtype=np.int64) + ax) / 8.0
    coded = len(corner_coder.encode(res, False))
    assert abs(coded - model) <= 0.01 * model + 8
    # Laplace residuals of scale 30 take about log2(2e * 30) = 7.3 bits each: the model is not free.
    assert 6.5 * 3 * len(res) / 8 < model < 8.0 * 3 * len(res) / 8


def test_contexts_pay_where_magnitudes_cluster():
    # Rows alternate between small and large residuals on all three axes: the previous axis predicts
    # the next one's magnitude, which the context model learns and the flat one cannot.
    small, large = _residuals(4, 1000, 1.0), _residuals(5, 1000, 3000.0)
    res = np.where((np.arange(2000) % 2 == 0)[:, None], np.repeat(small, 2, axis=0), np.repeat(large, 2, axis=0))
    assert len(corner_coder.encode(res, True)) < 0.95 * len(corner_coder.encode(res, False))


def test_walk_residuals_are_the_writers_and_slack_keeps_the_bound():
    # measure() re-derives each walk's residuals and raises where they differ from the body's field.
    row = corner_levers.measure(str(CORPUS / "open" / "suzanne.ply"), 3.2e-5, hausdorff=1)
    assert row["walks"] >= 1 and row["unmatched"] == 0 and row["E"] > 100
    bits = row["bits"]
    # The tangential components take most of a corner's bits (issue 52: the surface does not need them).
    assert bits["normal only"] < 0.5 * bits["local"]
    # The closed loop on the global axes codes the writer's grid points from float predictions: within
    # a few percent of the writer's grid-value residuals.
    assert abs(bits["global"] - bits["grid"]) < 0.05 * bits["grid"]
    (measured,) = row["hausdorff"]
    assert measured["cubic"] <= 1.0 and measured["slack"] <= 1.0
