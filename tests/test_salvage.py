"""Salvage: recover every intact part group around a damaged chunk (issue 7)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

import planefmt
from planefmt.model import GroupKind, Header, PartGroup
from planefmt.container.salvage import salvage

CUBE = np.column_stack([np.radians([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]]),
                        [1, 1, 0, 0, 1, 0]])


def ten_groups() -> bytes:
    sink = io.BytesIO()
    with planefmt.Writer(sink, Header()) as w:
        for k in range(10):
            o = w.add_object(f"part{k}")
            first = w.add_planes(CUBE + [0, 0, k])
            w.add_group(o, GroupKind.CONVEX, np.arange(first, first + 6))
    return sink.getvalue()


def grup_offsets(data: bytes) -> list[int]:
    with planefmt.open(io.BytesIO(data)) as r:
        entries = r.index()
    return [int(e["offset"]) for e in entries if e["type"] == b"GRUP"]


def test_corrupted_group_in_the_middle_is_reported_and_the_rest_recovered():
    data = bytearray(ten_groups())
    pos = grup_offsets(bytes(data))[4]
    data[pos + 30] ^= 0xFF
    with pytest.raises(planefmt.ChecksumError):
        with planefmt.open(io.BytesIO(bytes(data))) as r:
            list(r)
    got = salvage(io.BytesIO(bytes(data)))
    assert [g.index for g in got.part_groups] == [0, 1, 2, 3, 5, 6, 7, 8, 9]
    assert any(loss.code == "CRC_MISMATCH" and loss.offset == pos for loss in got.losses)
    assert any("part group 4 lost" in loss.message for loss in got.losses)
    assert all(np.isfinite(g.planes).all() for g in got.part_groups)


def test_corrupted_length_resynchronizes_on_the_next_chunk():
    data = bytearray(ten_groups())
    pos = grup_offsets(bytes(data))[2]
    data[pos + 4:pos + 8] = (0x7FFF0000).to_bytes(4, "little")  # length now points far past the end
    got = salvage(io.BytesIO(bytes(data)))
    assert [g.index for g in got.part_groups] == [0, 1, 3, 4, 5, 6, 7, 8, 9]
    assert got.losses


def test_lost_plane_block_loses_only_the_groups_that_use_it():
    data = bytearray(ten_groups())
    with planefmt.open(io.BytesIO(bytes(data))) as r:
        plns = [int(e["offset"]) for e in r.index() if e["type"] == b"PLNS"]
    data[plns[6] + 25] ^= 0x01
    got = salvage(io.BytesIO(bytes(data)))
    assert [g.index for g in got.part_groups] == [0, 1, 2, 3, 4, 5, 7, 8, 9]
    assert any(loss.code == "BAD_PLANE_REFERENCE" and "GRUP" in loss.message for loss in got.losses)


def test_truncated_file_keeps_everything_before_the_cut():
    data = ten_groups()
    cut = grup_offsets(data)[7] + 10
    got = salvage(io.BytesIO(data[:cut]))
    assert [g.index for g in got.part_groups] == list(range(7))
    assert any(loss.code == "TRUNCATED" for loss in got.losses)
    assert isinstance(got.part_groups[0], PartGroup)


def damaged_file(folder: Path) -> Path:
    """ten_groups() with a flipped byte inside group 4's chunk, written to ``folder``."""
    data = bytearray(ten_groups())
    data[grup_offsets(bytes(data))[4] + 30] ^= 0xFF
    path = folder / "damaged.pln"
    path.write_bytes(bytes(data))
    return path


def test_cli_info_salvage_lists_losses_and_exits_1(tmp_path):
    import json
    import subprocess
    import sys

    path = damaged_file(tmp_path)
    cmd = [sys.executable, "-m", "planefmt_converters.cli", "info"]
    plain = subprocess.run([*cmd, str(path)], capture_output=True, text=True)
    assert plain.returncode == 2 and "CRC mismatch" in plain.stderr
    p = subprocess.run([*cmd, str(path), "--salvage", "--json"], capture_output=True, text=True)
    assert p.returncode == 1, p.stderr
    info = json.loads(p.stdout)
    assert info["groups"]["total"] == 9
    assert {loss["code"] for loss in info["losses"]} >= {"CRC_MISMATCH"}


def test_cli_convert_salvage_writes_the_intact_objects_and_lists_the_lost(tmp_path):
    import subprocess
    import sys

    import trimesh

    path = damaged_file(tmp_path)
    out = tmp_path / "rescued.glb"
    cmd = [sys.executable, "-m", "planefmt_converters.cli", "convert"]
    plain = subprocess.run([*cmd, str(path), str(out)], capture_output=True, text=True)
    assert plain.returncode == 2 and not out.exists()
    p = subprocess.run([*cmd, str(path), str(out), "--salvage"], capture_output=True, text=True)
    assert p.returncode == 1, p.stderr
    assert "part group 4 lost" in p.stderr and "Traceback" not in p.stderr
    scene = trimesh.load(out)
    volumes = sorted(round(g.volume, 9) for g in scene.geometry.values())
    # Group k is the cube [-k, 1 + k]^3; group 4's chunk is the damaged one.
    assert volumes == [float((1 + 2 * k) ** 3) for k in range(10) if k != 4]
    not_pln = tmp_path / "cube.obj"
    not_pln.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    p = subprocess.run([*cmd, str(not_pln), str(tmp_path / "x.pln"), "--salvage"], capture_output=True, text=True)
    assert p.returncode == 2 and "--salvage reads damaged .pln files" in p.stderr


def test_a_group_index_claiming_billions_is_one_loss():
    """A damaged GRUP index says group 4,294,967,040 follows group 3: the groups in between are
    reported as one run, not one loss each (which took 1.8 s and 590k records for a fuzzer input
    claiming 589,824, and would not end for this one)."""
    from planefmt.container.chunks import chunk_bytes

    data = ten_groups()
    pos = grup_offsets(data)[4]
    length = int.from_bytes(data[pos + 4:pos + 8], "little")
    payload = (0xFFFFFF00).to_bytes(4, "little") + data[pos + 12:pos + 8 + length]
    data = data[:pos] + chunk_bytes(b"GRUP", payload) + data[pos + 12 + length:]
    got = salvage(io.BytesIO(data))
    runs = [loss.message for loss in got.losses if loss.code == "GROUP_INDEX_MISMATCH"]
    assert runs[0] == "part groups 4..4294967039 lost"
    assert [g.index for g in got.part_groups][:5] == [0, 1, 2, 3, 0xFFFFFF00]
