"""The faster decoding paths of issue 55 against the ones they stand in for: the version 6 header and the
record heads read by hand against construct's parse (same values, and construct's error wherever the hand
parse gives up), the C walk's fresh corners and tree predictors against numpy's, a kind 9 walk resolved in
one pass against the chains per axis, a copy's source kept against one read again: the same arrays bit for
bit, on corpus meshes and on built and mutated bytes."""

from __future__ import annotations

import functools
import io

import construct as cs
import numpy as np
import pytest

from planefmt import codec
from planefmt.container import headers, records, schema, segments, shellfields, shellwalk
from planefmt.container import reader as reader_module
from planefmt.errors import PlnError
from planefmt.model import Coding, Header, Quantization, Units
from planefmt_converters import registry

from corpus import CORPUS

PINS = CORPUS / "gltf_scene" / "pins.glb"
BOX = CORPUS / "cad" / "box.STL"


@functools.lru_cache(maxsize=None)
def encoded(path, tolerance: float = 1e-6) -> bytes:
    scene, _ = registry.read(str(path))
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=tolerance, compress=True, compact=True)
    return buf.getvalue()


def arrays(data: bytes) -> list[np.ndarray]:
    scene = codec.decode_scene(io.BytesIO(data))
    out = []
    for node in scene.nodes:
        if node.mesh is not None:
            out += [node.mesh.vertices, node.mesh.faces]
            if node.mesh.face_colours is not None:
                out.append(node.mesh.face_colours)
    return out


