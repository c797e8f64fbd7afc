"""Topology of triangle meshes: closedness, Euler characteristic, enclosed volume.

Faces are ``(F, 3)`` vertex indices, counter-clockwise seen from outside.
"""

from __future__ import annotations

import numpy as np

from .polygonize import edge_adjacency


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by triangles (model units cubed; positive for outward, closed surfaces)."""
    p = vertices[faces]
    c = p.reshape(-1, 3).mean(axis=0)
    p = p - c
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum()) / 6.0


def euler_characteristic(faces: np.ndarray) -> int:
    """``V - E + F`` of a triangle mesh (vertices counted as used)."""
    e = np.sort(np.column_stack([faces.reshape(-1), faces[:, [1, 2, 0]].reshape(-1)]), axis=1)
    return len(np.unique(faces)) - len(np.unique(e, axis=0)) + len(faces)


def is_closed_manifold(faces: np.ndarray, vertex_count: int) -> bool:
    """Every edge shared by exactly two faces running opposite ways."""
    return bool(len(faces)) and edge_adjacency(faces, vertex_count).closed
