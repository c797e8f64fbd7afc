"""Version 2.0 (spec/pln.md, Appendix A.2): varints, the predicted plane coding and varint group bodies. A
compact file holds the planes and groups of the version 1 file, in fewer bytes."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
import trimesh

from planefmt import PlnError, codec
from planefmt.container import quantize, varint
from planefmt import open as planefmt_open
from planefmt.geometry.hausdorff import hausdorff
from planefmt.model import Coding, GroupKind, Header, Quantization
from planefmt.container.writer import Writer

from corpus import CORPUS



def _leb128(x: int) -> bytes:
    out = bytearray()
    while x >= 0x80:
        out.append((x & 0x7F) | 0x80)
        x >>= 7
    out.append(x)
    return bytes(out)


def test_varints_are_unsigned_leb128_and_round_trip():
    rng = np.random.default_rng(7)
    values = np.concatenate([np.array([0, 1, 127, 128, 300, 16383, 16384, 2**32 - 1, 2**63, 2**64 - 1],
                                      dtype=np.uint64), rng.integers(0, 2**62, 2000).astype(np.uint64)])
    data = varint.encode(values)
    assert data == b"".join(_leb128(int(x)) for x in values)
    # The C encoder, where built, and numpy's write the same bytes.
    assert varint._encode(values) == data and (varint._varints is None or varint._varints(values) == data)
    assert varint.encode([300]) == bytes.fromhex("ac02")
    back, used = varint.decode(data + b"\x05", len(values), "test")
    assert used == len(data) and np.array_equal(back, values)
    # The C decoder, where built, and numpy's read the same values.
    again, took = varint._decode(np.frombuffer(data + b"\x05", dtype=np.uint8), len(values), "test")
    assert took == used and np.array_equal(again, values)
    signed = np.array([0, -1, 1, -2, 2, 2**62, -(2**63)], dtype=np.int64)
    assert varint.zigzag(signed)[:5].tolist() == [0, 1, 2, 3, 4]
    assert np.array_equal(varint.unzigzag(varint.zigzag(signed)), signed)


def test_a_count_past_the_bytes_is_an_error_without_its_memory():
    # 2^40 varints cannot fit in 3 bytes: refused before anything of that size is allocated.
    with pytest.raises(PlnError, match="ends inside") as err:
        varint.decode(b"\x01\x02\x03", 2**40, "test")
    assert err.value.code == "BAD_PAYLOAD"


@pytest.mark.parametrize("data, why", [(b"\x80", "ends inside"), (b"\x86\x00", "not minimal"),
                                       (b"\xff" * 10 + b"\x01", "longer than 10"),
                                       (b"\xff" * 9 + b"\x02", "exceeds 2")])
def test_bad_varints_are_format_errors(data, why):
    # After a good varint too: the C decoder, where built, finds the bad one and numpy says why.
    for prefix in (b"", b"\x05"):
        with pytest.raises(PlnError, match=why) as err:
            varint.decode(prefix + data, 1 + len(prefix), "test")
        assert err.value.code == "BAD_PAYLOAD"


def _triplets(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.column_stack([rng.uniform(0, math.pi, n), rng.uniform(0, 2 * math.pi, n), rng.uniform(-3, 5, n)])
    # Poles, repeated normals and repeated planes: every rule of the prediction.
    extra = [[0.0, 0.0, 1.0], [math.pi, 0.0, 2.0], [math.pi / 2, 0.0, 1.0], [math.pi / 2, 0.0, 4.0]]
    return np.vstack([t, t[:20], extra, extra])


@pytest.mark.parametrize("widths", [(11, 13, 9), (2, 2, 1), (32, 32, 32), (16, 16, 16)])
@pytest.mark.parametrize("sort", [False, True])
def test_predicted_coding_gives_back_the_quantized_planes(widths, sort):
    t = _triplets(500, 1)
    q = Quantization(*widths, -3.0, 5.0)
    if sort:
        codes = quantize.quantize(t, q)
        t = t[np.lexsort((codes[:, 2], codes[:, 1], codes[:, 0]))]
    assert np.array_equal(quantize.roundtrip(t, Coding.PREDICTED, q), quantize.roundtrip(t, Coding.QUANTIZED, q))
    assert quantize.roundtrip(t[:0], Coding.PREDICTED, q).shape == (0, 3)


def test_random_predicted_data_decodes_or_fails_with_a_format_error():
    """Hostile bytes: a PlnError or in-range planes, nothing else (no overflow, no IndexError)."""
    rng = np.random.default_rng(3)
    q = Quantization(12, 12, 12, 0.0, 1.0)
    outcomes = set()
    for _ in range(400):
        count = int(rng.integers(0, 12))
        data = rng.integers(0, 256, int(rng.integers(0, 40)), dtype=np.uint8)
        data[rng.random(len(data)) < 0.6] &= 0x7F  # mostly short varints, so some decode
        try:
            t = quantize.decode_payload(data.tobytes(), count, Coding.PREDICTED, q)
        except PlnError as err:
            outcomes.add(err.code)
            continue
        outcomes.add("ok")
        assert t.shape == (count, 3) and (t[:, 0] >= 0).all() and (t[:, 0] <= math.pi).all()
        assert (t[:, 1] >= 0).all() and (t[:, 1] < 2 * math.pi).all() and ((t[:, 2] >= 0) & (t[:, 2] <= 1)).all()
    assert {"ok", "BAD_TRIPLET", "SIZE_MISMATCH", "BAD_PAYLOAD"} <= outcomes


def test_a_version_1_writer_refuses_the_predicted_coding(tmp_path):
    header = Header(coding=Coding.PREDICTED, quantization=Quantization(8, 8, 8, 0.0, 1.0))
    with pytest.raises(PlnError) as err:
        Writer(tmp_path / "x.pln", header)
    assert err.value.code == "UNSUPPORTED_CODING" and list(tmp_path.iterdir()) == []


def _load(relative: str):
    from planefmt_converters import registry

    scene, _ = registry.read(str(CORPUS / relative))
    return scene


def _surface(data: bytes):
    from planefmt_converters.assemble import flatten

    return flatten(codec.decode_scene(io.BytesIO(data)))


@pytest.mark.parametrize("name, tolerance", [("convex/cylinder.stl", 2e-5), ("convex/test_sphere.stl", 1e-6),
                                             ("cad/20mm-xyz-cube.stl", 2e-5), ("open/test_nm.obj", 1e-6),
                                             ("gltf_scene/simple_pole.glb", 1e-6)])
def test_compact_files_decode_to_the_surface_of_version_1_files(name, tolerance):
    scene = _load(name)
    files = {}
    for compact in (False, True):
        buf = io.BytesIO()
        # Version 5: the h range is the version 1 file's (version 6 chooses it as float32 values, spec §5).
        codec.encode_scene(scene, buf, tolerance=tolerance, compress=True, compact=compact, scheme="paper", major=5)
        files[compact] = buf.getvalue()
    tables = {}
    for compact in (False, True):
        with planefmt_open(io.BytesIO(files[compact])) as r:
            header = r.header
            recs = list(r)
        groups = [rec for rec in recs if hasattr(rec, "refs")]
        planes = np.concatenate([rec.triplets for rec in recs if hasattr(rec, "triplets")])
        tables[compact] = (header.quantization, planes[np.lexsort(planes.T)])
    assert header.version == (5, 0)
    # The version 1 file is a second encoding: the same widths and the same planes, in another order.
    assert tables[True][0] == tables[False][0]
    np.testing.assert_array_equal(tables[True][1], tables[False][1])
    assert all(np.all(np.diff(g.refs.astype(np.int64)) >= 0) for g in groups)
    v1, v3 = _surface(files[False]), _surface(files[True])
    diag = float(np.linalg.norm(np.ptp(v1.vertices, axis=0)))
    # The same planes; only the order of intersection differs (rounding).
    r = hausdorff(v1.vertices, v1.faces, v3.vertices, v3.faces, target=1e-10 * diag)
    assert r.certified and r.upper <= 1e-10 * diag
    print(f"{name}: version 1 {len(files[False])} B, version 3 {len(files[True])} B")
    assert len(files[True]) < len(files[False])


def test_a_compact_bsp_group_keeps_its_tree_when_references_are_sorted():
    box = trimesh.creation.box([2, 1, 1])
    notch = trimesh.creation.box([1, 1, 1.2])
    notch.apply_translation([0.5, 0.5, 0.0])
    m = box.difference(notch, engine="manifold")
    enc = codec.encode_mesh(np.asarray(m.vertices), np.asarray(m.faces), tolerance=1e-6, scheme="paper")
    assert [g.kind for g in enc.groups] == [GroupKind.BSP]
    from planefmt.model import Mesh, Node, Scene

    scene = Scene(nodes=(Node("L", mesh=Mesh(np.asarray(m.vertices), np.asarray(m.faces))),))
    volumes = []
    for compact in (False, True):
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, compact=compact, scheme="paper")
        back = codec.decode_scene(io.BytesIO(buf.getvalue())).nodes[0].mesh
        volumes.append(trimesh.Trimesh(back.vertices, back.faces).volume)
    assert volumes[1] == pytest.approx(volumes[0], rel=1e-12)
    assert volumes[1] == pytest.approx(m.volume, rel=1e-6)


def test_the_encoder_narrows_the_widths_below_the_bisections_choice():
    """20mm-xyz-cube.stl at 2.4e-5 (draco-14's measured error on it): the admission screen and the
    bisection stop at 19 bits for the angles; 18 verify too, and the encoder keeps trying narrower
    widths until one fails, so the file has 18 and the decoded surface is still within the tolerance."""
    from planefmt_converters.assemble import flatten

    scene = _load("cad/20mm-xyz-cube.stl")
    tolerance = 2.4e-5
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=tolerance, compress=True, compact=True, scheme="paper")
    with planefmt_open(io.BytesIO(buf.getvalue())) as r:
        header = r.header
    assert header.coding.quantized and header.quantization.bits_nu <= 18
    assert header.error_bound <= tolerance
    src, out = flatten(scene), _surface(buf.getvalue())
    diag = float(np.linalg.norm(np.ptp(src.vertices, axis=0)))
    r = hausdorff(src.vertices, src.faces, out.vertices, out.faces, target=tolerance * diag)
    assert r.certified and r.upper <= tolerance * diag
