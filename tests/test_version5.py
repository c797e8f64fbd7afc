"""Version 5.0 (spec/pln.md §4.1, §5, §9.2, §9.10): varint chunk lengths, the up axis in the header,
shells without references, float32 shell grids; and what a writer refuses that a reader would."""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest

import planefmt
from planefmt import codec
from planefmt.container import records, schema
from planefmt.container.chunks import chunk_bytes, chunks_of
from planefmt.model import Coding, GroupKind, Header, Shell
from planefmt_converters import registry

from corpus import CORPUS
from streams import TrickleReader

V5 = Header(version=(5, 0), coding=Coding.FLOAT64)
CUBE = np.array([[0.0, 0.0, 1.0], [np.pi, 0.0, 0.0], [np.pi / 2, 0.0, 1.0], [np.pi / 2, np.pi, 0.0],
                 [np.pi / 2, np.pi / 2, 1.0], [np.pi / 2, 3 * np.pi / 2, 0.0]])


def _pyramid(origin=(0.0, 0.0, 0.0), step: float = 0.5) -> Shell:
    """An open square pyramid, every corner explicit, every triangle free (spec §9.10's order)."""
    return Shell(explicit=np.ones(5, bool), vertex_planes=np.zeros((0, 3), np.int64),
                 grid=np.array([[0, 0, 0], [2, 0, 0], [1, 1, 2], [2, 2, 0], [0, 2, 0]]),
                 origin=np.array(origin), step=step,
                 facets=np.array([[-1, 0, 1, 2], [-1, 1, 3, 2], [-1, 3, 4, 2], [-1, 4, 0, 2]]))


def test_lengths_are_varints_after_the_header_and_a_two_byte_one_reads() -> None:
    name = "n" * 200  # an OBJT payload over 127 bytes: a two-byte length
    buf = io.BytesIO()
    with planefmt.Writer(buf, V5, index=False) as w:
        w.add_planes(CUBE)
        w.add_group(w.add_object(name), GroupKind.CONVEX, np.arange(6))
    data = buf.getvalue()
    framing = [(c.type, c.framing) for c in chunks_of(data)]
    assert framing[0] == (b"PHDR", 12) and dict(framing[1:])[b"OBJT"] == 10 and dict(framing[1:])[b"PEND"] == 9
    assert data[-9:] == chunk_bytes(schema.PEND, b"", compact=True)
    for source in (io.BytesIO(data), TrickleReader(data)):
        with planefmt.open(source) as r:
            records = list(r)
        assert r.objects[0].name == name and [type(x).__name__ for x in records][-1] == "PartGroup"


def test_random_access_through_the_index_of_a_version_5_file() -> None:
    buf = io.BytesIO()
    with planefmt.Writer(buf, V5, index=True) as w:
        w.add_planes(CUBE)
        for k in range(3):
            w.add_group(w.add_object(f"o{k}"), GroupKind.CONVEX, np.arange(6))
    data = buf.getvalue()
    assert data[-17:-13] == b"PEND" and data[-13] == 8  # an 8-byte PEND: 17 bytes (spec §4.4)
    with planefmt.open(io.BytesIO(data)) as r:
        assert [r.group(k).object for k in range(3)] == [0, 1, 2]


def test_a_shell_of_explicit_corners_needs_no_plane() -> None:
    buf = io.BytesIO()
    with planefmt.Writer(buf, dataclasses.replace(V5, coding=Coding.FLOAT32)) as w:
        k = w.add_group(w.add_object("pyramid"), GroupKind.SHELL, np.zeros(0, np.int64), shell=_pyramid())
        w.add_colours(k, np.array([[10, 20, 30, 255]], np.uint8))  # one colour for all its triangles
    scene = codec.decode_scene(io.BytesIO(buf.getvalue()))
    mesh = scene.nodes[0].mesh
    assert len(mesh.faces) == 4 and np.allclose(mesh.vertices.max(axis=0), [1.0, 1.0, 1.0])
    assert (mesh.face_colours == [10, 20, 30, 255]).all()
    assert b"PLNS" not in buf.getvalue()