def same_arrays(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    return len(a) == len(b) and all(x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
                                    for x, y in zip(a, b))


def outcome(call):
    """What ``call()`` gives: its value, or the PlnError's code and message."""
    try:
        return call()
    except PlnError as exc:
        return ("error", exc.code, str(exc))


def headers6() -> list[bytes]:
    q = Quantization(20, 21, 22, -1.5, 2.25)
    bbox = np.array([[-1.0, -2.0, -3.0], [1.0, 2.0, 3.0]])
    out = []
    for coding, quantization in ((Coding.FLOAT64, None), (Coding.PREDICTED, q)):
        for box in (None, bbox):
            for counts in ((None, None, None), (7, 2, 3)):
                h = Header(version=(6, 0), coding=coding, quantization=quantization, units=Units.METRE, bbox=box,
                           tolerance=1e-6, error_bound=float("nan") if box is None else 3e-7,
                           plane_count=counts[0], object_count=counts[1], group_count=counts[2],
                           extra=b"" if box is None else b"\x05\x06", up_axis="Z")
                out.append(headers.encode_header6(h) + b"\x00\x01")  # a segment's first bytes after it
    return out


def test_a_version_6_header_reads_by_hand_as_construct_reads_it():
    for payload in headers6():
        fields, offset = headers._header6_fields(payload)
        r = schema.Header6.parse(payload)
        assert offset == r.segment_offset
        for name in ("flags", "units", "coding", "widths", "tolerance", "error_bound", "extra"):
            want, got = getattr(r.fields, name), getattr(fields, name)
            assert got == want or (got != got and want != want), name
        for name in ("h_range", "bbox"):
            want, got = getattr(r.fields, name), getattr(fields, name)
            assert (got is None) == (want is None) and (got is None or list(got) == list(want)), name
        if r.fields.counts is None:
            assert fields.counts is None
        else:
            assert [fields.counts.plane_count, fields.counts.object_count, fields.counts.group_count] == \
                [r.fields.counts.plane_count, r.fields.counts.object_count, r.fields.counts.group_count]


def test_a_damaged_version_6_header_fails_as_construct_makes_it_fail(monkeypatch):
    rng = np.random.default_rng(55)
    cases = []
    for payload in headers6():
        cases += [payload[:n] for n in range(2, len(payload))]
        for _ in range(60):
            b = bytearray(payload)
            for k in rng.integers(2, len(b), 2):
                b[k] = int(rng.integers(256))
            cases.append(bytes(b))
    slow = {}
    with monkeypatch.context() as patch:
        patch.setattr(headers, "_header6_fields", lambda payload: None)
        for i, payload in enumerate(cases):
            slow[i] = outcome(lambda: headers.decode_header6(payload))
    failed = 0
    for i, payload in enumerate(cases):
        fast = outcome(lambda: headers.decode_header6(payload))
        assert repr(fast) == repr(slow[i]), payload
        failed += isinstance(fast, tuple) and fast[0] == "error"
    assert failed > 100


#: Record heads as construct declares them and as quick_head reads them, with the parse window each reader uses.
HEADS = [(schema.RecordHead, ("tag", "length"), "payload_offset", (headers.BYTE, headers.VARINT32), 6),
         (schema.Segment, ("compression", "raw_size"), "data_offset", (headers.BYTE, headers.VARINT32), 6),
         (schema.GroupHead6, ("object", "kind"), "body_offset", (headers.VARINT32, headers.BYTE), 6),
         (schema.ColoursHead6, ("group", "count"), "rgba_offset", (headers.VARINT32, headers.VARINT32), 10),
         (schema.Object6Head, ("parent", "flags", "name_length"), None,
          (headers.VARINT32, headers.BYTE, headers.VARINT64), 21)]


@pytest.mark.parametrize("struct, names, offset, layout, window", HEADS,
                         ids=["record", "segment", "group", "colours", "object"])
def test_a_record_head_reads_by_hand_as_construct_reads_it(struct, names, offset, layout, window):
    rng = np.random.default_rng(9)
    parsed = refused = 0
    for size in range(0, 24):
        for _ in range(150):
            # short varints mostly: high bits set on a quarter of the bytes
            data = bytes(int(x) | (0x80 if rng.random() < 0.25 else 0) for x in rng.integers(0, 128, size))
            quick = headers.quick_head(data, layout, window)
            try:
                r = struct.parse(data[:window])
            except (cs.ConstructError, ValueError):
                assert quick is None, data
                refused += 1
                continue
            parsed += 1
            assert quick is not None, data
            values, end = quick
            assert values == [r[n] for n in names]
            if offset is not None:
                assert end == r[offset]
    assert parsed > 500 and refused > 200


def test_objects_with_transforms_read_by_hand_as_construct_reads_them(monkeypatch):
    # The corpus's pins.glb: objects with and without transforms (spec §8), read whole and cut short.
    data = encoded(PINS)
    payloads = []
    original = records.decode_object

    def keep(payload, *args, **kwargs):
        payloads.append((bytes(payload), args, kwargs))
        return original(payload, *args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(records, "decode_object", keep)
        codec.decode_scene(io.BytesIO(data))
    assert len(payloads) >= 2
    cases = [(p[:n], a, k) for p, a, k in payloads for n in range(len(p) + 1)]
    slow = {}
    with monkeypatch.context() as patch:
        patch.setattr(records, "quick_head", lambda *args: None)
        for i, (p, a, k) in enumerate(cases):
            slow[i] = outcome(lambda: original(p, *a, **k))
    transforms = 0
    for i, (p, a, k) in enumerate(cases):
        fast = outcome(lambda: original(p, *a, **k))
        if isinstance(fast, tuple):
            assert fast == slow[i]
        else:
            assert (fast.name, fast.parent, fast.index) == (slow[i].name, slow[i].parent, slow[i].index)
            assert (fast.transform is None) == (slow[i].transform is None)
            if fast.transform is not None:
                transforms += 1
                assert fast.transform.tobytes() == slow[i].transform.tobytes()
    assert transforms >= 1


def test_a_scene_decodes_the_same_arrays_without_the_quick_heads_and_the_kept_sources(monkeypatch):
    for data in (encoded(PINS), encoded(PINS, 3.2e-5)):
        fast = arrays(data)
        with monkeypatch.context() as patch:
            patch.setattr(reader_module, "RECENT_BYTES", 0)
            patch.setattr(records, "quick_head", lambda *args: None)
            patch.setattr(segments, "quick_head", lambda *args: None)
            patch.setattr(headers, "_header6_fields", lambda payload: None)
            slow = arrays(data)
        assert same_arrays(fast, slow)


def test_a_kept_source_is_the_source_read_again(monkeypatch):
    data = encoded(PINS, 3.2e-5)
    copies = []
    original = reader_module.Reader._copied

    def watch(self, copy):
        out = original(self, copy)
        copies.append(out)
        return out

    monkeypatch.setattr(reader_module.Reader, "_copied", watch)
    with reader_module.Reader(io.BytesIO(data)) as r:
        list(r)
    kept = copies[:]
    copies.clear()
    monkeypatch.setattr(reader_module, "RECENT_BYTES", 0)
    with reader_module.Reader(io.BytesIO(data)) as r:
        list(r)
    assert len(kept) >= 2 and len(kept) == len(copies)
    for a, b in zip(kept, copies):
        assert (a.index, a.object, a.source, a.kind) == (b.index, b.object, b.source, b.kind)
        assert np.array_equal(a.shell.facets, b.shell.facets) and np.array_equal(a.shell.grid, b.shell.grid)


@pytest.mark.skipif(shellwalk._walk_c is None, reason="the C extension was not built")
def test_the_c_walk_says_which_corner_codes_are_new_as_code_stream_does():
    data = encoded(BOX)
    bodies = []
    original = shellwalk._walk

    def keep(symbols, escapes, v):
        out = original(symbols, escapes, v)
        bodies.append(out)
        return out

    shellwalk._walk = keep
    try:
        codec.decode_scene(io.BytesIO(data))
    finally:
        shellwalk._walk = original
    assert bodies
    for tri, links, new in bodies:
        assert np.array_equal(new, shellfields.code_stream(tri, links == 0)[1])


@pytest.mark.skipif(shellfields._tree_terms is None, reason="the C extension was not built")
@pytest.mark.parametrize("parallelogram, later", [(False, False), (True, False), (False, True), (True, True)])
def test_tree_predictors_in_c_are_numpys(parallelogram, later, monkeypatch):
    data = encoded(BOX)
    bodies = []
    original = shellwalk._walk

    def keep(symbols, escapes, v):
        out = original(symbols, escapes, v)
        bodies.append(out)
        return out

    monkeypatch.setattr(shellwalk, "_walk", keep)
    codec.decode_scene(io.BytesIO(data))
    rng = np.random.default_rng(1)
    for tri, links, new in bodies:
        v = int(new.sum())
        for explicit in (np.ones(v, dtype=bool), rng.random(v) < 0.7):
            per = np.where(links == 0, 3, 1)
            fast = shellfields._tree_predictors(links, tri, explicit, per, new, parallelogram, later)
            with monkeypatch.context() as patch:
                patch.setattr(shellfields, "_tree_terms", None)
                slow = shellfields._tree_predictors(links, tri, explicit, per, new, parallelogram, later)
            assert fast.dtype == slow.dtype and np.array_equal(fast, slow)
            assert (fast[:, 1] >= 0).any() == parallelogram


def test_a_walk_whose_corners_pass_2_to_the_52_fails_alike_in_one_pass_and_per_axis(monkeypatch):
    # Residuals of 2^52 on every explicit corner of a corpus walk: the first corner stepped from another
    # passes 2^52, in one pass over the rows as in the chains of each axis.
    data = encoded(BOX)
    grabbed = []
    original = shellwalk.tree_rest

    def keep(*args, **kwargs):
        grabbed.append((args, kwargs))
        return original(*args, **kwargs)

    monkeypatch.setattr(shellwalk, "tree_rest", keep)
    codec.decode_scene(io.BytesIO(data))
    args, kwargs = grabbed[0]
    raw = args[0]
    e = int(args[6].sum())
    assert e > 100
    # The coordinates are the body's last 3e varints: replace them by zigzag(2^52) each.
    start = len(raw)
    for _ in range(3 * e):
        start -= 1
        while start > 0 and raw[start - 1] >= 0x80:
            start -= 1
    big = np.frombuffer(shellfields.varint.encode(np.full(3 * e, 1 << 53, dtype=np.uint64)), dtype=np.uint8)
    hostile = np.concatenate([raw[:start], big])
    results = []
    for reflect in (shellfields._reflect, None):
        monkeypatch.setattr(shellfields, "_reflect", reflect)
        results.append(outcome(lambda: original(hostile, *args[1:], **kwargs)))
    assert results[0] == results[1] and results[0][0] == "error" and "2^52" in results[0][2]
    grids = []
    for reflect in (shellfields._reflect, None):
        monkeypatch.setattr(shellfields, "_reflect", reflect)
        grids.append(original(*args, **kwargs).grid)
    assert grids[0].dtype == grids[1].dtype and np.array_equal(grids[0], grids[1]) and len(grids[0]) == e


def test_a_shell_groups_unused_references_are_setdiff1ds():
    rng = np.random.default_rng(4)
    for m in (1, 5, 40):
        face = rng.integers(-1, m, 200)
        unused = np.ones(m, dtype=bool)
        unused[face[(face >= 0) & (face < m)]] = False
        assert np.array_equal(np.flatnonzero(unused), np.setdiff1d(np.arange(m), face))
