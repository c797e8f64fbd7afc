"""Triangle-strip PLY files made as the Cyberware scans of the Stanford repository store them: binary
big-endian, float vertices, one ``tristrips`` row of ``vertex_indices`` (``list int int``) whose strips
run along the rows of the range grid, -1 between strips."""

from __future__ import annotations

import numpy as np


def grid_strips(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of a ``rows x cols`` height field and its strips, one per pair of grid rows, each
    ``(r, 0), (r+1, 0), (r, 1), (r+1, 1), ...`` ending in -1. The second strip runs
    ``(r+1, 0), (r, 0), ...`` after a joint (its first corner twice), which flips the parity back as
    strip builders do: every triangle faces -z."""
    j, r = np.meshgrid(np.arange(cols, dtype=np.float64), np.arange(rows, dtype=np.float64))
    vertices = np.stack([j, r, np.sin(j / 3.0) * np.cos(r / 4.0)], axis=-1).reshape(-1, 3)
    strips = []
    for row in range(rows - 1):
        strip = np.stack([row * cols + np.arange(cols), (row + 1) * cols + np.arange(cols)], axis=1).reshape(-1)
        if row == 1:
            strip = strip.reshape(-1, 2)[:, ::-1].reshape(-1)
            strip = np.concatenate([strip[:1], strip])
        strips.append(np.append(strip, -1))
    return vertices, np.concatenate(strips)


def ply_bytes(vertices: np.ndarray, strip: np.ndarray) -> bytes:
    """A binary big-endian PLY of ``vertices`` and one ``tristrips`` row holding ``strip``."""
    header = (f"ply\nformat binary_big_endian 1.0\ncomment made by tests/plystrips.py as Cyberware scans are\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
              "element tristrips 1\nproperty list int int vertex_indices\nend_header\n").encode("ascii")
    return (header + vertices.astype(">f4").tobytes() + np.array([len(strip)], ">i4").tobytes()
            + strip.astype(">i4").tobytes())


def stripify(faces: np.ndarray) -> np.ndarray:
    """``faces`` as triangle strips, -1 after each, built greedily as strip builders walk a mesh: a strip
    grows across the edge its last two corners share with an unused triangle of the winding its place
    in the strip gives (even places ``(s[i], s[i+1], s[i+2])``, odd ``(s[i+1], s[i], s[i+2])``)."""
    faces = np.asarray(faces, dtype=np.int64)
    across = {}
    for t, (a, b, c) in enumerate(faces.tolist()):
        across.update({(a, b): (t, c), (b, c): (t, a), (c, a): (t, b)})
    used = np.zeros(len(faces), dtype=bool)
    out: list[int] = []
    for t in range(len(faces)):
        if used[t]:
            continue
        used[t] = True
        strip = faces[t].tolist()
        while True:
            edge = (strip[-1], strip[-2]) if len(strip) % 2 == 1 else (strip[-2], strip[-1])
            nxt = across.get(edge)
            if nxt is None or used[nxt[0]]:
                break
            used[nxt[0]] = True
            strip.append(nxt[1])
        out += strip + [-1]
    return np.array(out, dtype=np.int64)
