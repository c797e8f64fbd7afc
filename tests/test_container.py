"""Container round trips, streaming, damage and limits (issue 2)."""

from __future__ import annotations

import dataclasses
import io
import math
import os
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import planefmt
from planefmt import chunk_bytes
from planefmt.container import quantize, records, schema, shellfields
from planefmt.model import BSP_IN, BSP_OUT, Coding, GroupKind, Header, PartGroup, PlaneBlock, Quantization, Shell
from planefmt.groups.shells import shell_tree

from streams import TrickleReader, TrickleWriter

CUBE = np.column_stack([np.radians([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]]),
                        [1, 1, 0, 0, 1, 0]])


def write_bytes(header: Header, build, **kw) -> bytes:
    sink = io.BytesIO()
    with planefmt.Writer(sink, header, **kw) as w:
        build(w)
    return sink.getvalue()


def cube_file(**kw) -> bytes:
    def build(w):
        o = w.add_object("cube", transform=np.diag([2.0, 2.0, 2.0, 1.0]))
        w.add_planes(CUBE)
        w.add_group(o, GroupKind.CONVEX, np.arange(6))
    return write_bytes(Header(coding=Coding.FLOAT32, bbox=np.array([[0, 0, 0], [1, 1, 1.0]]),
                              tolerance=1e-6, error_bound=0.0), build, **kw)


# -- property tests: every coding, trickled through non-seekable streams ---------------------

angles = st.tuples(
    st.one_of(st.sampled_from([0.0, math.pi]), st.floats(0, math.pi)),
    st.one_of(st.sampled_from([0.0, 2 * math.pi - 1e-12, math.nextafter(2 * math.pi, 0)]),
              st.floats(0, 2 * math.pi, exclude_max=True)),
    st.floats(-1e6, 1e6),
)
plane_sets = st.lists(angles, min_size=1, max_size=40).map(lambda rows: np.array(rows, dtype=np.float64))
quantizations = st.builds(
    lambda bn, bp, bh: Quantization(bn, bp, bh, -1e6, 1e6),
    st.integers(1, 32), st.integers(1, 32), st.integers(1, 32))


