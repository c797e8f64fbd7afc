"""Shell walks with reflections (kind 12, spec §9.16): the prediction is the spec's formula in exact
integers, decodes alike in C and in Python, turns only within 2^18, refuses what resolves beyond 2^52;
the encoder writes it where it is smaller (a torus knot walked round its tube), as version 5.1, and
never for readers of 4.x."""

from __future__ import annotations

import io
import math
import random
from fractions import Fraction

import numpy as np
import pytest
import trimesh

import planefmt
from planefmt import codec
from planefmt.container import shellfields, shellwalk, varint
from planefmt.errors import FormatError
from planefmt.model import GroupKind
from planefmt_converters import registry

from corpus import CORPUS
from test_shell_walk import decode_body, explicit_walk, same

REFLECT = GroupKind.SHELL_WALK_REFLECT


def spec_prediction(a: list[int], b: list[int], c: list[int]) -> list[int] | None:
    """§9.16's prediction from its words, in fractions: None where the chain does not turn."""
    d1 = [y - z for y, z in zip(b, c)]
    d2 = [x - y for x, y in zip(a, b)]
    d = sum(x * x for x in d2)
    if d == 0 or max(map(abs, d1 + d2)) > 1 << 18:
        return None
    dot = sum(x * y for x, y in zip(d1, d2))
    return [a[i] + math.floor(Fraction(2 * (2 * dot * d2[i] - d * d1[i]) + d, 2 * d)) for i in range(3)]


def test_the_prediction_is_the_formula_of_the_spec_in_exact_integers():
    rng = random.Random(12)
    rows = []
    for scale in (1, 7, 1 << 10, 1 << 17, 1 << 18, (1 << 18) + 1, 1 << 40):
        for _ in range(300):
            c = [rng.randint(-(1 << 50), 1 << 50) for _ in range(3)]
            b = [x + rng.randint(-scale, scale) for x in c]
            a = [x + rng.randint(-scale, scale) for x in b]
            rows.append((a, b, c))
    rows.append(([5, 5, 5], [5, 5, 5], [1, 2, 3]))  # D = 0: no turn
    values = np.array([r for row in rows for r in (row[2], row[1], row[0])], dtype=np.int64)
    step = np.full(len(values), -1, dtype=np.int64)
    step[1::3], step[2::3] = np.arange(0, len(values), 3), np.arange(1, len(values), 3)
    # Each triple's predicted corner: a fourth row per triple whose step source is its a.
    values = np.vstack([values, np.zeros((len(rows), 3), dtype=np.int64)])
    step = np.r_[step, np.arange(2, 3 * len(rows), 3)]
    fallback = np.full((len(values), 3), -7, dtype=np.int64)
    got = shellfields.predict_reflected(values, step, fallback)[3 * len(rows):]
    turned = 0
    for (a, b, c), row in zip(rows, got.tolist()):
        want = spec_prediction(a, b, c)
        assert row == (want if want is not None else [-7, -7, -7])
        turned += want is not None
    assert 0 < turned < len(rows)


def test_a_regular_polygon_walked_round_is_predicted_exactly():
    # A square and a regular octagon whose corners are grid points: every step a chain turns is exact.
    octagon = [(2, 0), (4, 0), (6, 2), (6, 4), (4, 6), (2, 6), (0, 4), (0, 2)]
    for ring in ([(0, 0), (1, 0), (1, 1), (0, 1)] * 3, octagon * 2):
        values = np.array([(x, y, 0) for x, y in ring], dtype=np.int64)
        step = np.arange(-1, len(values) - 1)
        prediction = shellfields.predict_reflected(values, step, np.zeros_like(values))
        assert np.array_equal(prediction[3:], values[3:])


MESHES = {"torus": trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16),
          "sphere": trimesh.creation.icosphere(subdivisions=2)}


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("step", [1e-3, 2.0 ** -19])
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_c_and_python_decode_a_reflected_walk_alike(name, step, mode, monkeypatch):
    m = MESHES[name]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces), step)
    body = b"".join(shellwalk.shell_walk_fields(shell, mode, REFLECT).values())
    assert same(decode_body(body, REFLECT), shell)
    monkeypatch.setattr(shellfields, "_reflect", None)
    assert same(decode_body(body, REFLECT), shell)


