"""Building model meshes from raw arrays, and placing scene nodes in world space.

Every reader funnels its triangles through :func:`build_mesh`, so all formats
agree on what a :class:`planefmt.model.Mesh` holds: finite float64 vertices,
each distinct position stored once (exact comparison only), every vertex used
by a face, and no face that repeats a vertex. The codec relies on the shared
vertices: it sees connectivity only through equal indices.

The flat formats (OBJ, PLY, STL, OFF) hold one mesh in one frame, so their
writers call :func:`flatten` to bake the scene's transforms into one mesh.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

import numpy as np

from planefmt.errors import ConversionError
from planefmt.model import Mesh, Node, Scene, Units

#: A triangle whose height is at most this fraction of its mesh's bounding-box diagonal has no plane:
#: collinear corners in float64 give heights about 1e-16 of the diagonal, and dropping the triangle moves
#: the surface by its height, far under any tolerance the codec accepts.
ZERO_AREA = 1e-12

#: Face colour given to uncoloured meshes when a flattened scene mixes
#: coloured and uncoloured ones (opaque white: the colour a viewer assumes).
DEFAULT_COLOUR = np.array([255, 255, 255, 255], dtype=np.uint8)


def build_mesh(
    vertices: np.ndarray,
    faces: np.ndarray,
    face_colours: np.ndarray | None = None,
    *,
    what: str | None = "mesh",
    file: str | None = None,
) -> tuple[Mesh | None, int]:
    """Clean raw triangles into a :class:`Mesh`.

    ``vertices`` (n, 3) and ``faces`` (m, 3) as read; ``face_colours`` (m, 4)
    uint8 or None. Returns ``(mesh, degenerate)`` where ``degenerate`` counts
    the faces removed because they repeat a vertex after merging, and
    ``mesh`` is None when no face is left. ``what`` names the mesh (node or
    prim path) in error messages; None where the file name says enough.

    Raises :class:`ConversionError` for non-finite coordinates or face indices
    outside the vertex array.
    """
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    prefix = f"{what}: " if what else ""
    if not np.isfinite(vertices).all():
        raise ConversionError(f"{prefix}vertex coordinates are NaN or infinite", file=file)
    if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ConversionError(
            f"{prefix}face index outside the {len(vertices)} vertices", file=file)
    if face_colours is not None:
        face_colours = np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)
        if len(face_colours) != len(faces):
            raise ConversionError(
                f"{prefix}{len(face_colours)} face colours for {len(faces)} faces", file=file)

    # Adding 0.0 turns -0.0 into +0.0, so that the two zeros merge.
    merged, remap = _merge_exact(vertices + 0.0)
    faces = remap[faces]
    keep = ((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2])
            & (faces[:, 2] != faces[:, 0]))
    degenerate = int(len(faces) - np.count_nonzero(keep))
    faces = faces[keep]
    if face_colours is not None:
        face_colours = face_colours[keep]
    if len(faces) == 0:
        return None, degenerate

    # Drop vertices no face uses (points, loose vertices, merged leftovers),
    # keeping the survivors in their original order.
    used = np.zeros(len(merged), dtype=bool)
    used[faces.ravel()] = True
    new_index = np.cumsum(used) - 1
    return Mesh(vertices=merged[used], faces=new_index[faces],
                face_colours=face_colours), degenerate


def _merge_exact(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge rows with identical coordinates; first occurrences keep their order."""
    if len(vertices) == 0:
        return vertices, np.zeros(0, dtype=np.int64)
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return vertices[first[order]], rank[inverse.reshape(-1)]


