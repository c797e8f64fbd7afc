"""Copies (kind 11, spec §9.15): a scene that places one mesh several times stores it once; every
reader path (streaming, a pipe, random access) gives each copy its source's surface in its own object."""

from __future__ import annotations

import functools
import io

import numpy as np
import pytest

import planefmt
from planefmt import codec
from planefmt.codec import encoding
from planefmt.container.chunks import chunks_of
from planefmt.model import GroupKind
from planefmt_converters import registry

from corpus import CORPUS
from streams import TrickleReader

PINS = CORPUS / "gltf_scene" / "pins.glb"


def encoded(path, tolerance: float, copies: bool = True, monkeypatch=None, major: int = 6) -> bytes:
    scene, _ = registry.read(str(path))
    if not copies:
        monkeypatch.setattr(encoding, "Writer", functools.partial(planefmt.Writer, copies=False))
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=tolerance, major=major)
    return buf.getvalue()


def meshes(data: bytes) -> list[tuple[np.ndarray, np.ndarray]]:
    scene = codec.decode_scene(io.BytesIO(data))
    return [(np.asarray(n.mesh.vertices), np.asarray(n.mesh.faces)) for n in scene.nodes if n.mesh is not None]


@pytest.mark.parametrize("major", [5, 6])
def test_a_scene_of_one_mesh_placed_six_times_stores_it_once(monkeypatch, major):
    with_copies = encoded(PINS, 3.2e-5, major=major)
    without = encoded(PINS, 3.2e-5, copies=False, monkeypatch=monkeypatch, major=major)
    if major == 5:
        assert len(with_copies) < 0.7 * len(without)
    else:
        # Version 6 compresses the repeated bodies in one segment, which finds the repeats itself (measured:
        # 1,545 bytes with copies, 1,542 without): the copies save the decode, not bytes.
        assert len(with_copies) <= 1.01 * len(without) < 0.7 * len(encoded(PINS, 3.2e-5, copies=False,
                                                                           monkeypatch=monkeypatch, major=5))
    with planefmt.open(io.BytesIO(with_copies)) as r:
        version = r.header.version
        groups = list(r.part_groups())
    # 5.1 where a walk (the source) is kind 12, 5.2 where kind 13, spec §11: the lowest minor version that
    # holds the kinds; 6.0 has them all.
    assert version == (6, 0) if major == 6 else version == (
        (5, 2) if any(g.kind == GroupKind.SHELL_WALK_LATER for g in groups) else
        (5, 1) if any(g.kind == GroupKind.SHELL_WALK_REFLECT for g in groups) else (5, 0))
    copies = [g for g in groups if g.source is not None]
    assert len(copies) == 5 and {g.source for g in copies} == {1}
    assert all(g.kind == groups[1].kind and np.array_equal(g.shell.facets, groups[1].shell.facets) for g in copies)
    assert len({g.object for g in copies}) == 5
    a, b = meshes(with_copies), meshes(without)
    assert len(a) == len(b) == 7
    for (va, fa), (vb, fb) in zip(a, b):
        assert np.array_equal(va, vb) and np.array_equal(fa, fb)


def test_copies_read_alike_streamed_through_a_pipe_and_by_random_access(monkeypatch):
    from planefmt.container import writer

    monkeypatch.setattr(writer, "INDEX_MIN_BYTES", 0)  # an index for random access, small as the file is
    data = encoded(PINS, 3.2e-5)
    with planefmt.open(io.BytesIO(data)) as r:
        streamed = list(r.part_groups())
    with planefmt.open(TrickleReader(data)) as r:
        piped = list(r.part_groups())
    with planefmt.open(io.BytesIO(data)) as r:
        random = [r.group(k) for k in reversed(range(len(streamed)))][::-1]
    for a, b, c in zip(streamed, piped, random):
        assert (a.index, a.object, a.kind, a.source) == (b.index, b.object, b.kind, b.source) \
            == (c.index, c.object, c.kind, c.source)
        assert np.array_equal(a.shell.grid, b.shell.grid) and np.array_equal(a.shell.grid, c.shell.grid)


