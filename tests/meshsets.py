"""Generated datasets for batch conversion tests and ``bench/batch.py``: many tiny meshes in several
formats (boxes, tetrahedra and prisms under random transforms, each encoding in milliseconds), some
small real corpus files, and broken files (truncated, empty, NaN coordinates).

:func:`build` writes one into a folder and returns what each file should give.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Formats the generated meshes are written in, in turn.
FORMATS = ("obj", "ply", "stl", "off", "glb")
#: Small corpus meshes (category/name) that encode in well under a second.
CORPUS_FILES = ("convex/tet.ply", "cad/20mm-xyz-cube.stl")


@dataclass(frozen=True)
class Expected:
    """What a dataset file should give: ``triangles`` and ``bbox`` ((2, 3)) of a good one, None for a
    broken one."""

    path: Path
    triangles: int | None
    bbox: np.ndarray | None

    @property
    def good(self) -> bool:
        return self.triangles is not None


def _box() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


def _tetrahedron() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    return v, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _prism() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[0, 0, 0], [1, 0, 0], [0.3, 1, 0], [0, 0, 1], [1, 0, 1], [0.3, 1, 1]], dtype=float)
    f = np.array([[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3], [2, 3, 5]])
    return v, f


SHAPES = (_box, _tetrahedron, _prism)


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def _mesh(rng: np.random.Generator, shape) -> tuple[np.ndarray, np.ndarray]:
    v, f = shape()
    scale = rng.uniform(0.5, 3.0, 3)
    v = (v * scale) @ _random_rotation(rng).T + rng.uniform(-10, 10, 3)
    return v, f


def build(folder: Path, count: int = 200, broken: int = 12, seed: int = 7,
          corpus: Path | None = None) -> list[Expected]:
    """``count`` generated meshes in :data:`FORMATS` under ``folder`` (in sub-folders by format, some
    one level deeper), ``broken`` broken files among them and, with ``corpus``, the
    :data:`CORPUS_FILES` copied in; what each file should give."""
    import trimesh

    rng = np.random.default_rng(seed)
    expected = []
    for i in range(count):
        fmt = FORMATS[i % len(FORMATS)]
        sub = folder / fmt / (f"group{i % 3}" if i % 2 else "")
        sub.mkdir(parents=True, exist_ok=True)
        v, f = _mesh(rng, SHAPES[i % len(SHAPES)])
        path = sub / f"mesh{i:04d}.{fmt}"
        trimesh.Trimesh(v, f, process=False).export(path)
        expected.append(Expected(path, len(f), np.array([v.min(axis=0), v.max(axis=0)])))
    for j in range(broken):
        kind = ("truncated", "empty", "nan")[j % 3]
        fmt = FORMATS[j % len(FORMATS)]
        path = folder / "broken" / f"{kind}{j:02d}.{'obj' if kind == 'nan' else fmt}"
        path.parent.mkdir(parents=True, exist_ok=True)
        if kind == "empty":
            path.write_bytes(b"")
        elif kind == "nan":
            path.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
        else:
            v, f = _mesh(rng, _box)
            data = trimesh.Trimesh(v, f, process=False).export(file_type=fmt)
            data = data.encode() if isinstance(data, str) else data
            path.write_bytes(data[: len(data) // 2 - 7])
        expected.append(Expected(path, None, None))
    for name in CORPUS_FILES if corpus is not None else ():
        path = folder / "corpus" / Path(name).name
        path.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(corpus / name, path)
        mesh = trimesh.load(path, force="mesh", process=False)
        expected.append(Expected(path, len(mesh.faces), np.asarray(mesh.bounds)))
    return expected
