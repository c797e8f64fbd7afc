"""``pln convert`` in everyday use (issue 35): it never overwrites an input, a sibling output or a file
the user did not name."""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planefmt.model import Units
from planefmt_converters import registry
from planefmt_converters.cli import main

from corpus import CORPUS

CUBE = CORPUS / "convex" / "cube_subd.obj"
TET = CORPUS / "convex" / "tet.ply"


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _forbid_reading(monkeypatch: pytest.MonkeyPatch) -> None:
    """A refusal comes before any work: from here on, reading an input fails the test."""
    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the conversion started")

    monkeypatch.setattr(registry, "read", refuse)


@pytest.fixture
def cube_pln(tmp_path: Path) -> Path:
    out = tmp_path / "m.pln"
    assert main(["convert", str(CUBE), str(out)]) == 0
    return out


@pytest.mark.parametrize("link", ["same", "symlink", "hardlink", "dotted"])
@pytest.mark.parametrize("name", ["m.pln", "t.obj"])
def test_output_that_is_the_input_is_refused(name: str, link: str, tmp_path: Path, cube_pln: Path,
                                             monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture) -> None:
    src = cube_pln if name == "m.pln" else Path(shutil.copy(CUBE, tmp_path / name))
    dst = {"same": src, "dotted": tmp_path / "." / src.name, "symlink": tmp_path / f"link{src.suffix}",
           "hardlink": tmp_path / f"hard{src.suffix}"}[link]
    if link == "symlink":
        dst.symlink_to(src.name)
    elif link == "hardlink":
        os.link(src, dst)
    before = _snapshot(tmp_path)
    _forbid_reading(monkeypatch)
    assert main(["convert", str(src), str(dst)]) == 2
    err = capsys.readouterr().err
    assert str(src) in err and str(dst) in err and "same file" in err, err
    assert len(err.splitlines()) == 1
    assert _snapshot(tmp_path) == before


def test_batch_inputs_with_one_output_name_are_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first, second = (str(shutil.copy(src, tmp_path / dst)) for src, dst in ((CUBE, "a/model.obj"), (TET, "b/model.ply")))
    _forbid_reading(monkeypatch)
    out = tmp_path / "out"
    assert main(["convert", first, second, "-d", str(out), "--to", "obj"]) == 2
    err = capsys.readouterr().err
    assert first in err and second in err and str(out / "model.obj") in err, err
    assert len(err.splitlines()) == 1
    assert not out.exists()


def test_batch_output_that_is_an_input_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture) -> None:
    src, other = str(shutil.copy(CUBE, tmp_path / "model.obj")), str(shutil.copy(TET, tmp_path / "tet.ply"))
    before = _snapshot(tmp_path)
    _forbid_reading(monkeypatch)
    assert main(["convert", other, src, "-d", str(tmp_path), "--to", "obj"]) == 2
    err = capsys.readouterr().err
    assert src in err and "same file" in err, err
    assert _snapshot(tmp_path) == before


def test_gltf_sidecar_that_belongs_to_another_file_is_kept(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                           capsys: pytest.CaptureFixture) -> None:
    unrelated = tmp_path / "model.bin"
    unrelated.write_bytes(b"someone else's data")
    with monkeypatch.context() as patched:
        _forbid_reading(patched)
        assert main(["convert", str(CUBE), str(tmp_path / "model.gltf")]) == 2
    err = capsys.readouterr().err
    assert str(unrelated) in err and "--force" in err, err
    assert unrelated.read_bytes() == b"someone else's data"
    assert not (tmp_path / "model.gltf").exists()
    assert main(["convert", "--force", str(CUBE), str(tmp_path / "model.gltf")]) == 0
    assert registry.read(tmp_path / "model.gltf")[0].nodes
    # The .bin now belongs to model.gltf: converting again replaces both, without --force.
    assert main(["convert", str(TET), str(tmp_path / "model.gltf")]) == 0
    assert len(registry.read(tmp_path / "model.gltf")[0].nodes[0].mesh.faces) == 4


