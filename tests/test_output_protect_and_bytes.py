"""Issue 50 items 12 and 13: the bytes in counted over every file an input is made of (a .gltf's buffers
and images, an OBJ's materials and textures), and a write-protected output refused without --force."""

from __future__ import annotations

import json
import shutil
import struct
import zlib
from pathlib import Path

import pytest

from planefmt_converters.cli import main

from corpus import CORPUS



def _png(side: int = 16) -> bytes:
    """A grey ``side`` x ``side`` PNG."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    rows = b"".join(b"\0" + b"\x80" * side for _ in range(side))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", side, side, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))

TETRAHEDRON = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.fixture
def source(tmp_path: Path) -> Path:
    path = tmp_path / "in" / "tet.obj"
    path.parent.mkdir()
    path.write_text(TETRAHEDRON)
    return path


def test_write_protected_output_is_refused_without_force(tmp_path: Path, source: Path,
                                                         capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "tet.ply"
    out.write_bytes(b"kept")
    out.chmod(0o444)
    assert main(["convert", str(source), str(out)]) == 2
    err = capsys.readouterr().err
    assert "OUTPUT_CONFLICT" in err or "write-protected" in err, err
    assert out.read_bytes() == b"kept" and not [p for p in tmp_path.iterdir() if p.name.startswith(".tet")]
    assert main(["convert", "--force", str(source), str(out)]) == 0
    assert out.read_bytes().startswith(b"ply")


def test_write_protected_gltf_sidecar_is_refused(tmp_path: Path, source: Path) -> None:
    out = tmp_path / "tet.gltf"
    assert main(["convert", str(source), str(out)]) == 0
    sidecar = tmp_path / "tet.bin"
    before = sidecar.read_bytes()
    sidecar.chmod(0o444)
    assert main(["convert", str(source), str(out)]) == 2
    assert sidecar.read_bytes() == before


def test_batch_refuses_a_write_protected_output(tmp_path: Path, source: Path,
                                                capsys: pytest.CaptureFixture) -> None:
    outdir = tmp_path / "out"
    outdir.mkdir()
    (outdir / "tet.ply").write_bytes(b"kept")
    (outdir / "tet.ply").chmod(0o444)
    assert main(["convert", str(source), "-d", str(outdir), "--to", "ply"]) == 2
    assert "write-protected" in capsys.readouterr().err
    assert (outdir / "tet.ply").read_bytes() == b"kept"
    assert main(["convert", "--force", str(source), "-d", str(outdir), "--to", "ply"]) == 0
    assert (outdir / "tet.ply").read_bytes().startswith(b"ply")


def _ledger_bytes_in(outdir: Path) -> int:
    (entry,) = [json.loads(line) for line in (outdir / "pln-report.jsonl").read_text().splitlines()]
    assert entry["status"] == "ok", entry
    return entry["bytes_in"]


def test_batch_counts_a_gltf_with_its_buffer_and_images(tmp_path: Path) -> None:
    src = tmp_path / "scene"
    src.mkdir()
    tree = json.loads((CORPUS / "gltf_scene" / "TestScene.gltf").read_bytes())
    shutil.copy(CORPUS / "gltf_scene" / "TestScene.bin", src / "TestScene.bin")
    tree["images"] = [{"uri": "label%201.png"}]  # a URI reference: "label 1.png" on disk
    (src / "label 1.png").write_bytes(_png())
    (src / "TestScene.gltf").write_text(json.dumps(tree))
    total = sum(path.stat().st_size for path in src.iterdir())
    outdir = tmp_path / "out"
    assert main(["convert", str(src / "TestScene.gltf"), "-d", str(outdir)]) == 0
    assert _ledger_bytes_in(outdir) == total


def test_batch_counts_an_obj_with_its_material_and_texture(tmp_path: Path, source: Path,
                                                            capsys: pytest.CaptureFixture) -> None:
    source.write_text("mtllib tet.mtl\nusemtl red\n" + TETRAHEDRON)
    (source.parent / "tet.mtl").write_text("newmtl red\nKd 1 0 0\nmap_Kd -s 1 1 1 red.png\n")
    (source.parent / "red.png").write_bytes(_png())
    outdir = tmp_path / "out"
    assert main(["convert", str(source), "-d", str(outdir), "-v"]) == 0
    total = sum(path.stat().st_size for path in source.parent.iterdir())
    assert _ledger_bytes_in(outdir) == total
    assert main(["convert", str(source), str(tmp_path / "tet.pln"), "-v"]) == 0
    err = capsys.readouterr().err
    assert f"{total:,} B in" in err and "textures" in err, err
