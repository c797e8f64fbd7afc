"""Small files and scenes (issue 52): what a version 6 writer leaves out or stores shorter where it is not
information: h ranges of few r32 bytes, and the bbox and counts of files of shells under 4 KiB raw (spec §5)."""

from __future__ import annotations

import io

import numpy as np
import pytest

from planefmt import codec
from planefmt.container import headers, records, schema
from planefmt.container.writer import SMALL_SEGMENT_BYTES, SMALL_SHELLS_BYTES
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


def _raw_size(data: bytes) -> int:
    """Raw bytes of the records of a file of one segment, in PHDR."""
    payload = next(iter(chunks_of(data))).payload
    size, pos = schema.Varint32.parse(bytes(payload[2:7])), 2
    pos += len(schema.Varint32.build(size)) + size  # header fields
    return schema.Varint32.parse(bytes(payload[pos + 1:pos + 6]))


def _written(name: str) -> tuple[bytes, object]:
    scene, _ = registry.read(str(CORPUS / name))
    buf = io.BytesIO()
    header = codec.encode_scene(scene, buf, tolerance=3e-5)
    return buf.getvalue(), header


def test_a_file_of_shells_under_4096_raw_bytes_leaves_out_its_bbox_and_counts() -> None:
    data, header = _written("open/test_nm.obj")
    assert [c.type for c in chunks_of(data)] == [b"PHDR", b"PEND"]
    assert SMALL_SEGMENT_BYTES <= _raw_size(data) < SMALL_SHELLS_BYTES
    stored = _header(data)
    assert stored.bbox is None and stored.plane_count is None and stored.object_count is None
    assert header.error_bound <= header.tolerance or header.lossy
    mesh = codec.decode_mesh(io.BytesIO(data))
    assert len(mesh.faces) > 0


def test_a_file_of_polytopes_over_256_raw_bytes_keeps_its_bbox_which_caps_their_merge_distance() -> None:
    # spec §9.4: L, the cap of the merge distance, is half the tolerance times the stored bbox's diagonal.
    data, _ = _written("convex/cylinder.stl")
    assert _raw_size(data) >= SMALL_SEGMENT_BYTES
    stored = _header(data)
    assert stored.bbox is not None and stored.plane_count is not None
