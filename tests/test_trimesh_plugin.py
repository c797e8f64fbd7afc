"""trimesh integration: importing planefmt_converters.trimesh_plugin registers "pln" with trimesh."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

import planefmt_converters.trimesh_plugin  # noqa: F401  (registers the loader and exporter)
from planefmt.geometry.hausdorff import closest_distance  # noqa: I001  (after the plugin on purpose: it is what is tested)


def test_trimesh_exports_and_loads_pln(tmp_path: Path):
    mesh = trimesh.creation.icosphere(subdivisions=1, radius=2.0)
    path = tmp_path / "ico.pln"
    mesh.export(path)
    with open(path, "rb") as f:
        assert f.read(4) == b"\x89PLN"
    scene = trimesh.load(path)
    assert isinstance(scene, trimesh.Scene) and len(scene.geometry) == 1
    back = trimesh.load(path, force="mesh")
    assert back.is_watertight and back.is_winding_consistent and back.volume > 0
    assert abs(back.volume - mesh.volume) <= 1e-6 * mesh.volume
    # Quantized planes may split a 5-plane vertex into a tiny cluster, but never beyond the tolerance.
    diag = float(np.linalg.norm(mesh.extents))
    d, _ = closest_distance(np.asarray(back.vertices), np.asarray(mesh.vertices), np.asarray(mesh.faces))
    assert d.max() <= 1e-6 * diag