def groups_for(n: int, draw, version: tuple[int, int] = (1, 0)) -> list[dict]:
    kinds = [k for k in GroupKind if (k != GroupKind.SEALED or (version >= (3, 1) and n >= 3))
             and (k != GroupKind.SHELL or version >= (3, 2)) and (k != GroupKind.SHELL_TREE or version >= (3, 3))
             and (k != GroupKind.SHELL_TREE_PARALLELOGRAM or version >= (3, 4))
             and k not in (GroupKind.SHELL_WALK, GroupKind.SHELL_WALK_MULTI, GroupKind.COPY, GroupKind.SHELL_WALK_REFLECT,
                           GroupKind.SHELL_WALK_LATER)]
    out = []
    for kind in draw(st.lists(st.sampled_from(kinds), min_size=1, max_size=4)):
        m = draw(st.integers(3 if kind == GroupKind.SEALED else 1, min(n, 12)))
        refs = np.array(draw(st.lists(st.integers(0, n - 1), min_size=m, max_size=m)))
        bounding = np.array(draw(st.lists(st.booleans(), min_size=m, max_size=m)))
        g = dict(kind=kind, refs=refs, bounding=bounding)
        if kind == GroupKind.SEALED:
            # Vertices on any three distinct local references; triangles on the face planes.
            bounding[0] = False
            faces = np.flatnonzero(~bounding)
            g["vertex_planes"] = np.array(draw(st.lists(st.permutations(range(m)).map(lambda p: p[:3]),
                                                        min_size=3, max_size=8)))
            v = len(g["vertex_planes"])
            # Every vertex on a triangle: the first ones run through them all, the rest are any.
            cover = (3 * np.arange((v + 2) // 3)[:, None] + np.arange(3)) % v
            more = draw(st.lists(st.permutations(range(v)).map(lambda p: p[:3]), max_size=4))
            corners = np.vstack([cover] + [np.array(more).reshape(-1, 3)])
            g["facets"] = np.column_stack([np.sort(draw(st.lists(st.sampled_from(list(faces)), min_size=len(corners),
                                                                 max_size=len(corners)))), corners])
        if kind == GroupKind.SHELL:
            g["shell"] = draw(shells(m, bounding))
        if kind in (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM):
            g["shell"] = as_tree(draw(shells(m, bounding)))
        if kind == GroupKind.CELLS:
            g["cells"] = (np.array([0, 3], dtype=np.uint32) % (2 * m), np.array([1], dtype=np.uint32))
        if kind == GroupKind.BSP:
            g["tree"] = np.array([0, BSP_IN, BSP_OUT], dtype=np.uint32)
        out.append(g)
    return out


@st.composite
def shells(draw, m: int, bounding: np.ndarray) -> Shell:
    """A well-formed shell over ``m`` references with roles ``bounding`` (spec §9.10): corners
    named by three distinct references (where ``m`` >= 3) or explicit, triangles on face planes or
    free, corners in order of first use."""
    v = draw(st.integers(3, 9))
    explicit = np.array(draw(st.lists(st.booleans(), min_size=v, max_size=v))) | (m < 3)
    explicit[0] = True  # at least one corner on the grid: its origin and step are then stored
    cover = (3 * np.arange((v + 2) // 3)[:, None] + np.arange(3)) % v
    more = draw(st.lists(st.permutations(range(v)).map(lambda p: p[:3]), max_size=4))
    tri = np.vstack([cover] + [np.array(more, dtype=np.int64).reshape(-1, 3)])
    rank = shellfields.first_use_order(tri, v)
    tri, explicit = rank[tri], explicit[np.argsort(rank)]
    faces = np.flatnonzero(~bounding)
    free = draw(st.integers(0, len(tri))) if len(faces) else len(tri)
    face = np.r_[np.sort(draw(st.lists(st.sampled_from(list(faces)) if len(faces) else st.nothing(),
                                       min_size=len(tri) - free, max_size=len(tri) - free))),
                 np.full(free, -1)].astype(np.int64)
    named = int((~explicit).sum())
    vertex_planes = np.array(draw(st.lists(st.permutations(range(m)).map(lambda p: p[:3]), min_size=named,
                                           max_size=named)), dtype=np.int64).reshape(-1, 3)
    grid = np.array(draw(st.lists(st.integers(-2**40, 2**40), min_size=3 * int(explicit.sum()),
                                  max_size=3 * int(explicit.sum()))), dtype=np.int64).reshape(-1, 3)
    origin = np.array(draw(st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3)))
    return Shell(explicit=explicit, vertex_planes=vertex_planes, grid=grid, origin=origin,
                 step=draw(st.floats(1e-9, 1e3)), facets=np.column_stack([face, tri]))


def as_tree(shell: Shell) -> Shell:
    """``shell`` as a shell tree (spec 3.3 §8.10) with every corner explicit: a tree's named corners
    are named by the face planes of the triangles around them, which a drawn shell's need not be."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    grid = np.zeros((len(explicit), 3), dtype=np.int64)
    grid[explicit] = shell.grid
    return shell_tree(dataclasses.replace(shell, explicit=np.ones(len(explicit), dtype=bool),
                                          vertex_planes=np.zeros((0, 3), dtype=np.int64), grid=grid))[0]


@st.composite
def files(draw):
    """Planes, coding, quantization, groups, compression and version: the predicted coding only in
    versions 2 and 3, whose groups list their references in increasing order."""
    planes = draw(plane_sets)
    coding = draw(st.sampled_from(list(Coding)))
    q = draw(quantizations) if coding.quantized else None
    versions = [(2, 0), (3, 0), (3, 1), (3, 2), (3, 3), (3, 4), (4, 0)] if coding == Coding.PREDICTED else \
        [(1, 0), (2, 0), (3, 0), (3, 1), (3, 2), (3, 3), (3, 4), (4, 0)]
    version = draw(st.sampled_from(versions))
    groups = groups_for(len(planes), draw, version)
    if version[0] >= 2:
        for g in groups:
            g["refs"] = np.sort(g["refs"])
    return planes, coding, q, groups, draw(st.booleans()), version


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(files())
def test_write_read_roundtrip_trickled(spec):
    planes, coding, q, groups, compress, version = spec
    header = Header(version=version, coding=coding, quantization=q)
    sink = TrickleWriter()
    with planefmt.Writer(sink, header, compress=compress) as w:
        obj = w.add_object("ö-object", transform=np.eye(4))
        w.add_planes(planes)
        for g in groups:
            w.add_group(obj, g["kind"], g["refs"], g["bounding"], cells=g.get("cells"), tree=g.get("tree"),
                        vertex_planes=g.get("vertex_planes"), facets=g.get("facets"), shell=g.get("shell"))
    with planefmt.open(TrickleReader(bytes(sink.data))) as r:
        records = list(r)
    assert r.header.plane_count is None  # a non-seekable sink cannot patch counts in
    got = np.concatenate([b.triplets for b in records if isinstance(b, PlaneBlock)])
    if coding == Coding.FLOAT64:
        assert got.tobytes() == planes.tobytes()
    elif coding == Coding.FLOAT32:
        expect = planes.astype(np.float32)
        expect[expect[:, 1] >= np.float32(2 * math.pi), 1] = 0
        assert np.array_equal(got.astype(np.float32), expect)
    else:
        err = np.abs(got - planes)
        err[:, 1] = np.minimum(err[:, 1], 2 * math.pi - err[:, 1])  # phi wraps
        poles = (got[:, 0] == 0) | (got[:, 0] == math.pi)
        err[poles, 1] = 0  # phi carries no information at the poles
        assert (err <= quantize.half_steps(q) * (1 + 1e-9) + 1e-9).all()
    read_groups = [g for g in records if isinstance(g, PartGroup)]
    assert len(read_groups) == len(groups)
    for want, g in zip(groups, read_groups):
        assert g.kind == want["kind"]
        assert np.array_equal(g.refs, want["refs"])
        assert np.array_equal(g.bounding, want["bounding"])
        assert np.array_equal(g.planes, got[want["refs"]])
        if "tree" in want:
            assert np.array_equal(g.tree, want["tree"])
        if "cells" in want:
            assert all(np.array_equal(a, b) for a, b in zip(g.cells, want["cells"]))
        if "facets" in want:
            assert np.array_equal(g.vertex_planes, want["vertex_planes"])
            assert np.array_equal(g.facets, want["facets"])
        if "shell" in want:
            s, w = g.shell, want["shell"]
            assert np.array_equal(s.explicit, w.explicit) and np.array_equal(s.facets, w.facets)
            assert np.array_equal(s.vertex_planes, w.vertex_planes) and np.array_equal(s.grid, w.grid)
            assert s.origin.tobytes() == w.origin.tobytes() and s.step == w.step
            assert (s.links is None) == (w.links is None) and (w.links is None or np.array_equal(s.links, w.links))


@pytest.mark.parametrize("widths", [(8, 8, 8), (16, 16, 16), (32, 32, 32), (8, 16, 32), (7, 9, 13),
                                    (24, 24, 24), (1, 1, 1), (31, 3, 17)])
def test_quantized_widths_roundtrip_within_half_a_step(widths):
    rng = np.random.default_rng(sum(widths))
    n = 1001  # not a multiple of 8: the last row of the bit stream is partial
    t = np.column_stack([rng.uniform(0, math.pi, n), rng.uniform(0, 2 * math.pi, n), rng.uniform(-3, 5, n)])
    t[:4] = [[0, 1, -3], [math.pi, 2, 5], [1, 2 * math.pi - 1e-12, 0], [2, 0, 1]]
    q = Quantization(*widths, -3.0, 5.0)
    payload = quantize.encode_payload(t, Coding.QUANTIZED, q)
    assert len(payload) == (n * sum(widths) + 7) // 8
    back = quantize.decode_payload(payload, n, Coding.QUANTIZED, q)
    assert np.array_equal(quantize.quantize(back, q), quantize.quantize(t, q))
    err = np.abs(back - t)
    err[:, 1] = np.minimum(err[:, 1], 2 * math.pi - err[:, 1])
    err[(back[:, 0] == 0) | (back[:, 0] == math.pi), 1] = 0
    assert (err <= quantize.half_steps(q) * (1 + 1e-9)).all()


def test_quantize_poles_and_phi_wrap_exact():
    q = Quantization(8, 8, 8, 0.0, 1.0)
    t = np.array([[0.0, 1.0, 0.5], [math.pi, 2.0, 0.5], [1.0, 2 * math.pi - 1e-9, 0.5]])
    codes = quantize.quantize(t, q)
    assert codes[0, 1] == 0 and codes[1, 1] == 0  # poles: phi code 0
    assert codes[1, 0] == 128 and codes[2, 1] == 0  # nu = pi is code 2^(bits-1); phi wraps to 0
    back = quantize.dequantize(codes, q)
    assert back[1, 0] == math.pi and back[2, 1] == 0.0
    # The equator and the axis azimuths are exact: axis-aligned CAD faces lose nothing.
    axes = np.array([[math.pi / 2, 0, 0.5], [math.pi / 2, math.pi / 2, 0.5], [math.pi / 2, math.pi, 0.5],
                     [math.pi / 2, 1.5 * math.pi, 0.5], [math.pi / 4, 0, 0.5]])
    assert np.array_equal(quantize.dequantize(quantize.quantize(axes, q), q)[:, :2], axes[:, :2])


def test_quantized_nu_code_out_of_range_is_an_error():
    q = Quantization(3, 2, 3, 0.0, 1.0)
    bits = [1, 0, 1] + [0, 0] + [0, 0, 0]  # nu code 5 > 2^(3-1) = 4
    payload = np.packbits(np.array(bits, np.uint8), bitorder="little").tobytes()
    with pytest.raises(planefmt.PlnError) as e:
        quantize.decode_payload(payload, 1, Coding.QUANTIZED, q)
    assert e.value.code == "BAD_TRIPLET"


def test_cube_float32_payload_is_72_bytes_and_counts_are_patched():
    data = cube_file()
    with planefmt.open(io.BytesIO(data)) as r:
        blocks = [b for b in r if isinstance(b, PlaneBlock)]
    assert r.header.plane_count == 6 and r.header.object_count == 1 and r.header.group_count == 1
    assert r.chunk_stats["PLNS"] == 12 + schema.PLANE_BLOCK_HEAD + 72
    assert np.array_equal(blocks[0].triplets, CUBE.astype(np.float32).astype(np.float64))


def test_unknown_ancillary_chunk_survives_read_write():
    def build(w):
        o = w.add_object("a")
        w.add_chunk(b"zNEW", b"\x00\x01future data")
        w.add_planes(CUBE)
        w.add_group(o, GroupKind.CONVEX, np.arange(6))
    src = write_bytes(Header(), build)
    out = io.BytesIO()
    with planefmt.open(io.BytesIO(src)) as r, planefmt.Writer(out, r.header) as w:
        for rec in r:
            w.write_record(rec)
    assert ("UNKNOWN_ANCILLARY_CHUNK" in [c for c, _ in r.findings])
    assert chunk_bytes(b"zNEW", b"\x00\x01future data") in out.getvalue()
    assert out.getvalue() == src


def test_unknown_critical_chunk_is_an_error():
    data = cube_file(index=False)
    pos = data.index(b"PEND")
    bad = data[:pos] + chunk_bytes(b"ZZZZ", b"?") + data[pos:]
    with pytest.raises(planefmt.FormatError) as e:
        with planefmt.open(io.BytesIO(bad)) as r:
            list(r)
    assert e.value.code == "UNKNOWN_CRITICAL_CHUNK" and e.value.chunk == "ZZZZ" and e.value.offset == pos


def test_random_access_through_index():
    def build(w):
        for k in range(5):
            o = w.add_object(f"o{k}")
            first = w.add_planes(CUBE + [0, 0, k])
            w.add_group(o, GroupKind.CONVEX, np.arange(first, first + 6))
    data = write_bytes(Header(), build)
    with planefmt.open(io.BytesIO(data)) as r:
        g = r.group(3)
    assert g.index == 3 and g.object == 3
    assert np.allclose(g.planes[:, 2], CUBE[:, 2] + 3)


# -- damage: truncation, flipped bytes, hostile lengths ---------------------------------------

def read_all(data: bytes) -> None:
    with planefmt.open(io.BytesIO(data)) as r:
        for _ in r:
            pass


@pytest.mark.parametrize("compress", [False, True])
def test_every_truncation_is_a_pln_error(compress):
    data = cube_file(compress=compress)
    for n in range(len(data)):
        with pytest.raises(planefmt.PlnError):
            read_all(data[:n])


def test_every_flipped_byte_is_a_pln_error():
    data = cube_file()
    for i in range(len(data)):
        for mask in (0x01, 0x80):
            bad = bytearray(data)
            bad[i] ^= mask
            with pytest.raises(planefmt.PlnError):
                read_all(bytes(bad))


def test_trickled_truncations_are_pln_errors():
    data = cube_file()
    for n in range(0, len(data), 7):
        with pytest.raises(planefmt.PlnError):
            with planefmt.open(TrickleReader(data[:n])) as r:
                list(r)


def test_declared_4gb_payload_fails_without_allocating():
    data = schema.SIGNATURE + b"PHDR" + (0xFFFFFFF0).to_bytes(4, "little") + bytes(84)
    assert len(data) == 100
    with pytest.raises(planefmt.FormatError) as e:
        read_all(data)
    assert e.value.code == "CHUNK_TOO_LONG" and e.value.offset == 8
    data = schema.SIGNATURE + b"PHDR" + (0x7FFFFFF0).to_bytes(4, "little") + bytes(84)
    with pytest.raises(planefmt.PlnError) as e:
        read_all(data)
    assert e.value.code in ("LIMIT_EXCEEDED", "TRUNCATED")
    limits = planefmt.Limits(max_chunk_length=2**31 - 1)
    with pytest.raises(planefmt.TruncatedError):  # the declared length is checked against the bytes left
        with planefmt.open(io.BytesIO(data), limits=limits) as r:
            list(r)


def test_deflate_bomb_is_refused():
    body_raw = bytes(50_000_000)
    stored = zlib.compress(body_raw, 9)
    head = schema.GroupHead.build(dict(index=0, object=0, kind=0, compression=1, reserved=b"\0\0",
                                       raw_size=len(body_raw), body=stored))
    base = cube_file(index=False)
    grup = base.index(b"GRUP") - 0
    # Replace the real group with the bomb, keeping everything else valid.
    end = grup + 8 + int.from_bytes(base[grup + 4:grup + 8], "little") + 4
    bad = base[:grup] + chunk_bytes(b"GRUP", head) + base[end:]
    limits = planefmt.Limits(max_raw_size=1 << 20)
    with pytest.raises(planefmt.LimitError):
        with planefmt.open(io.BytesIO(bad), limits=limits) as r:
            list(r)


def test_signature_damage_is_named():
    data = cube_file()
    with pytest.raises(planefmt.FormatError) as e:
        read_all(data.replace(b"\r\n", b"\n", 1))
    assert e.value.code == "TEXT_MODE_DAMAGE"
    with pytest.raises(planefmt.FormatError) as e:
        read_all(b"solid cube\nfacet normal 0 0 1\n")
    assert e.value.code == "BAD_SIGNATURE"


def test_error_message_names_file_chunk_and_offset(tmp_path):
    data = bytearray(cube_file())
    pos = data.index(b"GRUP")
    data[pos + 12] ^= 0xFF
    path = tmp_path / "bad.pln"
    path.write_bytes(bytes(data))
    with pytest.raises(planefmt.ChecksumError) as e:
        read_all_path(path)
    assert str(e.value).startswith(f"{path}: chunk GRUP at byte {pos}: CRC mismatch")


def read_all_path(path) -> None:
    with planefmt.open(path) as r:
        list(r)


# -- writer behaviour ---------------------------------------------------------------------------

def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.pln"
    with pytest.raises(RuntimeError):
        with planefmt.Writer(target, Header()) as w:
            w.add_object("x")
            raise RuntimeError("simulated crash")
    assert os.listdir(tmp_path) == []
    target.write_bytes(b"previous content")
    with pytest.raises(planefmt.PlnError):
        with planefmt.Writer(target, Header()) as w:
            w.add_object("x")
            w.add_group(0, GroupKind.CONVEX, [0])  # no planes yet: refused
    assert target.read_bytes() == b"previous content"
    assert os.listdir(tmp_path) == ["out.pln"]


def test_writer_refuses_references_to_unwritten_planes():
    with pytest.raises(planefmt.PlnError) as e:
        write_bytes(Header(), lambda w: (w.add_object("a"), w.add_planes(CUBE), w.add_group(0, 0, [6])))
    assert e.value.code == "BAD_PLANE_REFERENCE"


def test_newer_minor_version_is_read_and_unknown_kind_skipped():
    header = Header(version=(1, 3), extra=b"future header field")

    def build(w):
        o = w.add_object("a")
        w.add_planes(CUBE)
        w.add_group(o, 9, np.arange(6), extra=b"future kind data")
        w.add_group(o, GroupKind.CONVEX, np.arange(6))
    data = write_bytes(header, build)
    with planefmt.open(io.BytesIO(data)) as r:
        groups = list(r.part_groups())
    codes = [c for c, _ in r.findings]
    assert "NEWER_MINOR_VERSION" in codes and "SKIPPED_GROUP_KIND" in codes
    assert [g.kind for g in groups] == [9, 0] and groups[0].extra == b"future kind data"
    with pytest.raises(planefmt.FormatError) as e:
        read_all(write_bytes(Header(), build))
    assert e.value.code == "UNKNOWN_GROUP_KIND"


def test_major_version_mismatch():
    data = write_bytes(Header(version=(2, 0)), lambda w: None)
    data = data[:16] + b"\x07" + data[17:]  # PHDR's version_major: 7, which no reader of this version knows
    data = data[:124] + zlib.crc32(data[8:12] + data[16:124]).to_bytes(4, "little") + data[128:]
    with pytest.raises(planefmt.VersionError):
        read_all(data)


def test_chunk_after_the_index_is_chunk_order():
    data = cube_file()
    pos = data.index(b"PEND")
    bad = data[:pos] + chunk_bytes(b"tEXt", b"late") + data[pos:]
    with pytest.raises(planefmt.FormatError) as e:
        with planefmt.open(io.BytesIO(bad)) as r:
            list(r)
    assert e.value.code == "CHUNK_ORDER" and e.value.chunk == "tEXt" and e.value.offset == pos


def test_every_catalogued_code_is_in_the_spec():
    from pathlib import Path

    spec = "".join(p.read_text(encoding="utf-8")
                   for p in sorted((Path(__file__).resolve().parent.parent / "spec").glob("pln*.md")))
    assert [c for c in planefmt.CODES if f"`{c}`" not in spec] == []