def with_area(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per face: whether it is taller than ZERO_AREA of the mesh's diagonal."""
    v = vertices - vertices.min(axis=0)
    diagonal = float(np.linalg.norm(v.max(axis=0)))
    if not diagonal > 0:
        return np.zeros(len(faces), dtype=bool)
    # In units of the diagonal, so that products neither overflow nor underflow at extreme scales.
    corners = (v / diagonal)[faces]
    edges = corners[:, [1, 2, 0]] - corners
    longest = np.linalg.norm(edges, axis=2).max(axis=1)
    twice_area = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    return twice_area > ZERO_AREA * longest


def at_float32(scene: Scene) -> tuple[Scene, list[str]]:
    """``scene`` as a float32 format stores it, and the notes on what that cost.

    Rounding can make two vertices equal or three corners collinear. A reader
    welds equal positions, so triangles over welded corners would come back
    as zero-area triangles the source did not have, and the .pln encoder
    drops triangles without area: each mesh is welded after rounding and its
    triangles left without area removed here (:func:`_flip_flat`), so that the
    file holds what its readers will see. Meshes shared by several nodes stay
    shared. Raises :class:`ConversionError` when a mesh keeps no triangle.
    """
    rounded: dict[int, Mesh | None] = {}
    moved = dropped = 0
    for node in scene.nodes:
        mesh = node.mesh
        if mesh is None or id(mesh) in rounded:
            continue
        vertices = mesh.vertices.astype(np.float32).astype(np.float64)
        moved += int((vertices != mesh.vertices).any())
        welded, collapsed = build_mesh(vertices, mesh.faces, mesh.face_colours, what=node.name)
        flat = 0
        if welded is not None:
            faces, colours, flat = _flip_flat(welded.vertices, welded.faces, welded.face_colours)
            if flat:
                welded = build_mesh(welded.vertices, faces, colours, what=node.name)[0] if len(faces) else None
        if welded is None:
            raise ConversionError(f"{node.name + ': ' if node.name else ''}no triangle keeps an area at float32 "
                                  "precision")
        dropped += collapsed + flat
        rounded[id(mesh)] = welded
    notes = ["coordinates rounded to float32"] if moved else []
    if dropped:
        notes.append(f"{dropped} triangle{'s' if dropped > 1 else ''} without area at float32 precision")
    nodes = tuple(replace(node, mesh=None if node.mesh is None else rounded[id(node.mesh)]) for node in scene.nodes)
    return replace(scene, nodes=nodes), notes


def float32_shift(scene: Scene) -> float:
    """The farthest any vertex of ``scene`` moves, in world space, when its meshes' coordinates are rounded
    to float32, as a fraction of the diagonal of the scene's world bounding box (0 without extent).

    Each triangle's points move by at most the largest move of its corners, so this bounds the two-sided
    Hausdorff distance the rounding adds: what a float32 output adds to the error bound of its source.
    """
    moved, placed = 0.0, []
    for node, world in zip(scene.nodes, world_transforms(scene)):
        if node.mesh is None:
            continue
        v = node.mesh.vertices
        shift = (v.astype(np.float32).astype(np.float64) - v) @ world[:3, :3].T
        moved = max(moved, float(np.linalg.norm(shift, axis=1).max(initial=0.0)))
        placed.append(v @ world[:3, :3].T + world[:3, 3])
    if not placed:
        return 0.0
    points = np.concatenate(placed)
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    return moved / diagonal if diagonal > 0 else 0.0


def _flip_flat(vertices: np.ndarray, faces: np.ndarray,
               colours: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None, int]:
    """``faces`` without the triangles that have no area, and how many there were.

    A flat triangle (a, b, c) with c on its longest edge ab is taken out
    together with its neighbour (b, a, d) across that edge, which is split at
    c into (b, c, d) and (c, a, d): the surface is the same point set and a
    closed mesh stays closed (dropping the flat triangle alone would leave a
    T-junction at c). Flat triangles that share a neighbour are flipped in
    turn, one per pass. One whose edge has no single neighbour, or whose
    neighbour is flat too or would split into flat halves, is only dropped.
    """
    n = len(vertices)
    count = int(len(faces) - np.count_nonzero(with_area(vertices, faces)))
    while True:
        flat = np.flatnonzero(~with_area(vertices, faces))
        if not len(flat):
            break
        corners = vertices[faces[flat]]
        k = np.argmax(np.linalg.norm(corners[:, [1, 2, 0]] - corners, axis=2), axis=1)
        a, b, c = faces[flat][np.arange(len(flat))[:, None], (k[:, None] + np.arange(3)) % 3].T
        # Each directed edge once in a manifold: the neighbour across a->b holds b->a.
        keys = (faces * n + faces[:, [1, 2, 0]]).ravel()
        order = np.argsort(keys, kind="stable")
        want = b * n + a
        first = np.searchsorted(keys[order], want, side="left")
        unique = np.searchsorted(keys[order], want, side="right") - first == 1
        edge = order[np.minimum(first, len(keys) - 1)]
        neighbour = edge // 3
        d = faces[neighbour, (edge % 3 + 2) % 3]
        split = np.stack([np.column_stack([b, c, d]), np.column_stack([c, a, d])], axis=1)
        is_flat = np.zeros(len(faces), dtype=bool)
        is_flat[flat] = True
        ok = np.flatnonzero(unique & ~is_flat[neighbour]
                            & with_area(vertices, split.reshape(-1, 3)).reshape(-1, 2).all(axis=1))
        # A neighbour split for one flat triangle is gone for the others: they wait for the next pass.
        chosen = ok[np.unique(neighbour[ok], return_index=True)[1]]
        if not len(chosen):
            break
        drop = np.zeros(len(faces), dtype=bool)
        drop[flat[chosen]] = True
        drop[neighbour[chosen]] = True
        faces = np.concatenate([faces[~drop], split[chosen].reshape(-1, 3)])
        if colours is not None:
            colours = np.concatenate([colours[~drop], np.repeat(colours[neighbour[chosen]], 2, axis=0)])
    keep = with_area(vertices, faces)
    return faces[keep], None if colours is None else colours[keep], count


def world_transforms(scene: Scene) -> list[np.ndarray]:
    """Local-to-world 4x4 matrix of every node (parents precede children)."""
    world: list[np.ndarray] = []
    for node in scene.nodes:
        local = np.eye(4) if node.transform is None else np.asarray(node.transform, np.float64)
        world.append(local if node.parent is None else world[node.parent] @ local)
    return world


#: A Z-up scene turned Y-up (spec §10.3): (x, y, z) -> (x, z, -y), a right-handed quarter turn about
#: +x that keeps x and brings +z up to +y, as Blender's and USD's glTF exporters turn it; its transpose
#: turns a Y-up scene Z-up.
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def up_rotation(source: str, target: str) -> np.ndarray:
    """The 4x4 rotation taking a scene whose ``source`` axis points up to one whose ``target`` axis does."""
    if source == target:
        return np.eye(4)
    return Z_UP_TO_Y_UP if (source, target) == ("Z", "Y") else Z_UP_TO_Y_UP.T


def reoriented(scene: Scene, up_axis: str) -> Scene:
    """``scene`` with ``up_axis`` pointing up: its root nodes turned by :func:`up_rotation` where its own
    up axis differs. Meshes are untouched, so nodes sharing one still share it. A scene that does not
    say which way is up is taken as it is, now said to be ``up_axis`` up."""
    if scene.up_axis in (None, up_axis):
        return replace(scene, up_axis=up_axis)
    turn = up_rotation(scene.up_axis, up_axis)
    nodes = tuple(node if node.parent is not None else
                  replace(node, transform=turn if node.transform is None else turn @ node.transform)
                  for node in scene.nodes)
    return replace(scene, nodes=nodes, up_axis=up_axis)


#: Metres per unit of each unit the model knows (USD's metersPerUnit).
METERS_PER_UNIT = {
    Units.METRE: 1.0, Units.CENTIMETRE: 0.01, Units.MILLIMETRE: 0.001,
    Units.MICROMETRE: 1e-6, Units.KILOMETRE: 1000.0, Units.INCH: 0.0254,
    Units.FOOT: 0.3048,
}


def in_metres(scene: Scene) -> Scene:
    """``scene`` with its coordinates in metres: every mesh and every node's translation scaled by the
    metres per unit of its units (a uniform scale s commutes with rotations, so scaling the translations
    of all nodes and the vertices of all meshes scales the world by s). Meshes shared stay shared. A
    scene in metres, or of unspecified units, is returned as it is."""
    scale = METERS_PER_UNIT.get(scene.units, 1.0)
    if scene.units == Units.UNSPECIFIED or scale == 1.0:
        return scene
    scaled: dict[int, Mesh] = {}
    nodes = []
    for node in scene.nodes:
        mesh = node.mesh
        if mesh is not None and id(mesh) not in scaled:
            scaled[id(mesh)] = replace(mesh, vertices=mesh.vertices * scale)
        transform = None
        if node.transform is not None:
            transform = np.array(node.transform, dtype=np.float64)
            transform[:3, 3] *= scale
        nodes.append(replace(node, mesh=None if mesh is None else scaled[id(mesh)], transform=transform))
    return replace(scene, nodes=tuple(nodes), units=Units.METRE)


def instancing_note(scene: Scene, instanced: frozenset[int] = frozenset()) -> str | None:
    """For writers that store a node's mesh with the node: how many nodes share how many meshes that are
    stored more than once, and how many times the source's triangles the output holds; None if no mesh
    is. ``instanced``: the nodes whose mesh the writer stores once for all of them (USD instances)."""
    faces = {id(node.mesh): len(node.mesh.faces) for node in scene.nodes if node.mesh is not None}
    copies = Counter(id(node.mesh) for k, node in enumerate(scene.nodes)
                     if node.mesh is not None and k not in instanced)
    copies.update({id(scene.nodes[k].mesh) for k in instanced})  # the one copy the instances share
    flattened = [key for key, count in copies.items() if count > 1]
    if not flattened:
        return None
    nodes = sum(1 for node in scene.nodes if node.mesh is not None and id(node.mesh) in flattened)
    stored = sum(count * faces[key] for key, count in copies.items())
    return (f"instancing flattened ({nodes} nodes share {len(flattened)} "
            f"mesh{'es' if len(flattened) > 1 else ''}; output {stored / max(sum(faces.values()), 1):.3g}× the "
            "source's triangles)")


def transform_mesh(mesh: Mesh, matrix: np.ndarray) -> Mesh:
    """``mesh`` with ``matrix`` applied; winding flipped if the matrix mirrors.

    A mirroring transform turns counter-clockwise faces clockwise, so the
    faces are reversed to keep them counter-clockwise seen from outside.
    """
    vertices = mesh.vertices @ matrix[:3, :3].T + matrix[:3, 3]
    faces = mesh.faces[:, ::-1] if np.linalg.det(matrix[:3, :3]) < 0 else mesh.faces
    return Mesh(vertices=vertices, faces=np.ascontiguousarray(faces),
                face_colours=mesh.face_colours)


def flattened(scene: Scene) -> Scene:
    """``scene`` as one node holding :func:`flatten`'s world-space mesh."""
    return replace(scene, nodes=(Node(name="", mesh=flatten(scene)),))


def flatten(scene: Scene) -> Mesh:
    """All meshes of ``scene`` in world coordinates, concatenated into one mesh.

    Vertices are not merged across nodes: separate objects stay separate
    components. Raises :class:`ConversionError` when the scene has no mesh.
    """
    placed = [transform_mesh(node.mesh, matrix)
              for node, matrix in zip(scene.nodes, world_transforms(scene))
              if node.mesh is not None]
    if not placed:
        raise ConversionError("the scene holds no mesh")
    offsets = np.cumsum([0] + [len(m.vertices) for m in placed[:-1]])
    vertices = np.concatenate([m.vertices for m in placed])
    faces = np.concatenate([m.faces + off for m, off in zip(placed, offsets)])
    colours = None
    if any(m.face_colours is not None for m in placed):
        colours = np.concatenate([
            m.face_colours if m.face_colours is not None
            else np.broadcast_to(DEFAULT_COLOUR, (len(m.faces), 4))
            for m in placed])
    return Mesh(vertices=vertices, faces=faces, face_colours=colours)