def test_a_tube_walked_round_costs_less_with_reflections():
    m = MESHES["torus"]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces), 1e-4)
    coordinates = {kind: len(shellwalk.shell_walk_fields(shell, 0, kind)["coordinates"])
                   for kind in (GroupKind.SHELL_WALK, REFLECT)}
    assert coordinates[REFLECT] < 0.8 * coordinates[GroupKind.SHELL_WALK]


def _beyond_body() -> bytes:
    m = MESHES["torus"]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces), 1e-3)
    fields = shellwalk.shell_walk_fields(shell, 0, REFLECT)
    coded, _ = varint.decode(np.frombuffer(fields["coordinates"], dtype=np.uint8), 3 * len(shell.grid), "coordinates")
    residuals = varint.unzigzag(coded).reshape(3, -1)
    # Within 2^52 each, the last corner's x residual lifts it past 2^52: the resolved value is refused.
    residuals[0, -1] = (1 << 52) - 1
    return b"".join({**fields, "coordinates": varint.encode(varint.zigzag(residuals).reshape(-1))}.values())


def test_a_value_resolved_beyond_2_52_is_refused_in_c_and_in_python(monkeypatch):
    body = _beyond_body()
    with pytest.raises(FormatError) as caught:
        decode_body(body, REFLECT)
    assert caught.value.code == "BAD_GROUP_STRUCTURE"
    monkeypatch.setattr(shellfields, "_reflect", None)
    with pytest.raises(FormatError) as caught:
        decode_body(body, REFLECT)
    assert caught.value.code == "BAD_GROUP_STRUCTURE"


def _encode(path, major: int = 5) -> bytes:
    scene, _ = registry.read(path)
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=3e-5, major=major)
    return buf.getvalue()


def test_the_encoder_writes_reflections_on_a_knot_as_5_1_and_never_for_4_x():
    path = CORPUS / "nonconvex_watertight" / "quadknot.obj"
    v5, v4 = _encode(path), _encode(path, major=4)
    with planefmt.open(io.BytesIO(v5)) as r:
        assert r.header.version == (5, 1)
        kinds5 = [g.kind for g in r.part_groups()]
    with planefmt.open(io.BytesIO(v4)) as r:
        assert r.header.version[0] == 4
        kinds4 = [g.kind for g in r.part_groups()]
    assert REFLECT in kinds5 and REFLECT not in kinds4
    # The same corners either way: only the coding of the walk's coordinates differs.
    a, b = codec.decode_mesh(io.BytesIO(v5)), codec.decode_mesh(io.BytesIO(v4))
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    assert len(v5) < 0.85 * len(v4)


def test_a_file_without_reflections_stays_version_5_0():
    with planefmt.open(io.BytesIO(_encode(CORPUS / "cad" / "box.STL"))) as r:
        kinds = [g.kind for g in r.part_groups()]
        assert REFLECT not in kinds and r.header.version == (5, 0)


def _outcome(body: bytes):
    try:
        shell = decode_body(body, REFLECT)
    except FormatError as exc:
        assert exc.code in ("BAD_GROUP_STRUCTURE", "BAD_PAYLOAD")
        return exc.code
    return np.asarray(shell.grid).tobytes()


def test_damaged_bodies_are_read_or_refused_alike_in_c_and_in_python(monkeypatch):
    # Residual bytes changed at random: corners pushed past 2^52 or past their tables, or read as other
    # values, must come out the same from both loops.
    m = MESHES["torus"]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces), 2.0 ** -17)
    bodies = [b"".join(shellwalk.shell_walk_fields(shell, mode, REFLECT).values()) for mode in (0, 2)]
    rng = np.random.default_rng(12)
    damaged = []
    for body in bodies:
        for _ in range(60):
            b = bytearray(body)
            for k in rng.integers(len(b) // 2, len(b), 2):
                b[k] = int(rng.integers(256))
            damaged.append(bytes(b))
    in_c = [_outcome(b) for b in damaged]
    monkeypatch.setattr(shellfields, "_reflect", None)
    assert [_outcome(b) for b in damaged] == in_c
    assert sum(isinstance(x, str) for x in in_c) > 10 and sum(isinstance(x, bytes) for x in in_c) > 10