def test_a_file_read_again_keeps_no_payloads_and_a_pipe_keeps_them(tmp_path):
    data = encoded(PINS, 3.2e-5)
    path = tmp_path / "pins.pln"
    path.write_bytes(data)
    with planefmt.open(path, retain_planes=False) as r:
        from_file = list(r.part_groups())
        # A source is read again where a copy names it: memory stays that of the largest chunk.
        assert not r._payloads and len(r._offsets) == len(from_file)
    with planefmt.open(TrickleReader(data)) as r:
        piped = list(r.part_groups())
        assert len(r._payloads) == len(piped) and not r._offsets
    assert [g.source for g in from_file] == [g.source for g in piped] and sum(g.source is not None for g in piped) == 5
    for a, b in zip(from_file, piped):
        assert a.kind == b.kind and np.array_equal(a.shell.grid, b.shell.grid)
        assert np.array_equal(a.shell.facets, b.shell.facets)


@pytest.mark.parametrize("major", [5, 6])
def test_a_source_read_again_that_is_no_longer_a_group_is_an_error(tmp_path, major):
    data = encoded(PINS, 3.2e-5, major=major)
    path = tmp_path / "pins.pln"
    path.write_bytes(data)
    with planefmt.open(path) as r:
        groups = r.part_groups()
        assert next(groups).source is None and next(groups).source is None  # group 1: the copies' source
        # As if the file had changed since: the source's offset now holds the first object's chunk (version
        # 6: its segment's chunk, PEND, another than the one being read).
        if major == 5:
            r._offsets[1] = next(off for off, t, _ in r._listed if t == b"OBJT")
        else:
            r._offsets[1] = (len(data) - 9, 0)
        r._recent.clear()  # a reader keeps small sources as decoded (Reader._remember): read this one again
        with pytest.raises(planefmt.FormatError, match="changed while read") as info:
            list(groups)
    assert info.value.offset == (r._offsets[1] if major == 5 else len(data) - 9) and info.value.file == str(path)


def test_a_writer_asked_for_no_copies_writes_every_group(tmp_path):
    header = planefmt.Header(version=(4, 2), coding=planefmt.Coding.FLOAT64)
    cube = np.array([[0.0, 0.0, 1.0], [np.pi, 0.0, 0.0], [np.pi / 2, 0.0, 1.0], [np.pi / 2, np.pi, 0.0],
                     [np.pi / 2, np.pi / 2, 1.0], [np.pi / 2, 3 * np.pi / 2, 0.0]])
    for copies, kinds in ((True, [GroupKind.CONVEX, GroupKind.COPY]), (False, [GroupKind.CONVEX, GroupKind.CONVEX])):
        path = tmp_path / f"{copies}.pln"
        with planefmt.Writer(path, header, copies=copies) as w:
            w.add_planes(cube)
            for name in ("a", "b"):
                w.add_group(w.add_object(name), GroupKind.CONVEX, np.arange(6))
        # index, object (one-byte varints), then the kind
        stored = [GroupKind(c.payload[2]) for c in chunks_of(path.read_bytes()) if c.type == b"GRUP"]
        assert stored == kinds
        with planefmt.open(path) as r:
            assert [g.kind for g in r.part_groups()] == [GroupKind.CONVEX] * 2


@pytest.mark.parametrize("major", [3, 4])
def test_a_file_for_older_readers_repeats_the_group(tmp_path, major):
    scene, _ = registry.read(str(PINS))
    header = codec.encode_scene(scene, tmp_path / "p.pln", tolerance=3.2e-5, major=major)
    assert header.version < (4, 2) or major == 4
    with planefmt.open(tmp_path / "p.pln") as r:
        sources = [g.source for g in r.part_groups()]
    assert (major == 3) == all(s is None for s in sources)
