"""Version 4.0 (spec §6, §8, §10.1): Brotli payloads where they are smaller than deflate, within the ratio
every reader accepts; transforms entry by entry, bit-exact; a group's one colour stored once."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

import planefmt
from planefmt import codec
from planefmt.container import records, schema
from planefmt.model import TREE_KINDS, Coding, GroupKind, Header, Mesh, Node, ObjectRecord, Scene, Units

from corpus import CORPUS


def _payload_methods(data: bytes) -> list[int]:
    from planefmt.container.chunks import chunks_of

    methods = []
    for chunk in chunks_of(data):
        if chunk.type == schema.GRUP:
            methods.append(schema.GroupHead3.parse(chunk.payload).compression)
        elif chunk.type == schema.PLNS:
            methods.append(schema.PlaneBlock3.parse(chunk.payload).compression)
    return methods


def test_a_corpus_shell_is_stored_as_brotli_and_decodes_as_before(tmp_path) -> None:
    from planefmt_converters import registry

    scene, _ = registry.read(str(CORPUS / "nonconvex_watertight" / "torus.STL"))
    header = codec.encode_scene(scene, tmp_path / "t.pln", tolerance=3e-5, major=5)
    data = (tmp_path / "t.pln").read_bytes()
    assert header.version[0] == 5 and schema.COMPRESSION_BROTLI in _payload_methods(data)
    source = next(n.mesh for n in scene.nodes if n.mesh is not None)
    decoded = codec.decode_scene(tmp_path / "t.pln").nodes[0].mesh
    assert len(decoded.faces) == len(source.faces)
    with planefmt.open(tmp_path / "t.pln") as r:
        (group,) = list(r.part_groups())
    assert group.kind in TREE_KINDS


@pytest.mark.parametrize("data", [bytes(1_000_000), b"plane" * 200_000], ids=["zeros", "repeats"])
def test_no_payload_is_written_past_the_ratio_every_reader_accepts(data) -> None:
    method, stored = records.pack(data, True, brotli_allowed=True)
    assert len(data) <= schema.MAX_WRITTEN_RATIO * len(stored)
    assert records.unpack(method, stored, len(data), records.Limits(), 4) == data


def test_brotli_only_in_version_4() -> None:
    raw = bytes(range(256)) * 8
    method, stored = records.pack(raw, True, brotli_allowed=True)
    assert method == schema.COMPRESSION_BROTLI
    assert records.unpack(method, stored, len(raw), records.Limits(), 4) == raw
    with pytest.raises(planefmt.FormatError) as err:
        records.unpack(method, stored, len(raw), records.Limits(), 3)
    assert err.value.code == "BAD_COMPRESSION"


def _rotation(angle: float) -> np.ndarray:
    m = np.eye(4)
    m[:2, :2] = [[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]]
    return m


@pytest.mark.parametrize("transform", [
    np.eye(4),
    np.array([[1, 0, 0, 2.5], [0, 1, 0, -1], [0, 0, 1, 0.125], [0, 0, 0, 1]], dtype=float),
    _rotation(0.3) @ np.diag([2.0, 2.0, 2.0, 1.0]),
    np.array([[-0.0, 1e-300, 0, 1e300], [0, -1, 0, 0.1], [0, 0, 1, -0.0], [0, 0, 0, 1]]),
], ids=["identity", "translation", "rotation", "signed zeros and extremes"])
def test_transforms_round_trip_bit_exactly_in_fewer_bytes(transform) -> None:
    record = ObjectRecord(0, "node", None, transform)
    payload = records.encode_object(record, 4)
    back = records.decode_object(payload, 0, 4).transform
    assert back.tobytes() == transform.astype(np.float64).tobytes()
    assert len(payload) < len(records.encode_object(record, 3))


def test_one_colour_for_a_group_is_stored_once(tmp_path) -> None:
    import trimesh

    box = trimesh.creation.box()
    colours = np.tile(np.array([[12, 34, 56, 255]], dtype=np.uint8), (len(box.faces), 1))
    scene = Scene(nodes=(Node("box", mesh=Mesh(np.asarray(box.vertices), np.asarray(box.faces),
                                               face_colours=colours)),))
    codec.encode_scene(scene, tmp_path / "c.pln", tolerance=1e-6, major=5)
    data = (tmp_path / "c.pln").read_bytes()
    at = data.index(schema.COLR)
    assert int.from_bytes(data[at + 4:at + 8], "little") == 12
    decoded = codec.decode_scene(tmp_path / "c.pln").nodes[0].mesh
    assert (decoded.face_colours == [12, 34, 56, 255]).all()


def test_a_version_3_4_writer_still_writes_what_3_4_readers_read() -> None:
    header = Header(version=(3, 4), coding=Coding.FLOAT32, units=Units.METRE)
    buf = io.BytesIO()
    with planefmt.Writer(buf, header, compress=True) as w:
        w.add_object("n", None, np.eye(4))
        w.add_planes(np.array([[0.5, 0.5, 1.0]] * 4))
        w.add_group(0, GroupKind.CONVEX, np.arange(4), np.zeros(4, bool))
        w.add_colours(0, np.tile(np.array([[1, 2, 3, 4]], dtype=np.uint8), (4, 1)))
    data = buf.getvalue()
    assert schema.COMPRESSION_BROTLI not in _payload_methods(data)
    at = data.index(schema.COLR)
    assert int.from_bytes(data[at + 4:at + 8], "little") == 8 + 4 * 4


def test_a_brotli_bomb_stops_at_its_declared_raw_size() -> None:
    """77 stored bytes of 50 MB of zeros, declared as 1,000 bytes: refused after about one decoder block,
    never decompressed whole (spec §6: at most raw size + 16 MiB held)."""
    import brotli
    import tracemalloc

    stored = brotli.compress(bytes(50_000_000), quality=5)
    tracemalloc.start()
    try:
        with pytest.raises(planefmt.FormatError) as err:
            records.unpack(schema.COMPRESSION_BROTLI, stored, 1_000, records.Limits(max_compression_ratio=10 ** 9), 4)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert err.value.code == "SIZE_MISMATCH" and peak < 4_000_000


def test_major_3_writes_the_lowest_3x_version_for_readers_of_3x(tmp_path) -> None:
    """``pln convert --major 3``: the same objects, triangles and surface as the default version, in the
    file a 3.x reader reads. Version 6 may store an h range of fewer bytes (spec §5, §7.3), which moves a
    plane by less than the error it leaves: each vertex then lies within the two files' bounds of the
    other's, not at the same bits."""
    from planefmt_converters.cli import main

    src = CORPUS / "gltf_scene" / "TestScene.gltf"
    assert main(["convert", str(src), str(tmp_path / "v3.pln"), "--major", "3", "--tolerance", "1e-4"]) == 0
    assert main(["convert", str(src), str(tmp_path / "v4.pln"), "--tolerance", "1e-4"]) == 0
    v3, v4 = (tmp_path / "v3.pln").read_bytes(), (tmp_path / "v4.pln").read_bytes()
    with planefmt.open(tmp_path / "v3.pln") as r:
        header, kinds = r.header, {g.kind for g in r.part_groups()}
    expected = 4 if GroupKind.SHELL_TREE_PARALLELOGRAM in kinds else 3 if GroupKind.SHELL_TREE in kinds else 2
    assert header.version == (3, expected) and schema.COMPRESSION_BROTLI not in _payload_methods(v3)
    assert len(v4) < len(v3)
    a, b = (codec.decode_scene(tmp_path / name) for name in ("v3.pln", "v4.pln"))
    bounds = []
    for name in ("v3.pln", "v4.pln"):
        with planefmt.open(tmp_path / name) as r:
            bounds.append(r.header.error_bound)
    world = codec.decode_mesh(tmp_path / "v3.pln").vertices
    apart = sum(bounds) * float(np.linalg.norm(np.ptp(world, axis=0)))
    for x, y in zip(a.nodes, b.nodes, strict=True):
        assert x.name == y.name and (x.transform is None) == (y.transform is None)
        assert x.transform is None or np.array_equal(x.transform, y.transform)
        assert (x.mesh is None) == (y.mesh is None)
        if x.mesh is not None:
            assert np.array_equal(x.mesh.faces, y.mesh.faces)
            assert np.abs(x.mesh.vertices - y.mesh.vertices).max() <= apart


def test_an_unknown_major_is_refused_before_any_work(tmp_path) -> None:
    import trimesh

    box = trimesh.creation.box()
    scene = Scene(nodes=(Node("box", mesh=Mesh(np.asarray(box.vertices), np.asarray(box.faces))),))
    with pytest.raises(planefmt.PlnError) as err:
        codec.encode_scene(scene, tmp_path / "x.pln", major=7)
    assert err.value.code == "UNSUPPORTED_VERSION" and not (tmp_path / "x.pln").exists()
