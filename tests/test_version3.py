"""Version 3.0 (spec/pln.md): compact chunk heads around the planes and group bodies of 2.0."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

import planefmt
from planefmt import PlnError
from planefmt.container import records, schema
from planefmt.model import Coding, GroupKind, Header, Quantization

CUBE = np.column_stack([np.radians([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]]),
                        [1, 1, 0, 0, 1, 0]])
BBOX = np.array([[-0.1, 0.0, 1e-3], [1.0, 1.1, 3.3]])


def _cube(version=(3, 0), *, counts=True, index=False, coding=Coding.FLOAT32, q=None, sink=None, **header):
    sink = io.BytesIO() if sink is None else sink
    h = Header(version=version, coding=coding, quantization=q, bbox=BBOX, tolerance=1e-6, error_bound=3e-7,
               **(dict(plane_count=6, object_count=1, group_count=1) if counts else {}), **header)
    with planefmt.Writer(sink, h, index=index) as w:
        o = w.add_object("cube", transform=np.diag([2.0, 2.0, 2.0, 1.0]))
        w.add_planes(CUBE)
        w.add_group(o, GroupKind.CONVEX, np.arange(6))
    return sink.getvalue()


def _read(data: bytes):
    with planefmt.open(io.BytesIO(data)) as r:
        return r.header, list(r)


def test_version3_holds_the_planes_and_groups_of_version2_in_fewer_bytes():
    v2, v3 = _cube((2, 0), counts=False), _cube()
    (_, rec2), (h3, rec3) = _read(v2), _read(v3)
    assert h3.version == (3, 0) and (h3.plane_count, h3.object_count, h3.group_count) == (6, 1, 1)
    assert len(rec2) == len(rec3)
    for a, b in zip(rec2, rec3, strict=True):
        assert type(a) is type(b)
        if isinstance(a, planefmt.PlaneBlock):
            assert a.triplets.tobytes() == b.triplets.tobytes()
        if isinstance(a, planefmt.PartGroup):
            assert np.array_equal(a.refs, b.refs) and a.kind == b.kind
        if isinstance(a, planefmt.ObjectRecord):
            assert a.name == b.name and np.array_equal(a.transform, b.transform)
    print(f"cube: version 2.0 {len(v2)} B, version 3.0 {len(v3)} B")
    # PHDR 108 -> 9 + 24 + 8 + 3, PLNS head 20 -> 4, OBJT head 12 -> 4, GRUP head 16 -> 5, PEND 8 -> 0
    assert len(v2) - len(v3) == (108 - 44) + (20 - 4) + (12 - 4) + (16 - 5) + 8


def test_header_values_are_rounded_outward_and_up_to_float32():
    h, _ = _read(_cube())
    assert (h.bbox[0] <= BBOX[0]).all() and (h.bbox[1] >= BBOX[1]).all()
    assert np.array_equal(h.bbox, h.bbox.astype(np.float32).astype(np.float64))
    assert (np.abs(h.bbox - BBOX) <= 1.2e-7 * np.maximum(np.abs(BBOX), 1e-3)).all()
    assert h.tolerance >= 1e-6 and h.error_bound >= 3e-7 and h.error_bound <= h.tolerance
    assert float(np.float32(h.tolerance)) == h.tolerance
    sink = io.BytesIO()
    with planefmt.Writer(sink, Header(version=(3, 0), coding=Coding.FLOAT64)) as w:
        w.add_object("x")
    nan, _ = _read(sink.getvalue())
    assert math.isnan(nan.tolerance) and math.isnan(nan.error_bound) and nan.plane_count is None


def test_a_bbox_beyond_float32_cannot_be_written():
    with pytest.raises(PlnError) as e:
        with planefmt.Writer(io.BytesIO(), Header(version=(3, 0), bbox=np.array([[0, 0, 0], [1e39, 1, 1]]))):
            pass
    assert e.value.code == "BAD_HEADER_VALUE"


def test_declared_counts_that_do_not_match_discard_the_output(tmp_path):
    target = tmp_path / "x.pln"
    h = Header(version=(3, 0), coding=Coding.FLOAT64, plane_count=7, object_count=1, group_count=1)
    with pytest.raises(PlnError) as e:
        with planefmt.Writer(target, h) as w:
            o = w.add_object("cube")
            w.add_planes(CUBE)
            w.add_group(o, GroupKind.CONVEX, np.arange(6))
    assert e.value.code == "COUNT_MISMATCH" and not target.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("coding, q", [(Coding.FLOAT32, None), (Coding.FLOAT64, None),
                                       (Coding.QUANTIZED, Quantization(2, 2, 1, 0.0, 1.0)),
                                       (Coding.PREDICTED, Quantization(16, 16, 16, 0.0, 1.0))])
def test_every_truncation_and_flipped_byte_of_a_version3_file_is_a_pln_error(coding, q):
    data = _cube(coding=coding, q=q, index=True)
    assert _read(data)[0].coding == coding
    for n in range(len(data)):
        with pytest.raises(PlnError):
            _read(data[:n])
    for i in range(len(data)):
        bad = bytearray(data)
        bad[i] ^= 0x01
        with pytest.raises(PlnError):
            _read(bytes(bad))


def test_random_access_with_an_8_byte_end_and_no_index_with_an_empty_end():
    with_index, without = _cube(index=True), _cube(index=False)
    assert without.endswith(planefmt.chunk_bytes(schema.PEND, b"")) and len(with_index) > len(without)
    with planefmt.open(io.BytesIO(with_index)) as r:
        g = r.group(0)
    assert g.index == 0 and np.allclose(g.planes, CUBE.astype(np.float32))
    with planefmt.open(io.BytesIO(without)) as r:
        with pytest.raises(PlnError) as e:
            r.group(0)
    assert e.value.code == "BAD_INDEX" and "no index" in str(e.value)


def test_a_stream_writes_no_counts_and_objects_keep_parents_and_long_names():
    sink = io.BytesIO()
    name = "n" * 300
    with planefmt.Writer(sink, Header(version=(3, 0), coding=Coding.FLOAT64)) as w:
        a = w.add_object("root")
        w.add_object(name, parent=a, transform=np.diag([1.0, 2.0, 3.0, 1.0]))
    h, recs = _read(sink.getvalue())
    assert h.plane_count is None
    objs = [r for r in recs if isinstance(r, planefmt.ObjectRecord)]
    assert [o.parent for o in objs] == [None, 0] and objs[1].name == name


@pytest.mark.parametrize("payload, code", [(b"", "BAD_PAYLOAD"), (bytes(4), "BAD_PAYLOAD"),
                                           (bytes(8), "BAD_INDEX")])
def test_version3_end_payloads(payload, code):
    if payload == b"":
        assert records.decode_end(payload, 3) == 0
        with pytest.raises(PlnError) as e:
            records.decode_end(payload, 1)
    else:
        with pytest.raises(PlnError) as e:
            records.decode_end(payload, 3)
    assert e.value.code == code


@pytest.mark.parametrize("case", ["minor_3_5", "minor_1_1", "sealed_in_1_1"])
def test_decoding_skips_the_groups_of_a_newer_minor_versions_kind_and_says_which(case: str, tmp_path) -> None:
    """Spec §11: a reader skips a group of a kind its version does not know and reads the rest;
    decode_scene, pln convert and salvage_scene do so and name the group skipped."""
    import subprocess
    import sys
    from pathlib import Path

    from planefmt import codec
    from planefmt.errors import SkippedGroupsWarning

    path = Path(__file__).resolve().parents[1] / "conformance" / "valid" / f"{case}.pln"
    with planefmt.open(path) as r:
        groups = [g for g in r if isinstance(g, planefmt.PartGroup)]
        known = records.kinds_of(*r.header.version)
    skipped = [g for g in groups if int(g.kind) not in known]
    assert [g.index for g in skipped] == [1]
    # The triangles reference.py counts for the groups kept (null for the skipped one), not the
    # decoder's own count.
    summary = json.loads(path.with_suffix(".json").read_text())["geometry"]["groups"]
    assert summary[1] is None
    expected = sum(s["triangles"] for s in summary if s is not None)
    with pytest.warns(SkippedGroupsWarning, match=rf"part group 1 \(kind {int(skipped[0].kind)}\)"):
        scene = codec.decode_scene(path)
    assert sum(len(n.mesh.faces) for n in scene.nodes if n.mesh is not None) == expected > 0

    out = tmp_path / "out.obj"
    p = subprocess.run([sys.executable, "-m", "planefmt_converters.cli", "convert", str(path), str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0 and out.exists(), p.stderr
    assert f"dropped part group 1 (kind {int(skipped[0].kind)})" in p.stderr

    _, lost = codec.salvage_scene(path)
    assert any("part group 1" in line and "skipped" in line for line in lost)
