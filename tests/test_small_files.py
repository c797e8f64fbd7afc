"""Small files and scenes (issue 52): what a version 6 writer leaves out or stores shorter where it is not
information: h ranges of few r32 bytes (spec §5)."""

from __future__ import annotations

import io

import numpy as np
import pytest

from planefmt import codec
from planefmt.container import headers, records
from planefmt.container.chunks import chunks_of
from planefmt.model import Mesh, Node, Scene, Units
from planefmt_converters import registry

from corpus import CORPUS


def _r32_bytes(values: tuple[float, float]) -> int:
    return headers.r32_size(values)


@pytest.mark.parametrize("h_min, h_max, levels, room", [
    (1 - 1e-7, 1 + 1e-7, 1, 3e-7), (0.8234, 3.14159, 255, 1e-4), (-2.3, 5.7, 1023, 1e-5), (-2.3, -0.001, 7, 1e-3),
    (0.0003, 2.0, 1, 1e-3), (5.0, 5.0, 1, 0.0), (0.0, 0.0, 1, 0.0), (1e-30, 1e-30, 1, 0.0), (-1e30, 3e38, 3, 1e35)])
def test_a_short_h_range_holds_the_planes_within_the_room_in_no_more_bytes(h_min, h_max, levels, room) -> None:
    lo, hi = headers.short_range(h_min, h_max, levels, room)
    hull = headers.f32_range(h_min, h_max)
    assert np.float32(lo) == lo and np.float32(hi) == hi and lo <= hi
    assert lo <= h_min + room and hi >= h_max - room
    moved = max(lo - h_min, h_max - hi, 0.0) + max(hi - lo - (hull[1] - hull[0]), 0.0) / (2 * levels)
    assert moved <= room
    assert _r32_bytes((lo, hi)) <= _r32_bytes(hull)


def test_without_room_the_h_range_is_the_float32_hull() -> None:
    assert headers.short_range(0.8234, 3.14159, 255, 0.0) == headers.f32_range(0.8234, 3.14159)
    # Planes 1 +- 1e-7, one step: the hull takes 10 bytes, [1, 1] four, moving no plane more than 1.2e-7.
    assert headers.short_range(1 - 1e-7, 1 + 1e-7, 1, 1.2e-7) == (1.0, 1.0)
    assert _r32_bytes(headers.f32_range(1 - 1e-7, 1 + 1e-7)) == 10


def _noisy_cube() -> Scene:
    """A cube of half-width 1 whose corners are off by one float32 ulp here and there, as a glTF exporter's
    float32 corners are (the bench corpus's Cube.gltf: its planes' h are 1 +- 1.2e-7)."""
    corners = np.array([(x, y, z) for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], dtype=np.float32)
    corners[[1, 6], 0] = np.nextafter(corners[[1, 6], 0], np.float32(2))
    corners[[3], 2] = np.nextafter(corners[[3], 2], np.float32(-2))
    faces = np.array([(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4), (1, 3, 7), (1, 7, 5),
                      (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)])
    return Scene((Node("Cube", mesh=Mesh(corners.astype(np.float64), faces)),), units=Units.METRE)


def _header(data: bytes):
    return records.decode_header(next(iter(chunks_of(data))).payload)[0]


def test_a_cube_of_float32_noise_stores_its_h_range_in_four_bytes() -> None:
    buf = io.BytesIO()
    header = codec.encode_scene(_noisy_cube(), buf, tolerance=6.3e-7)
    stored = _header(buf.getvalue())
    q = stored.quantization
    assert _r32_bytes((q.h_min, q.h_max)) == 4
    # Measured: 76 bytes (82 with the float32 hull [0.99999994, 1.0000001]).
    assert len(buf.getvalue()) <= 76
    assert header.error_bound <= header.tolerance
    mesh = codec.decode_scene(io.BytesIO(buf.getvalue())).nodes[0].mesh
    assert np.abs(np.abs(mesh.vertices) - 1).max() <= 6.3e-7 * np.sqrt(12)


@pytest.mark.parametrize("name", ["convex/cube_subd.obj", "convex/tet.ply", "gltf_scene/simple_pole.glb",
                                  "gltf_scene/pins.glb", "usd/bolt.usda"])
def test_corpus_files_keep_their_bound_with_short_h_ranges(name: str) -> None:
    scene, _ = registry.read(str(CORPUS / name))
    buf = io.BytesIO()
    header = codec.encode_scene(scene, buf, tolerance=3e-5)
    assert header.error_bound <= header.tolerance or header.lossy
    q = _header(buf.getvalue()).quantization
    if q is not None:
        assert q.h_min <= q.h_max and _r32_bytes((q.h_min, q.h_max)) <= 10
    decoded = codec.decode_scene(io.BytesIO(buf.getvalue()))
    assert [n.name for n in decoded.nodes] == [n.name for n in scene.nodes]