def test_gltf_sidecar_is_never_an_input_buffer(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture) -> None:
    # scene.gltf's buffer is TestScene.bin, which writing TestScene.gltf would replace.
    shutil.copy(CORPUS / "gltf_scene" / "TestScene.bin", tmp_path)
    src = shutil.copy(CORPUS / "gltf_scene" / "TestScene.gltf", tmp_path / "scene.gltf")
    before = _snapshot(tmp_path)
    _forbid_reading(monkeypatch)
    assert main(["convert", "--force", str(src), str(tmp_path / "TestScene.gltf")]) == 2
    err = capsys.readouterr().err
    assert str(tmp_path / "TestScene.bin") in err and str(src) in err, err
    assert _snapshot(tmp_path) == before


def test_library_gltf_write_keeps_an_unrelated_sidecar(tmp_path: Path) -> None:
    from planefmt.errors import ConversionError

    scene, _ = registry.read(CUBE)
    (tmp_path / "m.bin").write_bytes(b"other")
    with pytest.raises(ConversionError) as caught:
        registry.write(scene, tmp_path / "m.gltf")
    assert caught.value.code == "OUTPUT_CONFLICT" and caught.value.file == str(tmp_path / "m.bin")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.bin"]
    registry.write(scene, tmp_path / "m.gltf", force=True)
    assert (tmp_path / "m.bin").read_bytes() != b"other"
    registry.write(scene, tmp_path / "m.gltf")  # its own sidecar now


# A unit cube whose top is one pentagon with a vertex in the middle of an edge: trimesh fans it from its
# first corner, which makes one zero-area triangle (as polygon triangulations often do).
PENTAGON_TOP_CUBE = """\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 0.5 0 1
f 1 4 3 2\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\nf 5 9 6 7 8
"""
TETRA_FACES = "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def test_zero_area_triangles_are_dropped_with_a_warning(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = tmp_path / "pentagon.obj"
    src.write_text(PENTAGON_TOP_CUBE)
    assert len(registry.read(src)[0].nodes[0].mesh.faces) == 13
    assert main(["convert", str(src), str(tmp_path / "cube.pln")]) == 0
    err = capsys.readouterr().err
    assert "1 zero-area triangle" in err, err
    decoded = registry.read(tmp_path / "cube.pln")[0].nodes[0].mesh
    assert len(decoded.faces) == 12
    assert np.allclose([decoded.vertices.min(axis=0), decoded.vertices.max(axis=0)], [[0, 0, 0], [1, 1, 1]],
                       atol=1e-9)


