"""The decode budget of spec §12.4 and the other bounds of issue 49 (items 1, 5, 6, 7, 10), on small
files tests/spec_files.py builds: each ends in ``LimitError`` (or the reader's own code) before its
memory is spent, and decodes once the caller raises the limit."""

from __future__ import annotations

import io
import math
import struct
import tracemalloc

import brotli
import numpy as np
import pytest

import planefmt
from planefmt import Limits, codec
from planefmt.container import records
from planefmt.model import Coding, GroupKind, Header, Quantization
from planefmt_converters.cli import main
from spec_files import stored_file, walk_file, zero_planes_block

CUBE = np.array([[np.pi, 0, 0], [0, 0, 1], [np.pi / 2, 1.5 * np.pi, 0], [np.pi / 2, np.pi / 2, 1],
                 [np.pi / 2, np.pi, 0], [np.pi / 2, 0, 1]])


def code_of(data: bytes, **kw) -> str:
    try:
        codec.decode_mesh(io.BytesIO(data), **kw)
    except planefmt.PlnError as exc:
        return exc.code
    return "ok"


def cube_copies(copies: int) -> bytes:
    """A convex cube (group 0, 12 triangles over 8 corners) and ``copies`` copies of it, in as many objects."""
    buf = io.BytesIO()
    header = Header(version=(5, 0), coding=Coding.FLOAT64)
    with planefmt.Writer(buf, header) as w:
        w.add_planes(CUBE)
        for k in range(copies + 1):
            w.add_group(w.add_object(f"o{k}"), GroupKind.CONVEX, np.arange(6))
    return buf.getvalue()


def test_defaults_are_2_to_the_22() -> None:
    assert Limits().max_triangles == Limits().max_vertices == Limits().max_planes == 1 << 22


def test_a_walk_declaring_5m_triangles_is_refused_as_its_counts_are_read() -> None:
    data = walk_file(5_000_000)
    assert len(data) < 30_000
    assert code_of(data) == "LIMIT_EXCEEDED"
    with pytest.raises(planefmt.LimitError, match="part group 0: its 5,000,002 vertices .* pln --max-vertices"):
        with planefmt.open(io.BytesIO(data), retain_planes=False) as r:  # the container alone
            r.read_all()
    findings = codec.validate(io.BytesIO(data))
    assert [f.code for f in findings] == ["LIMIT_EXCEEDED"]


def test_a_raised_limit_decodes_the_walk() -> None:
    data = walk_file(1000)
    assert code_of(data, limits=Limits(max_triangles=999)) == "LIMIT_EXCEEDED"
    assert code_of(data, limits=Limits(max_vertices=1001)) == "LIMIT_EXCEEDED"
    mesh = codec.decode_mesh(io.BytesIO(data), limits=Limits(max_triangles=1000, max_vertices=1002))
    assert mesh.faces.shape == (1000, 3)


def test_copies_of_a_walk_count_their_source_again() -> None:
    data = walk_file(100, copies=20)  # 2,100 triangles over 2,142 corners in all
    assert code_of(data, limits=Limits(max_triangles=2099)) == "LIMIT_EXCEEDED"
    assert len(codec.decode_mesh(io.BytesIO(data), limits=Limits(max_triangles=2100)).faces) == 2100


def test_a_copies_bomb_stops_at_the_copy_past_the_budget() -> None:
    data = walk_file(3394, copies=5000)
    with pytest.raises(planefmt.LimitError, match=r"part group 1235: its 3,396 vertices"):
        codec.decode_mesh(io.BytesIO(data))


def test_copies_of_a_convex_group_are_charged_once_decoded() -> None:
    data = cube_copies(2)
    assert code_of(data, limits=Limits(max_triangles=35)) == "LIMIT_EXCEEDED"
    assert code_of(data, limits=Limits(max_vertices=23)) == "LIMIT_EXCEEDED"
    assert len(codec.decode_mesh(io.BytesIO(data), limits=Limits(max_triangles=36, max_vertices=24)).faces) == 36
    codes = [f.code for f in codec.validate(io.BytesIO(data), limits=Limits(max_triangles=35))]
    assert codes == ["LIMIT_EXCEEDED"]


