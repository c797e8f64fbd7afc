"""Plane math with the paper's conventions (spec §2.3, §8), vectorized over arrays of planes.

Conventions:

* An oriented plane is ``(omega, h)``: ``omega`` a unit vector, the
  **outward** normal; ``h`` the signed distance from the origin in model
  units. The plane is ``omega . x = h``; the solid lies in the closed inner
  half-space ``omega . x <= h``.
* The triplet is ``(nu, phi, h)`` in radians, radians, model units:
  ``nu = arccos(omega_z)`` in [0, pi], ``phi = atan2(omega_y, omega_x) mod 2 pi``
  in [0, 2 pi), with ``phi = 0`` exactly at the poles.
* A triangle P1 P2 P3 runs counter-clockwise seen from outside, so
  ``omega = (P2 - P1) x (P3 - P2) / |...|`` and ``h = omega . P1``.
* A transform is a 4x4 affine matrix ``M`` acting on column vectors
  ``(x, y, z, 1)``; ``M[:3, :3]`` is ``A``, ``M[:3, 3]`` the translation ``t``.

Arrays: ``omega`` is ``(n, 3)`` float64, ``h`` is ``(n,)`` float64,
triplets ``(n, 3)`` float64.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import GeometryError

TWO_PI = 2.0 * math.pi


def triangle_planes(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The oriented plane of every triangle, by the paper's conversion formulas (its §8).

    Returns ``(omega, h, area)``: ``omega`` ``(m, 3)`` unit outward normals,
    ``h`` ``(m,)`` in model units (``omega . P1``), ``area`` ``(m,)`` in model
    units squared. Triangles of zero area have no plane: their ``omega`` and
    ``h`` are NaN (callers mask them with ``area > 0``).
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    p1, p2, p3 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(p2 - p1, p3 - p2)
    norm = np.linalg.norm(n, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        omega = n / norm[:, None]
    omega[norm == 0] = np.nan
    h = np.einsum("ij,ij->i", omega, p1)
    return omega, h, 0.5 * norm


def angles_from_normals(omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(nu, phi)`` in radians of directions ``omega`` ``(n, 3)`` (need not be unit length).

    ``nu = atan2(hypot(wx, wy), wz)``, which equals ``arccos(wz)`` for unit
    vectors but keeps full precision near the poles where ``arccos`` loses
    half the digits. ``phi`` is in [0, 2 pi): exactly 0 at the poles and
    never 2 pi itself (a tiny negative angle that rounds to 2 pi maps to 0,
    the same direction).
    """
    w = np.asarray(omega, dtype=np.float64).reshape(-1, 3)
    rho = np.hypot(w[:, 0], w[:, 1])
    nu = np.arctan2(rho, w[:, 2])
    # "+ 0.0" turns atan2's -0.0 (omega_y = -0.0) into +0.0.
    phi = np.arctan2(w[:, 1], w[:, 0]) + 0.0
    phi = np.where(phi < 0.0, phi + TWO_PI, phi)
    phi[(phi >= TWO_PI) | (rho == 0.0)] = 0.0
    return nu, phi


def normals_from_angles(nu: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors ``(n, 3)`` ``(sin nu cos phi, sin nu sin phi, cos nu)`` from radians."""
    nu = np.asarray(nu, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    s = np.sin(nu)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(nu)], axis=-1)


def to_triplets(omega: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Triplets ``(n, 3)`` ``(nu, phi, h)`` of planes ``(omega, h)``."""
    nu, phi = angles_from_normals(omega)
    return np.column_stack([nu, phi, np.asarray(h, dtype=np.float64).reshape(-1)])


def from_triplets(triplets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planes ``(omega (n, 3), h (n,))`` of triplets ``(n, 3)`` ``(nu, phi, h)``."""
    t = np.asarray(triplets, dtype=np.float64).reshape(-1, 3)
    return normals_from_angles(t[:, 0], t[:, 1]), t[:, 2].copy()


def signed_distances(omega: np.ndarray, h: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``omega_i . p_j - h_i`` as an ``(n, k)`` array in model units: > 0 is outside plane i."""
    return np.asarray(omega) @ np.asarray(points, dtype=np.float64).T - np.asarray(h)[:, None]


def translate(omega: np.ndarray, h: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planes of the solid translated by vector ``a`` (paper, theorem 2): ``h' = h + <omega, a>``."""
    omega = np.asarray(omega, dtype=np.float64)
    return omega.copy(), np.asarray(h, dtype=np.float64) + omega @ np.asarray(a, dtype=np.float64)


def rotate(omega: np.ndarray, h: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planes of the solid rotated about the origin by the 3x3 matrix ``rotation`` (paper, theorem 3).

    ``omega' = R omega``, ``h' = h``. ``rotation`` must be orthogonal with
    determinant +1; use :func:`transform` for anything else.
    """
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape != (3, 3) or not np.allclose(r @ r.T, np.eye(3), atol=1e-9) or np.linalg.det(r) < 0:
        raise GeometryError("rotate() needs a proper rotation matrix; use transform() for other maps")
    return np.asarray(omega, dtype=np.float64) @ r.T, np.asarray(h, dtype=np.float64).copy()


def transform(omega: np.ndarray, h: np.ndarray, matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planes of the solid mapped by the affine 4x4 ``matrix`` ``x' = A x + t``.

    The inner half-space ``omega . x <= h`` maps to ``n . x' <= h + n . t``
    with ``n = A^-T omega``; normalizing gives ``omega' = n / |n|`` and
    ``h' = (h + n . t) / |n|`` (with translation and rotation this is the
    paper's theorems 2 and 3; non-uniform scale and shear need the
    inverse-transpose). The *inequality* is carried over, so each mapped
    plane keeps the mapped solid on its inner side: under a reflection
    (``det A < 0``) the plane set stays outward as it is, with no flipping.
    What a reflection does flip is the winding of triangles mapped vertex by
    vertex; decoding rebuilds winding from the outward planes, so decoded
    meshes are counter-clockwise from outside either way.
    """
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape != (4, 4) or not np.isfinite(m).all() or not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise GeometryError("a transform must be a finite affine 4x4 matrix with last row 0 0 0 1")
    a, t = m[:3, :3], m[:3, 3]
    if not np.linalg.cond(a) < 1e15:
        raise GeometryError("a singular transform maps solids to flat sets, which have no planes")
    n = np.asarray(omega, dtype=np.float64) @ np.linalg.inv(a)  # rows are (A^-T omega)^T
    s = np.linalg.norm(n, axis=1)
    return n / s[:, None], (np.asarray(h, dtype=np.float64) + n @ t) / s


def transform_triplets(triplets: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Triplets of planes mapped by the affine 4x4 ``matrix`` (see :func:`transform`)."""
    omega, h = from_triplets(triplets)
    return to_triplets(*transform(omega, h, matrix))


def transform_points(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Points ``(n, 3)`` mapped by the affine 4x4 ``matrix`` acting on column vectors."""
    m = np.asarray(matrix, dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ m[:3, :3].T + m[:3, 3]


def in_plane_basis(omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``e1, e2`` (n, 3) with ``(e1, e2, omega)`` right-handed, for unit normals
    ``omega`` (n, 3): angles measured in that basis run counter-clockwise seen from outside."""
    axis = np.zeros_like(omega)
    axis[np.arange(len(omega)), np.argmin(np.abs(omega), axis=1)] = 1.0
    e1 = np.cross(omega, axis)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(omega, e1)