@pytest.mark.parametrize("text,reason", [
    ("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "zero area"),
    ("v 0 0 0\nv 1e300 0 0\nv 0 1 0\nv 0 0 1\n" + TETRA_FACES, "float32"),
], ids=["all-degenerate", "1e300"])
def test_meshes_planes_cannot_hold_get_a_clear_error(text: str, reason: str, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture) -> None:
    src = tmp_path / "bad.obj"
    src.write_text(text)
    assert main(["convert", str(src), str(tmp_path / "bad.pln")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pln: {src}: ") and reason in err and "Error" not in err, err
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "bad.pln").exists()


# --------------------------------------------------------------------------- messages

PLN = [sys.executable, "-m", "planefmt_converters.cli"]

#: Internals a message must not show: exception class names, temporary files, raw warnings, tracebacks.
LEAKS = re.compile(r"\b[A-Z]\w*(Error|Exception|Warning)\b|\.tmp|/tmp/|Traceback")


def _bad_inputs(cube: bytes) -> dict[str, bytes]:
    crc = bytearray(cube)
    crc[cube.index(b"PHDR") + 24] ^= 0xFF  # a byte of the header chunk's payload: its body segment (version 6)
    return {
        "empty.glb": b"",
        "header-only.glb": b"glTF\x02\x00\x00\x00\x0c\x00\x00\x00",
        "missing-vertex.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
        "truncated.pln": cube[: len(cube) // 2],
        "corrupt.pln": bytes(crc),
        "wrong.ply": b"hello world\n",
        "binary.obj": bytes(range(256)) * 4,
        "text.glb": b"this is not a binary glTF file\n",
        "all-degenerate.obj": b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        "huge.obj": ("v 0 0 0\nv 1e300 0 0\nv 0 1 0\nv 0 0 1\n" + TETRA_FACES).encode(),
        "tiny.obj": ("v 0 0 0\nv 1e-150 0 0\nv 0 1e-150 0\nv 0 0 1e-150\n" + TETRA_FACES).encode(),
        "nan.obj": b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
    }


@pytest.fixture(scope="module")
def cube_bytes(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    out = tmp_path_factory.mktemp("cube") / "cube.pln"
    assert main(["convert", str(CUBE), str(out)]) == 0
    return out.read_bytes()


BAD_NAMES = ["empty.glb", "header-only.glb", "missing-vertex.obj", "truncated.pln", "corrupt.pln", "wrong.ply",
             "binary.obj", "text.glb", "all-degenerate.obj", "huge.obj", "tiny.obj", "nan.obj"]


@pytest.mark.parametrize("how", ["file", "stdin"])
@pytest.mark.parametrize("name", BAD_NAMES)
def test_bad_input_messages_are_one_plain_line(name: str, how: str, tmp_path: Path, cube_bytes: bytes) -> None:
    (tmp_path / name).write_bytes(_bad_inputs(cube_bytes)[name])
    out = "out.obj" if name.endswith(".pln") else "out.pln"
    args = [name, out] if how == "file" else ["-", out]
    with open(tmp_path / name, "rb") as stdin:
        run = subprocess.run([*PLN, "convert", *args], cwd=tmp_path, stdin=stdin, capture_output=True, text=True)
    assert run.returncode == 2, run.stderr
    assert len(run.stderr.splitlines()) == 1, run.stderr
    assert not LEAKS.search(run.stderr), run.stderr
    assert run.stderr.startswith(f"pln: {name if how == 'file' else '<stdin>'}: "), run.stderr
    if name in ("truncated.pln", "corrupt.pln"):
        assert "--salvage" in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_missing_output_folder_is_named_without_temporaries(tmp_path: Path) -> None:
    run = subprocess.run([*PLN, "convert", str(CUBE), "nowhere/out.pln"], cwd=tmp_path, capture_output=True,
                         text=True)
    assert run.returncode == 2
    assert run.stderr.startswith("pln: nowhere/out.pln: ") and not LEAKS.search(run.stderr), run.stderr


_NOISY = """
import sys, numpy
from planefmt.model import Units
from planefmt_converters import registry
from planefmt_converters.cli import main
read = registry.read
def noisy(*args, **kwargs):
    numpy.float64(1e308) * 10  # what numpy says on an overflow: RuntimeWarning
    return read(*args, **kwargs)
registry.read = noisy
sys.exit(main(sys.argv[1:]))
"""


def test_numpy_warnings_stay_off_stderr(tmp_path: Path) -> None:
    run = subprocess.run([sys.executable, "-c", _NOISY, "convert", str(CUBE), "out.pln"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert run.returncode == 0 and run.stderr == "", run.stderr


def test_dropped_notes_say_each_thing_once(tmp_path: Path) -> None:
    from planefmt_converters.trimesh_bridge import scene_from_trimesh
    import trimesh

    textured = trimesh.creation.box()
    textured.visual = trimesh.visual.TextureVisuals(uv=np.zeros((8, 2)))
    plain = trimesh.creation.box()
    plain.visual = trimesh.visual.TextureVisuals(
        material=trimesh.visual.material.PBRMaterial(baseColorFactor=[255, 0, 0, 255]))
    _, notes = scene_from_trimesh(trimesh.Scene([textured, plain]), Units.METRE, None)
    assert notes == ["materials (base colour kept as face colour)", "texture coordinates", "textures"], notes


@pytest.mark.parametrize("stem", ["back 1", "modèle", "100%"])
def test_gltf_with_spaces_or_non_ascii_names_reads_back(stem: str, tmp_path: Path) -> None:
    target = tmp_path / f"{stem}.gltf"
    assert main(["convert", str(CUBE), str(target)]) == 0
    assert (tmp_path / f"{stem}.bin").exists()
    scene, _ = registry.read(target)
    assert len(scene.nodes[0].mesh.faces) == len(registry.read(CUBE)[0].nodes[0].mesh.faces)


@pytest.mark.parametrize("tolerance", ["5", "0.5", "0", "-1e-6", "nan"])
def test_tolerance_outside_its_range_is_refused(tolerance: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                capsys: pytest.CaptureFixture) -> None:
    _forbid_reading(monkeypatch)
    assert main(["convert", f"--tolerance={tolerance}", str(CUBE), str(tmp_path / "c.pln")]) == 2
    err = capsys.readouterr().err
    assert "--tolerance" in err and "0.1" in err and len(err.splitlines()) == 1, err


def test_forced_coding_beyond_the_tolerance_is_marked_lossy_with_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    import planefmt

    out = tmp_path / "coarse.pln"
    assert main(["convert", "--scheme", "paper", "--bits", "4", str(CORPUS / "cad" / "box.STL"), str(out)]) == 0
    err = capsys.readouterr().err
    with planefmt.open(out) as f:
        header = f.header
    assert header.error_bound > header.tolerance and header.lossy
    assert "warning" in err and f"{header.error_bound:.3g}" in err and "lossy" in err, err
    assert main(["info", str(out)]) in (0, 1)
    assert "lossless" not in capsys.readouterr().out


def test_forced_coding_of_shells_still_meets_the_tolerance(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A shell names a corner by its planes only where they put it within the tolerance: coarse
    planes (--bits 4) make its corners explicit, not the file lossy."""
    import planefmt

    out = tmp_path / "coarse.pln"
    assert main(["convert", "--bits", "4", str(CORPUS / "cad" / "box.STL"), str(out)]) == 0
    with planefmt.open(out) as f:
        header = f.header
        kinds = {g.kind for g in f.part_groups()}
    assert len(kinds) == 1 and kinds <= set(planefmt.model.TREE_KINDS)
    assert header.error_bound <= header.tolerance and not header.lossy
    assert "warning" not in capsys.readouterr().err


_KILLED = """
import os, signal, sys
from pxr import UsdUtils
from planefmt_converters import registry
from planefmt_converters.cli import main
write = registry.write
def killed(scene, path, *args, **kwargs):
    os.kill(os.getpid(), signal.SIGKILL)
def killed_packaging(*args):
    os.kill(os.getpid(), signal.SIGKILL)
if sys.argv[-1].endswith(".usdz"):
    UsdUtils.CreateNewUsdzPackage = killed_packaging  # while the package's parts are being written
else:
    registry.write = killed
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("out", ["out.obj", "out.usdz"])
def test_sigkill_leaves_nothing_in_the_temporary_folder(out: str, tmp_path: Path) -> None:
    temp = tmp_path / "temp"
    temp.mkdir()
    run = subprocess.run([sys.executable, "-c", _KILLED, "convert", str(CUBE), out], cwd=tmp_path,
                         env={**os.environ, "TMPDIR": str(temp)}, capture_output=True, text=True)
    assert run.returncode == -9, run.stderr
    assert list(temp.iterdir()) == []
    assert not (tmp_path / out).exists()


def test_version_names_the_package_and_the_format_versions(capsys: pytest.CaptureFixture) -> None:
    import planefmt

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"pln {planefmt.__version__} (planefmt; reads .pln 1.0-6.0, writes 6.0)"


@pytest.mark.parametrize("to,name", [("glb", "x.pln"), ("obj", "x.ply"), ("pln", "x.glb")])
def test_output_extension_that_contradicts_to_is_refused(to: str, name: str, tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch,
                                                         capsys: pytest.CaptureFixture) -> None:
    _forbid_reading(monkeypatch)
    assert main(["convert", "--to", to, str(CUBE), str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert name in err and to in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / name).exists()


@pytest.mark.parametrize("to,name", [("usdc", "x.usd"), ("usda", "x.usd"), ("obj", "x.mesh"), ("ply", "noext")])
def test_output_extension_that_fits_to_or_no_format_is_kept(to: str, name: str, tmp_path: Path) -> None:
    assert main(["convert", "--to", to, str(CUBE), str(tmp_path / name)]) == 0
    assert registry.read(tmp_path / name, to)[0].nodes


def test_readme_cube_figures_are_what_pln_convert_writes(tmp_path: Path) -> None:
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    claim = re.search(r"`convex/cube_subd\.obj` \(six planes\) takes (\d+)\s+bytes, (\d+) as version 1\.0\s+"
                      r"\(`--no-compact`\), (\d+) as version 5\.0", readme)
    assert claim, "README no longer states the cube's sizes"
    sizes = []
    for options in ([], ["--no-compact"], ["--major", "5"]):
        out = tmp_path / f"cube{len(options)}.pln"
        assert main(["convert", *options, str(CUBE), str(out)]) == 0
        sizes.append(out.stat().st_size)
    assert sizes == [int(claim[1]), int(claim[2]), int(claim[3])]
    assert "version\n2.0" not in readme and "version 2.0 (`pln convert`" not in readme


def test_no_compact_says_when_the_file_is_not_version_1(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    import planefmt

    # A cube is convex groups, which version 1.0 has: 1.0 and no word about it.
    assert main(["convert", "--no-compact", str(CUBE), str(tmp_path / "cube.pln")]) == 0
    assert "not 1.0" not in capsys.readouterr().err
    with planefmt.open(tmp_path / "cube.pln") as r:
        assert r.header.version == (1, 0)
    # A non-convex part is a shell walk by default, which 1.0 has not: the file says 5.0, and so does pln.
    out = tmp_path / "part.pln"
    assert main(["convert", "--no-compact", str(CORPUS / "open" / "not_convex.obj"), str(out)]) == 0
    err = capsys.readouterr().err
    with planefmt.open(out) as r:
        version = r.header.version
    assert version != (1, 0)
    assert f"written as version {version[0]}.{version[1]}, not 1.0 (--no-compact)" in err and "shell walk" in err


def test_compact_help_names_the_default(capsys: pytest.CaptureFixture) -> None:
    assert main(["convert", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "(spec/pln.md; the default)" in text and "--no-compact writes version 1.0" in text


# --------------------------------------------------------------------------- progress and summary

class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_on_a_terminal_shows_stage_percent_and_elapsed(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    from planefmt_converters.cli import progress

    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.005)
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["convert", str(CUBE), str(tmp_path / "cube.pln")]) == 0
    lines = terminal.getvalue().split("\r")
    assert any(re.fullmatch(r"pln: encoding objects 0/1 \(0%\), \d+ s *", line) for line in lines), lines
    assert any(re.fullmatch(r"pln: verifying codings \(\d+ so far\), \d+ s *", line) for line in lines), lines
    *_, last = terminal.getvalue().splitlines()
    size = (tmp_path / "cube.pln").stat().st_size
    assert re.fullmatch(rf"pln: {re.escape(str(CUBE))} -> {re.escape(str(tmp_path / 'cube.pln'))}: "
                        rf"{CUBE.stat().st_size:,} B in, {size:,} B out, error at most \S+ of the diagonal, "
                        r"\d+\.\d s", last), last


def test_summary_on_a_pseudo_terminal_and_nothing_on_a_pipe(tmp_path: Path) -> None:
    import pty

    main_fd, sub_fd = pty.openpty()
    run = subprocess.run([*PLN, "convert", str(TET), "tet.obj"], cwd=tmp_path, stderr=sub_fd,
                         stdout=subprocess.DEVNULL)
    os.close(sub_fd)
    seen = b""
    with contextlib.suppress(OSError):  # EIO once the terminal's other end is closed and drained
        while chunk := os.read(main_fd, 4096):
            seen += chunk
    os.close(main_fd)
    assert run.returncode == 0
    assert re.search(rb"pln: \S+tet\.ply -> tet\.obj: \d+ B in, \d+ B out, \d+\.\d s", seen), seen
    piped = subprocess.run([*PLN, "convert", str(TET), "tet2.obj"], cwd=tmp_path, capture_output=True, text=True)
    assert piped.returncode == 0 and piped.stderr == ""
    verbose = subprocess.run([*PLN, "convert", "-v", str(TET), "tet.pln"], cwd=tmp_path, capture_output=True,
                             text=True)
    assert verbose.returncode == 0 and "\r" not in verbose.stderr
    assert re.fullmatch(r"pln: \S+tet\.ply -> tet\.pln: \d+ B in, \d+ B out, error at most \S+ of the diagonal, "
                        r"\d+\.\d s\n", verbose.stderr), verbose.stderr


def test_batch_with_a_missing_input_converts_the_others(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["convert", str(tmp_path / "absent.obj"), str(TET), "-d", str(tmp_path / "out"), "--to", "obj"]) == 2
    assert "absent.obj" in capsys.readouterr().err
    assert (tmp_path / "out" / "tet.obj").exists()
