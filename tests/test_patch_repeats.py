"""Spec §9.8: a face reference that appears k times yields its face k times, at any k; §12.4: those
triangles are counted before they are made. Files from fuzz/hostile.py (written from the spec through
tests/spec_files.py): the cube as a kind 3 patch with its +z face reference repeated, and a prism
whose +z face is repeated. planefmt gave the cube 14 to 28 triangles for k = 1 to 8, then 12 from
k = 9 on (past 14 references, the polytope went to Qhull, which keeps one of near-copies)."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pytest

import planefmt
from planefmt.codec import decode_mesh, decode_scene, salvage_scene, validate
from planefmt.errors import LimitError

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "fuzz"))

import hostile  # noqa: E402


@pytest.mark.parametrize("k", [1, 8, 9, 12, 40, 1000])
def test_repeated_face_once_per_reference(k: int):
    data = hostile.patch_repeated_face(k)
    mesh = decode_mesh(io.BytesIO(data))
    assert (len(mesh.vertices), len(mesh.faces)) == (8, 12 + 2 * k)
    scene = decode_scene(io.BytesIO(data))
    assert len(scene.nodes[0].mesh.faces) == 12 + 2 * k
    assert len(salvage_scene(io.BytesIO(data))[0].nodes[0].mesh.faces) == 12 + 2 * k
    assert validate(io.BytesIO(data)) == []


def test_repeated_polygon_counted_before_made():
    data = hostile.patch_repeated_polygon(40, 30)
    want = 40 * 2 + 38 * 31
    assert len(decode_mesh(io.BytesIO(data)).faces) == want
    with pytest.raises(LimitError, match=f"repeated face references make {want:,} triangles"):
        decode_mesh(io.BytesIO(data), limits=planefmt.Limits(max_triangles=want - 1))
    found = validate(io.BytesIO(data), limits=planefmt.Limits(max_triangles=want - 1))
    assert [f.code for f in found] == ["LIMIT_EXCEEDED"] and "repeated face references" in found[0].message


def test_repeated_polygon_default_limit():
    """9 M triangles from 72 kB: LIMIT_EXCEEDED with the defaults (2^22), by the count, not the memory."""
    with pytest.raises(LimitError, match="repeated face references make 9,002,998 triangles"):
        decode_mesh(io.BytesIO(hostile.patch_repeated_polygon(3000)))


@pytest.mark.parametrize("copies", [1, 12])
def test_identical_plane_under_another_index_bounds_no_face(copies: int):
    """§9.4: of planes that are one, the others are redundant: +z stored ``copies`` + 1 times in the table,
    each referenced once, is one face (planefmt gave one per copy up to 14 references; js/ one)."""
    planes = hostile.CUBE[:5] + [hostile.CUBE[4]] * copies + [hostile.CUBE[5]]
    data = hostile.cube_file([(3, hostile.body(range(len(planes))))], planes=planes)
    assert len(decode_mesh(io.BytesIO(data)).faces) == 12