def test_copies_reuse_their_decoded_source(monkeypatch) -> None:
    decoded = []
    real = codec.scenes.decode_groups

    def counting(items, *rest):
        decoded.extend(g.index for _, g, _ in items)
        return real(items, *rest)

    monkeypatch.setattr(codec.scenes, "decode_groups", counting)
    mesh = codec.decode_mesh(io.BytesIO(cube_copies(5)))
    assert decoded == [0] and len(mesh.faces) == 72


def test_zero_planes_past_the_limit_are_refused_before_they_are_inflated() -> None:
    data = stored_file([], plns_blocks=[zero_planes_block(0, 5_000_000)])
    assert len(data) < 100_000
    assert code_of(data) == "LIMIT_EXCEEDED"
    small = stored_file([], plns_blocks=[zero_planes_block(0, 1000)])
    assert code_of(small, limits=Limits(max_planes=999)) == "LIMIT_EXCEEDED"
    with planefmt.open(io.BytesIO(small), limits=Limits(max_planes=1000)) as r:
        r.read_all()
        assert r.planes.shape == (1000, 3)


@pytest.mark.parametrize("method", [1, 2])
def test_decompression_holds_the_raw_size_once(method: int) -> None:
    raw = np.random.default_rng(0).integers(0, 4, 32 << 20, dtype=np.uint8).tobytes()  # 32 MiB, 2 bits a byte
    # Brotli at quality 5 ends its input with output still held (brotli 1.2.1): a reader must drain it.
    stored = brotli.compress(raw, quality=5) if method == 2 else __import__("zlib").compress(raw, 1)
    tracemalloc.start()
    try:
        out = records.unpack(method, stored, len(raw), Limits(), 5)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert out == raw
    # spec §6: raw size + 16 MiB (a Brotli decoder's window, 4 MiB here); deflate's window is 32 KiB
    assert peak - len(raw) < (17 << 20 if method == 2 else 1 << 20), f"{peak / len(raw):.2f} x the raw size"


def test_an_h_range_whose_width_overflows_is_bad_header_value() -> None:
    q = dict(coding=2, bits=(8, 8, 8))
    assert code_of(stored_file([], h_range=(-1.7e308, 1.7e308), **q)) == "BAD_HEADER_VALUE"
    assert code_of(stored_file([], h_range=(-8e307, 8e307), **q)) == "ok"
    assert math.isinf(1.7e308 - -1.7e308)


@pytest.mark.parametrize("command, refused", [("info", 2), ("validate", 1), ("convert", 2)])
def test_cli_max_options(tmp_path, capsys, command: str, refused: int) -> None:
    path = tmp_path / "walk.pln"
    path.write_bytes(walk_file(100, copies=20))
    args = [command, str(path), *([str(tmp_path / "out.obj"), "--force"] if command == "convert" else [])]
    assert main([*args, "--max-triangles", "2099"]) == refused
    out = capsys.readouterr()
    assert "LIMIT_EXCEEDED" in out.out or "limit of 2,099 triangles" in out.err
    assert main([*args, "--max-triangles", "2100"]) == 0


def test_encoding_past_the_default_says_how_to_read_the_file(monkeypatch) -> None:
    from planefmt.codec import encoding

    monkeypatch.setattr(encoding, "Limits", lambda: Limits(max_triangles=11, max_vertices=7))
    import trimesh

    box = trimesh.creation.box()
    scene = planefmt.Scene(nodes=(planefmt.Node(name="box", mesh=planefmt.Mesh(box.vertices, box.faces)),))
    with pytest.warns(planefmt.PlnWarning, match="pln --max-triangles"):
        codec.encode_scene(scene, io.BytesIO())
