"""A headless picture of decoded part groups: a numpy z-buffer and a PNG writer, no display needed.

Used by ``pln preview``. Orthographic view along ``-view`` (a direction
towards the eye, model coordinates), the ``up`` axis (Y or Z) towards the
top of the picture, flat Lambert shading with a fixed
light over the eye's shoulder, one colour per part group. Back faces are
drawn darker so an open surface's inside shows as such. Rasterization is
vectorized over (triangle, pixel) pairs in bounded batches: memory stays
O(batch) whatever the mesh size.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from .assemble import up_rotation

#: A view from the front right and above a Z-up model (``DEFAULT_VIEW_Z_UP`` turned for other up axes).
DEFAULT_VIEW_Z_UP = (1.0, -1.4, 0.9)
#: Colours of part groups, cycled: Okabe-Ito, legible for colour-blind readers.
PALETTE = np.array([[230, 159, 0], [86, 180, 233], [0, 158, 115], [240, 228, 66], [0, 114, 178],
                    [213, 94, 0], [204, 121, 167], [120, 120, 120]], dtype=np.float64)
BACKGROUND = np.array([255, 255, 255], dtype=np.uint8)
#: (triangle, pixel) candidate pairs rasterized at once.
BATCH = 1 << 21


def _camera(view: np.ndarray) -> np.ndarray:
    """Rows: screen right, screen up, towards the eye (orthonormal, right-handed)."""
    back = np.asarray(view, dtype=np.float64)
    back = back / np.linalg.norm(back)
    up = np.array([0.0, 0.0, 1.0]) if abs(back[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(back, right), back])


def default_view(up: str) -> np.ndarray:
    """The default direction towards the eye for a model whose ``up`` axis points up: the same view of
    it whichever axis that is."""
    return up_rotation("Z", up)[:3, :3] @ np.array(DEFAULT_VIEW_Z_UP)


def render(vertices: np.ndarray, triangles: np.ndarray, group: np.ndarray, *, size: int = 640,
           view: tuple[float, float, float] = DEFAULT_VIEW_Z_UP, up: str = "Z") -> np.ndarray:
    """An ``(size, size, 3)`` uint8 image of ``triangles`` (T, 3) over ``vertices`` (V, 3).

    ``group`` (T,) gives each triangle's part group, which picks its colour; ``up`` ("Y" or "Z") is
    the model axis drawn upwards.
    """
    image = np.empty((size, size, 3), dtype=np.uint8)
    image[:] = BACKGROUND
    if len(triangles) == 0:
        return image
    # The camera is built for +z up: a model of another up axis is turned into that frame first.
    turn = up_rotation(up, "Z")[:3, :3]
    vertices = np.asarray(vertices, dtype=np.float64) @ turn.T
    cam = _camera(turn @ np.asarray(view, dtype=np.float64))
    p = vertices @ cam.T
    lo, hi = p[:, :2].min(axis=0), p[:, :2].max(axis=0)
    scale = 0.9 * size / max(float((hi - lo).max()), 1e-300)
    xy = (p[:, :2] - (lo + hi) / 2) * scale + size / 2
    xy[:, 1] = size - xy[:, 1]  # image rows grow downwards
    depth = p[:, 2]
    a, b, c = (xy[triangles[:, i]] for i in range(3))
    normal = np.cross(vertices[triangles[:, 1]] - vertices[triangles[:, 0]],
                      vertices[triangles[:, 2]] - vertices[triangles[:, 0]])
    length = np.linalg.norm(normal, axis=1)
    keep = length > 0
    normal[keep] /= length[keep, None]
    light = cam.T @ np.array([-0.4, 0.5, 0.77])
    lambert = normal @ light
    facing = normal @ cam[2] >= 0
    shade = np.where(facing, 0.35 + 0.65 * np.abs(lambert), 0.2 + 0.25 * np.abs(lambert))
    colour = PALETTE[np.asarray(group) % len(PALETTE)] * shade[:, None]

    x0 = np.clip(np.floor(np.minimum(np.minimum(a[:, 0], b[:, 0]), c[:, 0])), 0, size - 1).astype(np.int64)
    x1 = np.clip(np.ceil(np.maximum(np.maximum(a[:, 0], b[:, 0]), c[:, 0])), 0, size - 1).astype(np.int64)
    y0 = np.clip(np.floor(np.minimum(np.minimum(a[:, 1], b[:, 1]), c[:, 1])), 0, size - 1).astype(np.int64)
    y1 = np.clip(np.ceil(np.maximum(np.maximum(a[:, 1], b[:, 1]), c[:, 1])), 0, size - 1).astype(np.int64)
    w, h = x1 - x0 + 1, y1 - y0 + 1
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    live = np.flatnonzero(keep & (np.abs(area) > 1e-12))
    zbuf = np.full(size * size, np.inf)
    best = np.full(size * size, -1, dtype=np.int64)
    counts = (w * h)[live]
    bounds = np.concatenate([[0], np.cumsum(counts)])
    start = 0
    while start < len(live):
        stop = int(np.searchsorted(bounds, bounds[start] + BATCH, side="right")) - 1
        stop = max(stop, start + 1)
        t = np.repeat(live[start:stop], counts[start:stop])
        k = np.arange(len(t)) - np.repeat(bounds[start:stop] - bounds[start], counts[start:stop])
        px, py = x0[t] + k % w[t], y0[t] + k // w[t]
        cx, cy = px + 0.5, py + 0.5
        # Barycentric weights; a pixel centre inside (or on an edge) of the triangle is covered.
        wa = ((b[t, 0] - cx) * (c[t, 1] - cy) - (b[t, 1] - cy) * (c[t, 0] - cx)) / area[t]
        wb = ((c[t, 0] - cx) * (a[t, 1] - cy) - (c[t, 1] - cy) * (a[t, 0] - cx)) / area[t]
        wc = 1.0 - wa - wb
        inside = (wa >= 0) & (wb >= 0) & (wc >= 0)
        t, px, py = t[inside], px[inside], py[inside]
        z = -(wa[inside] * depth[triangles[t, 0]] + wb[inside] * depth[triangles[t, 1]]
              + wc[inside] * depth[triangles[t, 2]])
        pix = py * size + px
        order = np.lexsort((z, pix))
        pix, z, t = pix[order], z[order], t[order]
        first = np.ones(len(pix), dtype=bool)
        first[1:] = pix[1:] != pix[:-1]
        pix, z, t = pix[first], z[first], t[first]
        nearer = z < zbuf[pix]
        zbuf[pix[nearer]] = z[nearer]
        best[pix[nearer]] = t[nearer]
        start = stop
    hit = best >= 0
    image.reshape(-1, 3)[hit] = np.clip(colour[best[hit]], 0, 255).astype(np.uint8)
    return image


def png_bytes(image: np.ndarray) -> bytes:
    """An RGB ``(H, W, 3)`` uint8 image as PNG bytes (8-bit truecolour, no filtering)."""
    h, w, _ = image.shape
    raw = np.concatenate([np.zeros((h, 1), dtype=np.uint8), image.reshape(h, w * 3)], axis=1).tobytes()

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