def test_the_writer_refuses_what_a_version_5_reader_would() -> None:
    with planefmt.Writer(io.BytesIO(), V5) as w:
        w.add_planes(CUBE)
        obj = w.add_object("o")
        with pytest.raises(planefmt.PlnError) as e:
            w.add_group(obj, GroupKind.CONVEX, np.zeros(0, np.int64))
        assert e.value.code == "BAD_GROUP_STRUCTURE"
        with pytest.raises(planefmt.PlnError) as e:
            # 0.1 is no float32: a version 5 grid could not hold it.
            w.add_group(obj, GroupKind.SHELL, np.zeros(0, np.int64), shell=_pyramid(origin=(0.1, 0.0, 0.0)))
        assert e.value.code == "BAD_GROUP_STRUCTURE"
        k = w.add_group(obj, GroupKind.SHELL, np.zeros(0, np.int64), shell=_pyramid())
        with pytest.raises(planefmt.PlnError) as e:
            w.add_colours(k, np.zeros((0, 4), np.uint8))
        assert e.value.code == "BAD_COLOURS"
    with pytest.raises(planefmt.PlnError) as e:
        planefmt.Writer(io.BytesIO(), V5).add_metadata(planefmt.UP_AXIS, "Z")
    assert e.value.code == "BAD_METADATA"
    with pytest.raises(planefmt.PlnError):
        planefmt.Writer(io.BytesIO(), dataclasses.replace(V5, version=(4, 2), up_axis="Z"))


@pytest.mark.parametrize("mesh", ["cad/plate_holes.STL", "usd/bolt.usda", "usd/wheelNormalGeo.usda"])
def test_version_5_is_smaller_than_4_and_decodes_to_the_same_surface(mesh: str) -> None:
    scene, _ = registry.read(str(CORPUS / mesh))
    files = {}
    for major in (4, 5):
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=3e-5, major=major)
        files[major] = buf.getvalue()
    with planefmt.open(io.BytesIO(files[5])) as r:
        # 5.0, or the minor version of its walk's kind (spec §11): 5.2 for plate_holes.STL's kind 13.
        kinds = {int(g.kind) for g in r.part_groups()}
        minor = max((records.KIND_VERSION[k][1] for k in kinds if records.KIND_VERSION.get(k, (0, 0))[0] == 5), default=0)
        assert r.header.version == (5, minor) and r.plane_count == 0
    assert len(files[5]) < len(files[4]) - 40
    a, b = (codec.decode_scene(io.BytesIO(files[m])) for m in (4, 5))
    assert a.up_axis == b.up_axis
    for na, nb in zip(a.nodes, b.nodes):
        assert (na.mesh is None) == (nb.mesh is None)
        if na.mesh is not None:
            assert np.array_equal(na.mesh.faces, nb.mesh.faces)
            # A colour rides on a group without references as it did on its one plane.
            assert (na.mesh.face_colours is None) == (nb.mesh.face_colours is None)
            assert na.mesh.face_colours is None or np.array_equal(na.mesh.face_colours, nb.mesh.face_colours)
            # The same corners up to the grid: version 5's origin and step are float32 values.
            step = np.ptp(na.mesh.vertices, axis=0).max() * 3e-5
            assert np.abs(na.mesh.vertices - nb.mesh.vertices).max() <= 2 * step


def test_salvage_resynchronizes_on_varint_framed_chunks() -> None:
    buf = io.BytesIO()
    with planefmt.Writer(buf, V5) as w:
        w.add_planes(CUBE)
        for k in range(3):
            w.add_group(w.add_object(f"o{k}"), GroupKind.CONVEX, np.arange(6))
    data = bytearray(buf.getvalue())
    second = [c for c in chunks_of(bytes(data)) if c.type == b"GRUP"][1]
    data[second.offset + second.framing - 4] ^= 0xFF  # its payload's first byte: CRC mismatch
    scene, lost = codec.salvage_scene(io.BytesIO(bytes(data)))
    assert [n.mesh is not None for n in scene.nodes] == [True, False, True]
    assert any("CRC" in x for x in lost)
