"""``pln info``: pipes, JSON, exit codes, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

import planefmt
from planefmt.model import Coding, GroupKind, Header

from corpus import CORPUS, ROOT

PLN = [sys.executable, "-m", "planefmt_converters.cli"]


def make_file(path, **header):
    t = np.column_stack([np.radians([[90, 0], [90, 90], [90, 180], [90, 270], [0, 0], [180, 0]]),
                         [1, 1, 0, 0, 1, 0]])
    with planefmt.Writer(path, Header(coding=Coding.FLOAT32, **header)) as w:
        o = w.add_object("cube")
        w.add_object("child", parent=o, transform=np.eye(4))
        w.add_planes(t)
        w.add_group(o, GroupKind.CONVEX, np.arange(6))
        w.add_group(1, GroupKind.PSEUDO_CONVEX, np.arange(6), np.array([0, 0, 0, 0, 1, 1], bool))
    return path


def test_info_reads_a_pipe_and_json_parses(tmp_path):
    path = make_file(tmp_path / "cube.pln")
    with open(path, "rb") as f:
        p = subprocess.run([*PLN, "info", "-", "--json"], stdin=f, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    info = json.loads(p.stdout)
    assert info["planes"] == 6 and info["groups"]["total"] == 2
    assert info["groups"]["by_kind"] == {"convex": 1, "pseudo_convex": 1}
    assert info["groups"]["bounding_refs"] == 2
    assert [o["name"] for o in info["objects"]] == ["cube", "child"] and info["objects"][1]["parent"] == 0
    assert info["chunks"]["PLNS"]["bytes"] == 12 + 20 + 72
    assert info["file_bytes"] == path.stat().st_size
    p = subprocess.run([*PLN, "info", str(path)], capture_output=True, text=True)
    assert p.returncode == 0 and "pseudo_convex" in p.stdout and "PLNS" in p.stdout


def test_info_bad_input_is_one_line_and_exit_2(tmp_path):
    path = make_file(tmp_path / "cube.pln")
    data = bytearray(path.read_bytes())
    pos = data.index(b"GRUP")
    data[pos + 20] ^= 0x40
    bad = tmp_path / "bad.pln"
    bad.write_bytes(bytes(data))
    p = subprocess.run([*PLN, "info", str(bad)], capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr == f"pln: {bad}: chunk GRUP at byte {pos}: " + p.stderr.split(": ", 4)[-1]
    assert p.stderr.count("\n") == 1 and "CRC mismatch" in p.stderr and "Traceback" not in p.stderr
    for content in (b"", b"hello world\n", path.read_bytes()[:50]):
        bad.write_bytes(content)
        p = subprocess.run([*PLN, "info", str(bad)], capture_output=True, text=True)
        assert p.returncode == 2 and p.stderr.startswith(f"pln: {bad}: ") and p.stderr.count("\n") == 1
    p = subprocess.run([*PLN, "info", str(tmp_path / "missing.pln")], capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr
    p = subprocess.run([*PLN, "info"], capture_output=True, text=True)
    assert p.returncode == 2


def test_info_exit_1_on_warnings(tmp_path):
    path = tmp_path / "newer.pln"
    t = np.array([[0.0, 0.0, 1.0]])
    with planefmt.Writer(path, Header(version=(1, 1))) as w:
        w.add_object("a")
        w.add_planes(t)
        w.add_group(0, 77, [0])
    p = subprocess.run([*PLN, "info", str(path), "--json"], capture_output=True, text=True)
    assert p.returncode == 1
    assert {f["code"] for f in json.loads(p.stdout)["findings"]} == {"NEWER_MINOR_VERSION", "SKIPPED_GROUP_KIND"}


def test_info_planes_per_group_and_bytes_per_source_triangle(tmp_path):
    """A corpus mesh converted, then described against its source: bytes per source triangle."""
    import pytest

    src = CORPUS / "cad" / "angle_block.STL"
    out = tmp_path / "angle_block.pln"
    # Address space capped: its exact BSP decoding once sent the certified distance to 24 GB
    # (facets 1e-10 across chained perpendicular faces into one coplanar region).
    p = subprocess.run([*PLN, "convert", str(src), str(out)], capture_output=True, text=True,
                       preexec_fn=_address_space(4 << 30))
    assert p.returncode == 0, p.stderr
    p = subprocess.run([*PLN, "info", str(out), "--source", str(src), "--json"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    info = json.loads(p.stdout)
    triangles = (src.stat().st_size - 84) // 50  # binary STL: 84-byte header, 50 bytes a triangle
    assert info["source"]["triangles"] == triangles
    assert info["source"]["bytes_per_triangle"] == pytest.approx(out.stat().st_size / triangles)
    g = info["groups"]
    assert sum(g["by_kind"].values()) == g["total"] >= 1
    for kind, n in g["by_kind"].items():
        # Version 5: a shell of explicit corners and free triangles has no reference (spec §9.2).
        assert 0 <= g["largest_by_kind"][kind] <= g["plane_refs_by_kind"][kind]
    text = subprocess.run([*PLN, "info", str(out), "--source", str(src)], capture_output=True, text=True).stdout
    assert f"{triangles} triangles, {out.stat().st_size / triangles:.2f} bytes per triangle" in text
    print(f"angle_block.STL: {triangles} triangles, {out.stat().st_size} bytes, "
          f"{out.stat().st_size / triangles:.2f} bytes per triangle")


def _address_space(limit: int):
    """A ``preexec_fn`` capping the child's address space at ``limit`` bytes (Linux)."""
    import resource

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    return cap


def test_info_aligns_record_and_chunk_columns_around_an_unknown_tag():
    """A record of an unknown tag is named "tag 200", longer than a chunk's four letters: every row of
    the chunk and record tables puts its counts in the same columns (conformance's segments_v6_0 holds
    one, beside an unknown ancillary chunk)."""
    path = ROOT / "conformance" / "valid" / "segments_v6_0.pln"
    p = subprocess.run([*PLN, "info", str(path)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    rows = lines[lines.index("chunks:") + 1:]
    rows = [r for r in rows if r.startswith("  ")]
    assert any(r.lstrip().startswith("tag 200") for r in rows) and any("bOGU" in r for r in rows)
    assert len({r.index(" x ") for r in rows}) == 1, "\n".join(rows)
