"""pln preview: a headless PNG of the decoded part groups, one colour per group."""

from __future__ import annotations

import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import trimesh

from planefmt import codec
from planefmt.model import Mesh, Node, Scene
from planefmt_converters.assemble import up_rotation
from planefmt_converters.cli import main
from planefmt_converters.render import BACKGROUND, PALETTE, png_bytes, render

PLN = [sys.executable, "-m", "planefmt_converters.cli"]


def read_png(data: bytes) -> np.ndarray:
    """The RGB pixels of a PNG as png_bytes writes it (one IDAT, filter type 0 on every row)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, size = 8, b"", None
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        assert struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])[0] == zlib.crc32(tag + body)
        if tag == b"IHDR":
            size = struct.unpack(">II", body[:8])
        elif tag == b"IDAT":
            idat += body
        pos += 12 + n
    w, h = size
    rows = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, 1 + 3 * w)
    assert (rows[:, 0] == 0).all()
    return rows[:, 1:].reshape(h, w, 3)


def group_of(pixels: np.ndarray) -> np.ndarray:
    """The palette entry of each drawn pixel: shading scales a colour, its RGB direction stays."""
    direction = pixels / np.linalg.norm(pixels, axis=-1, keepdims=True)
    palette = PALETTE / np.linalg.norm(PALETTE, axis=1, keepdims=True)
    return np.argmax(direction @ palette.T, axis=-1)


def box(centre, size) -> tuple[np.ndarray, np.ndarray]:
    m = trimesh.creation.box(size)
    return np.asarray(m.vertices) + centre, np.asarray(m.faces)


def test_nearer_surface_hides_the_farther_one():
    far_v, far_f = box([0, 0, 0], [4, 4, 4])
    near_v, near_f = box([0, -3, 0], [1, 1, 1])  # between the big box and an eye on -y
    v = np.vstack([far_v, near_v])
    f = np.vstack([far_f, near_f + len(far_v)])
    group = np.repeat([0, 1], [len(far_f), len(near_f)])
    img = render(v, f, group, size=101, view=(0.0, -1.0, 0.0))
    assert group_of(img[50, 50].astype(float)) == 1 and group_of(img[50, 20].astype(float)) == 0
    assert (img[0, 0] == BACKGROUND).all()


def test_png_round_trips_pixels():
    img = np.random.default_rng(0).integers(0, 256, (7, 5, 3), dtype=np.uint8)
    assert np.array_equal(read_png(png_bytes(img)), img)


def test_cli_preview_draws_every_object_in_its_colour(tmp_path: Path):
    scene = Scene(nodes=tuple(Node(f"b{k}", None, np.array([[1, 0, 0, 2.0 * k], [0, 1, 0, 0], [0, 0, 1, 0],
                                                              [0, 0, 0, 1]]), Mesh(*box([0, 0, 0], [1, 1, 1])))
                              for k in range(3)))
    codec.encode_scene(scene, tmp_path / "three.pln")
    out = tmp_path / "three.png"
    p = subprocess.run([*PLN, "preview", str(tmp_path / "three.pln"), "-o", str(out), "--size", "200"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    img = read_png(out.read_bytes()).reshape(-1, 3).astype(float)
    drawn = img[(img != BACKGROUND).any(axis=1)]
    assert set(np.unique(group_of(drawn))) == {0, 1, 2}


def test_cli_preview_bad_input_is_one_line_and_no_file(tmp_path: Path):
    bad = tmp_path / "not.pln"
    bad.write_bytes(b"hello, not a pln file")
    out = tmp_path / "x.png"
    p = subprocess.run([*PLN, "preview", str(bad), "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not out.exists()


def _pole_scene(up: str | None, along: str) -> Scene:
    """A pole 10 long along +``along`` beside a small block: what stands upright when ``along`` is up."""
    pole_v, pole_f = box([0, 5, 0], [1, 10, 1])
    block_v, block_f = box([2, 0.25, 0], [1, 0.5, 1])
    if along == "Z":  # (x, y, z) -> (x, -z, y): exact, the same model standing on another axis
        pole_v, block_v = (v @ up_rotation("Y", "Z")[:3, :3].T for v in (pole_v, block_v))
    return Scene((Node("pole", mesh=Mesh(pole_v, pole_f)), Node("block", mesh=Mesh(block_v, block_f))), up_axis=up)


def _preview(scene: Scene, folder: Path, name: str, *options: str) -> np.ndarray:
    codec.encode_scene(scene, folder / f"{name}.pln")
    assert main(["preview", str(folder / f"{name}.pln"), "-o", str(folder / f"{name}.png"), "--size", "120",
                 *options]) == 0
    return read_png((folder / f"{name}.png").read_bytes())


def _drawn_extent(img: np.ndarray) -> tuple[int, int]:
    """Height and width of what is drawn, in pixels."""
    rows, cols = np.nonzero((img != BACKGROUND).any(axis=2))
    return rows.max() - rows.min() + 1, cols.max() - cols.min() + 1


def test_preview_draws_the_file_up_axis_upwards(tmp_path: Path):
    y_up = _preview(_pole_scene("Y", "Y"), tmp_path, "y")
    z_up = _preview(_pole_scene("Z", "Z"), tmp_path, "z")
    # A glTF-like Y-up file is drawn as its Z-up twin is: the same upright view, pixel for pixel.
    assert np.array_equal(y_up, z_up)
    height, width = _drawn_extent(y_up)
    assert height > 2 * width
    # A file that names no axis is drawn Z up, as before.
    assert np.array_equal(_preview(_pole_scene(None, "Z"), tmp_path, "none"), z_up)


def test_preview_up_option_overrides_the_file(tmp_path: Path):
    lying = _preview(_pole_scene("Y", "Y"), tmp_path, "y", "--up", "Z")
    height, width = _drawn_extent(lying)
    assert width > height  # the Y pole drawn as if Z were up lies on its side
    assert np.array_equal(_preview(_pole_scene("Z", "Y"), tmp_path, "z", "--up", "Y"),
                          _preview(_pole_scene("Y", "Y"), tmp_path, "y"))
