"""conformance/independent/plnspec.py, a container-level reader written from spec/pln.md alone,
passes every conformance case at container level: in process, case by case (so that a failure
names its case), and a few through the runner's command-line contract (``python -m conformance
--impl``)."""

from __future__ import annotations

import importlib.util
import json
import random
import struct
import sys
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # conformance/ is a folder of the repository, not an installed package

from conformance import runner  # noqa: E402
from conformance.runner import Case, Outcome  # noqa: E402

SUITE = ROOT / "conformance"
READER = SUITE / "independent" / "plnspec.py"
CASES = runner.load_manifest()

_spec = importlib.util.spec_from_file_location("plnspec", READER)
plnspec = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(plnspec)


def in_process(path: Path) -> Outcome:
    """What ``python plnspec.py path`` answers, without starting a process."""
    try:
        result = plnspec.Reader(path.read_bytes()).read()
    except plnspec.PlnError as exc:
        return Outcome(1, {"error": exc.code}, str(exc))
    return Outcome(0, json.loads(json.dumps(result, allow_nan=False)), "")


@pytest.mark.parametrize("case", CASES, ids=[c.path for c in CASES])
def test_spec_reader_conforms_at_container_level(case: Case):
    expected = json.loads((SUITE / case.path).with_suffix(".json").read_text(encoding="utf-8"))
    assert runner.check(case, expected, in_process(SUITE / case.path), "container") is None


#: One valid and one broken case of each version, through the command line (the in-process test
#: above covers every case; the whole suite by subprocess took 162 s on two loaded cores).
BY_COMMAND = ["valid/cube_float32.pln", "valid/cube_v3.pln", "valid/shell_mixed_v3_2.pln",
              "valid/shell_tree_mixed_v3_3.pln", "invalid/xv3_shell_code_back.pln",
              "invalid/xv3_tree_third_unnamed.pln", "invalid/xcrc_and_payload.pln",
              "valid/shell_walk_sphere_v4_1.pln", "invalid/xv41_left_none.pln",
              "valid/walk_planeless_v5_0.pln", "invalid/xv50_length_not_minimal.pln"]


@pytest.mark.parametrize("path", BY_COMMAND)
def test_spec_reader_answers_through_the_runner_s_command_contract(path):
    case = next(c for c in CASES if c.path == path)
    expected = json.loads((SUITE / path).with_suffix(".json").read_text(encoding="utf-8"))
    # timeout: a hang guard far above normal (a case takes under 3 s on a loaded machine)
    got = runner.run(f"{sys.executable} {READER}", SUITE / path, timeout=120)
    assert runner.check(case, expected, got, "container") is None


def test_spec_reader_reports_no_geometry():
    # A container-level reader: the runner compares no geometry, and geometry defects pass as accepted.
    got = in_process(SUITE / "valid" / "cube_v3.pln")
    assert got.exit_code == 0 and got.result["geometry"] is None


#: The error codes of spec/pln.md §12.2 that a container reader raises.
CODES = {"BAD_SIGNATURE", "TEXT_MODE_DAMAGE", "TRUNCATED", "BAD_CHUNK_TYPE", "BAD_CHUNK_LENGTH", "CHUNK_TOO_LONG",
         "CRC_MISMATCH",
         "UNKNOWN_CRITICAL_CHUNK", "MISSING_HEADER", "DUPLICATE_HEADER", "CHUNK_ORDER", "TRAILING_DATA",
         "UNSUPPORTED_VERSION", "UNSUPPORTED_CODING", "BAD_HEADER_VALUE", "COUNT_MISMATCH", "BAD_PAYLOAD",
         "BAD_COMPRESSION", "SIZE_MISMATCH", "LIMIT_EXCEEDED", "BAD_TRIPLET", "PLANE_INDEX_MISMATCH",
         "BAD_OBJECT", "BAD_OBJECT_REFERENCE", "BAD_PLANE_REFERENCE", "GROUP_INDEX_MISMATCH",
         "UNKNOWN_GROUP_KIND", "BAD_GROUP_STRUCTURE", "BAD_COLOURS", "BAD_METADATA", "BAD_INDEX"}

VALID = [c for c in CASES if c.expected == "ok"]


def chunk_heads(data: bytes):
    """(offset, head size, payload length) of each chunk of a valid file: the first chunk's length a
    u32, every later one's a varint in a version 5 file (spec §4.1), a u32 before."""
    out, pos = [], 8
    varint = len(data) > 16 and data[16] >= 5  # PHDR's version_major
    while pos + 8 <= len(data):
        if varint and pos > 8:
            n, i = 0, 0
            while True:
                byte = data[pos + 4 + i]
                n |= (byte & 0x7F) << (7 * i)
                i += 1
                if not byte & 0x80:
                    break
            head = 4 + i
        else:
            n, head = struct.unpack_from("<I", data, pos + 4)[0], 8
        out.append((pos, head, n))
        pos += head + n + 4
    return out


def damaged(data: bytes, seed: int):
    """Deterministic damage to a valid file: truncations, and byte changes inside a chunk's payload
    with the chunk's CRC made right again, so that they reach the payload's checks."""
    rng = random.Random(seed)
    chunks = [(pos, head, n) for pos, head, n in chunk_heads(data) if n]
    for _ in range(20):
        yield data[:rng.randrange(len(data))]
    for _ in range(200):
        start, head, n = rng.choice(chunks)
        b = bytearray(data)
        for _ in range(rng.choice((1, 1, 2, 3))):
            k = start + head + rng.randrange(n)
            b[k] = rng.choice((0, 1, 0x7F, 0x80, 0xFF, b[k] ^ (1 << rng.randrange(8)), rng.randrange(256)))
        crc = zlib.crc32(bytes(b[start:start + 4] + b[start + head:start + head + n]))
        b[start + head + n:start + head + n + 4] = struct.pack("<I", crc)
        yield bytes(b)


@pytest.mark.parametrize("case", VALID, ids=[c.path for c in VALID])
def test_spec_reader_answers_every_damaged_file_with_a_result_or_a_catalogue_code(case: Case):
    data = (SUITE / case.path).read_bytes()
    for k, bad in enumerate(damaged(data, seed=len(data))):
        try:
            json.dumps(plnspec.Reader(bad).read(), allow_nan=False)
        except plnspec.PlnError as exc:
            assert exc.code in CODES, (k, exc)
