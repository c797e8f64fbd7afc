"""The encoder's faster paths (issue 55) give what the slower ones gave: first-use numbering, the Euler
characteristic, welding by position and the rim without sorting rows; segments packed once and sized by
an estimate; and an encode that leaves nothing behind that changes the next one's bytes."""

from __future__ import annotations

import io
import warnings

import numpy as np
import pytest

from corpus import CORPUS
from planefmt import codec
from planefmt.codec.preparing import _rim, _welded
from planefmt.container import compression, schema
from planefmt.container.shellfields import first_use_order
from planefmt.geometry.topology import euler_characteristic
from planefmt.groups.shells import _row_keys, _rows
from planefmt.model import Mesh, Node, Scene
from planefmt_converters import registry


def _first_use_sorted(triangles: np.ndarray, count: int) -> np.ndarray:
    flat = np.asarray(triangles, dtype=np.int64).reshape(-1)
    seen, first = np.unique(flat, return_index=True)
    rank = np.full(count, -1, dtype=np.int64)
    rank[seen[np.argsort(first, kind="stable")]] = np.arange(len(seen))
    return rank


@pytest.mark.parametrize("seed", range(5))
def test_first_use_order_is_the_sorted_one(seed: int) -> None:
    rng = np.random.default_rng(seed)
    triangles = rng.integers(0, 40, (30, 3))
    got = first_use_order(triangles, 50)
    assert np.array_equal(got, _first_use_sorted(triangles, 50))
    assert (got[40:] == -1).all()


def test_first_use_order_of_no_triangle() -> None:
    assert first_use_order(np.zeros((0, 3), dtype=np.int64), 3).tolist() == [-1, -1, -1]


def test_euler_characteristic_of_closed_and_open_surfaces() -> None:
    tetrahedron = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    assert euler_characteristic(tetrahedron) == 2
    assert euler_characteristic(tetrahedron[:3]) == 1
    assert euler_characteristic(np.zeros((0, 3), dtype=np.int64)) == 0


def test_welded_numbers_positions_as_unique_rows_do() -> None:
    rng = np.random.default_rng(7)
    vertices = rng.integers(0, 4, (60, 3)).astype(np.float64) * 0.5
    vertices[rng.random(60) < 0.2] *= -0.0  # -0.0 and 0.0 are one position
    faces = rng.integers(0, 60, (80, 3))
    welded, merged = _welded(Mesh(vertices, faces))
    used = np.unique(faces)
    positions, index = np.unique(vertices[used], axis=0, return_inverse=True)
    lookup = np.zeros(len(vertices), dtype=np.int64)
    lookup[used] = index.reshape(-1)
    assert np.array_equal(welded, lookup[faces])
    assert merged == len(used) - len(positions) > 0


def test_rim_is_the_length_of_edges_on_one_triangle() -> None:
    square = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert _rim(square, np.array([[0, 1, 2], [0, 2, 3]])) == pytest.approx(4.0)
    assert _rim(square, np.array([[0, 1, 2]])) == pytest.approx(2.0 + np.sqrt(2.0))


def test_row_keys_are_one_to_one_within_the_margin() -> None:
    rng = np.random.default_rng(3)
    grid = rng.integers(-5, 5, (200, 3))
    keys = _row_keys(grid, 2)
    near = np.unique(np.concatenate([grid, grid + 2, grid - 2]), axis=0)
    assert len(np.unique(keys(near))) == len(np.unique(_rows(near))) == len(near)
    # A range too wide for one int64 falls back to the rows themselves.
    wide = np.array([[0, 0, 0], [1 << 40, 1 << 40, 1 << 40]])
    assert _row_keys(wide, 1) is _rows


def test_pack_once_and_estimates() -> None:
    compression.forget()
    data = bytes(np.random.default_rng(1).integers(0, 8, 40_000, dtype=np.uint8))
    written = compression.pack(data, True, brotli_allowed=True)
    assert written[0] == schema.COMPRESSION_BROTLI
    assert compression.pack(data, True, brotli_allowed=True) is written
    estimate = compression.pack(data, True, brotli_allowed=True, quality=1)
    assert estimate[0] == schema.COMPRESSION_BROTLI and estimate[1] != written[1]
    small = data[:compression.ESTIMATED_MIN_BYTES - 1]
    assert compression.pack(small, True, brotli_allowed=True, quality=1) == \
        compression.pack(small, True, brotli_allowed=True)


def _encoded(scene: Scene, tolerance: float) -> bytes:
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        codec.encode_scene(scene, buf, tolerance=tolerance)
    return buf.getvalue()


def test_an_encode_leaves_nothing_that_changes_the_next() -> None:
    box, _ = registry.read(str(CORPUS / "cad" / "box.STL"))
    torus, _ = registry.read(str(CORPUS / "nonconvex_watertight" / "torus.STL"))
    first = _encoded(box, 1e-4)
    _encoded(torus, 1e-4)
    assert _encoded(box, 1e-4) == first
    mesh = codec.decode_scene(io.BytesIO(first)).nodes[0].mesh
    assert len(mesh.faces) > 0
    scene = Scene((Node("", mesh=Mesh(mesh.vertices, mesh.faces)),))
    assert _encoded(scene, 1e-6)
