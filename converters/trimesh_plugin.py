"""trimesh integration: ``trimesh.load("x.pln")`` and ``mesh.export("x.pln")``.

trimesh has no plugin entry points; it dispatches on two module-level tables,
``trimesh.exchange.load.mesh_loaders`` and
``trimesh.exchange.export._mesh_exporters``. Importing this module adds
``pln`` to both (and :func:`register` does it again if trimesh was reloaded)::

    import planefmt_converters.trimesh_plugin  # noqa: F401  registers "pln"
    scene = trimesh.load("model.pln")          # a Scene: one node per .pln object
    trimesh.load("part.pln", force="mesh")     # or one Trimesh
    mesh.export("part.pln")                    # encodes losslessly (tolerance 1e-6)

Loading keeps object names, the hierarchy and each object's transform.
"""

from __future__ import annotations

import io

import numpy as np

from planefmt import codec
from planefmt.model import Mesh, Node, Scene

BASE_FRAME = "world"


def load_pln(file_obj, file_type=None, resolver=None, metadata=None, **kwargs) -> dict:
    """trimesh loader: a .pln stream -> the keyword arguments of a trimesh Scene."""
    scene = codec.decode_scene(file_obj)
    names: list[str] = []
    taken = {BASE_FRAME}
    for node in scene.nodes:
        name, k = node.name or "object", 1
        while name in taken:
            name, k = f"{node.name or 'object'}_{k}", k + 1
        taken.add(name)
        names.append(name)
    geometry, graph = {}, []
    for node, name in zip(scene.nodes, names):
        edge = {"frame_from": BASE_FRAME if node.parent is None else names[node.parent], "frame_to": name,
                "matrix": np.eye(4) if node.transform is None else node.transform}
        if node.mesh is not None:
            geometry[name] = {"vertices": node.mesh.vertices, "faces": node.mesh.faces, "process": False}
            edge["geometry"] = name
        graph.append(edge)
    return {"class": "Scene", "geometry": geometry, "graph": graph, "base_frame": BASE_FRAME}


def export_pln(mesh, tolerance: float = 1e-6, **kwargs) -> bytes:
    """trimesh exporter: a Trimesh -> .pln bytes (lossless within ``tolerance`` of the diagonal)."""
    scene = Scene(nodes=(Node(name=mesh.metadata.get("name", "mesh") if hasattr(mesh, "metadata") else "mesh",
                              mesh=Mesh(np.asarray(mesh.vertices, dtype=np.float64),
                                        np.asarray(mesh.faces, dtype=np.int64))),))
    sink = io.BytesIO()
    codec.encode_scene(scene, sink, tolerance=tolerance, **kwargs)
    return sink.getvalue()


def register() -> None:
    """Add ``pln`` to trimesh's loader and exporter tables."""
    from trimesh.exchange import export, load

    load.mesh_loaders["pln"] = load_pln
    export._mesh_exporters["pln"] = export_pln


register()
