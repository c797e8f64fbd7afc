"""Shell walks stepping from the later gate corner (kind 13, spec §9.17): the predictor is the later-named
of the naming triangle's first two corners, decoded alike in C and in Python, in every mode; the rule
matters (the golden file read with kind 9's predictor is another surface); the encoder writes kind 13
where it is smaller (a CAD part), as version 5.2, and never for readers of 4.x."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
import trimesh

import planefmt
from planefmt import codec
from planefmt.container import schema, shellfields, shellwalk
from planefmt.container.shellfields import code_stream
from planefmt.errors import FormatError
from planefmt.model import GroupKind
from planefmt_converters import registry

from conformance.cases_valid import _explicit_walk
from corpus import CORPUS
from test_shell_walk import decode_body, same

LATER = GroupKind.SHELL_WALK_LATER
GOLDEN = Path(__file__).resolve().parent.parent / "conformance" / "valid"

MESHES = {"sphere": trimesh.creation.icosphere(subdivisions=2),
          "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)}


def walked(name: str, step: float = 1e-3):
    """``MESHES[name]`` as a walk of explicit corners that crosses each triangle's edge 2 before its edge 1
    (conformance's): a gate's later-named corner is then mostly not its first. planefmt's own walk of
    these meshes names i0 later nearly always; its CAD walks (planes left for later) do not."""
    return _explicit_walk(MESHES[name], True, 1.0 / step)


def _predictors(shell) -> np.ndarray:
    """§9.17's step source of each explicit corner from its words: scan the triangles for the attached one
    whose code named the corner anew, take the larger of its first two corners where explicit."""
    tri = np.asarray(shell.facets, dtype=np.int64)[:, 1:]
    links = np.asarray(shell.links, dtype=np.int64)
    explicit = np.asarray(shell.explicit, dtype=bool)
    out, named, previous = [], 0, -1
    for j, (a, b, c) in enumerate(tri.tolist()):
        corners = (a, b, c) if links[j] == 0 else (c,)
        for k in corners:
            if k != named:
                continue
            named += 1
            later = max(a, b)
            out.append(later if links[j] != 0 and explicit[later] else previous)
            previous = k if explicit[k] else previous
    return np.array(out)


@pytest.mark.parametrize("name", sorted(MESHES))
def test_the_predictor_is_the_later_gate_corner(name):
    shell = walked(name)
    tri = np.asarray(shell.facets, dtype=np.int64)[:, 1:]
    links = np.asarray(shell.links, dtype=np.int64)
    explicit = np.asarray(shell.explicit, dtype=bool)
    _, new, _ = code_stream(tri, links == 0)
    per = np.where(links == 0, 3, 1)
    later = shellfields._tree_predictors(links, tri, explicit, per, new, False, True)[:, 0]
    first = shellfields._tree_predictors(links, tri, explicit, per, new, False, False)[:, 0]
    assert np.array_equal(later, _predictors(shell))
    # On these walks the later-named gate corner is another corner than i0 for most corners.
    assert np.mean(later != first) > 0.5


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_c_and_python_decode_a_later_walk_alike(name, mode, monkeypatch):
    shell = walked(name)
    body = b"".join(shellwalk.shell_walk_fields(shell, mode, LATER).values())
    assert same(decode_body(body, LATER), shell)
    monkeypatch.setattr(shellfields, "_resolve_forward", None)
    assert same(decode_body(body, LATER), shell)
    # In modes 0 and 2 the same body read by kind 9's rule is another shell, or refused (an index past
    # its table); in modes 1 and 3 parallelograms predict every corner of these all-explicit walks alike.
    if mode & shellwalk.MODE_PARALLELOGRAM:
        return
    with pytest.raises(AssertionError):
        try:
            assert same(decode_body(body, GroupKind.SHELL_WALK), shell)
        except FormatError:
            raise AssertionError from None


def test_the_golden_file_read_by_kind_9s_rule_is_another_surface():
    data = (GOLDEN / "shell_walk_later_values_v5_2.pln").read_bytes()
    with planefmt.open(io.BytesIO(data)) as r:
        (group,) = list(r.part_groups())
        assert r.header.version == (5, 2) and group.kind == LATER
    mesh = codec.decode_mesh(io.BytesIO(data))
    body = b"".join(shellwalk.shell_walk_fields(group.shell, 0, LATER).values())
    as_nine = decode_body(body, GroupKind.SHELL_WALK)
    assert not np.array_equal(np.asarray(as_nine.grid), np.asarray(group.shell.grid))
    assert len(mesh.faces) == 80 and len(mesh.vertices) == 42


def _encode(path, major: int = 5) -> bytes:
    scene, _ = registry.read(path)
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=3.3e-5, major=major)
    return buf.getvalue()


def test_the_encoder_writes_later_steps_on_a_cad_part_as_5_2_and_never_for_4_x():
    path = CORPUS / "cad" / "ADIS16480.STL"
    v5, v4 = _encode(path), _encode(path, major=4)
    with planefmt.open(io.BytesIO(v5)) as r:
        assert r.header.version == (5, 2)
        kinds5 = [g.kind for g in r.part_groups()]
    with planefmt.open(io.BytesIO(v4)) as r:
        assert r.header.version[0] == 4
        kinds4 = [g.kind for g in r.part_groups()]
    assert LATER in kinds5 and LATER not in kinds4
    a, b = codec.decode_mesh(io.BytesIO(v5)), codec.decode_mesh(io.BytesIO(v4))
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    # 4,016 bytes against 4,179 (kind 9) when measured; major 4 also pays f64 grids and u32 lengths.
    assert len(v5) < 0.97 * len(v4)


def test_mode_bits_are_those_of_kind_9_and_the_encoder_tries_those_without_parallelograms():
    assert schema.SHELL_WALK_MODES == 0b11
    assert {m for k, m in shellwalk.codings((LATER,))} == {0, 2}
    assert {m for k, m in shellwalk.codings((LATER,), 3)} == {3}
