"""Prototype, not wired into the writer: an adaptive binary range coder (LZMA's range coder: 32-bit
range, carry by a cached byte; its probabilities, 12-bit, from each context's counts of zeros and ones
as Krichevsky and Trofimov estimate them, both halved at 1,024, instead of LZMA's shifts, which learn
sparse contexts worse: 2,125 B against 2,072 without contexts on kuka_kr10r1100sixx_link_6.stl) for a
shell walk's integer
residuals, to learn whether the code lengths ``bench/corner_levers.py`` estimates are bytes a real
coder writes, and what Brotli-11 writes for the same residuals.

The binarization is ``corner_levers.adaptive_bits``': per residual, its magnitude's bit length b in
unary ("b > j" for j = 0, 1, ..., each an adaptive bit of its context and j), the bit below the leading
one adaptive per (context, b), the sign and the other bits direct. Residuals are coded corner by corner,
x, y, z in turn; the context of an axis is ``corner_levers.prev_contexts``' (the bit length, clipped at
12, of the corner's earlier axes' largest residual, for x the previous corner's), or 0 for none.
Integer arithmetic only, so a Python, C or JavaScript reader (32-bit unsigned operations) decodes the
same bits. Decoding is a loop over bits: in a reader it would be C, as the walk is.

Usage: ``python bench/corner_coder.py [paths relative to the bench corpus]``: per mesh, its walks'
residuals as the writer codes them (Brotli-11 of the tables and coordinates fields), this coder's bytes
without and with contexts (each decoded again and checked), and the model's estimate.
"""

from __future__ import annotations

import io
import json
import os
import sys

import brotli
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import corner_levers as cl  # noqa: E402

#: Probability precision; counts are halved when their sum reaches LIMIT (the model keeps adapting).
BITS, LIMIT = 12, 1024
TOP = 1 << 24
#: Unary decisions of a bit length: at most 53 (a residual is within 2^52).
LENGTHS = 54


class Encoder:
    """LZMA's range encoder."""

    def __init__(self) -> None:
        self.low, self.range, self.cache, self.pending = 0, 0xFFFFFFFF, 0, 1
        self.out = bytearray()

    def _shift(self) -> None:
        if self.low < 0xFF000000 or self.low > 0xFFFFFFFF:
            carry = self.low >> 32
            byte = self.cache
            while self.pending:
                self.out.append((byte + carry) & 0xFF)
                byte = 0xFF
                self.pending -= 1
            self.cache = (self.low >> 24) & 0xFF
        self.pending += 1
        self.low = (self.low << 8) & 0xFFFFFFFF

    def bit(self, probs: list[int], i: int, bit: int) -> None:
        bound = (self.range >> BITS) * _p0(probs, i)
        if bit:
            self.low += bound
            self.range -= bound
        else:
            self.range = bound
        _count(probs, i, bit)
        while self.range < TOP:
            self.range = (self.range << 8) & 0xFFFFFFFF
            self._shift()

    def direct(self, value: int, count: int) -> None:
        for k in range(count - 1, -1, -1):
            self.range >>= 1
            if (value >> k) & 1:
                self.low += self.range
            while self.range < TOP:
                self.range = (self.range << 8) & 0xFFFFFFFF
                self._shift()

    def finish(self) -> bytes:
        for _ in range(5):
            self._shift()
        return bytes(self.out)


class Decoder:
    """LZMA's range decoder over ``data``; reading past its end reads zeros (a reader would stop
    with an error there)."""

    def __init__(self, data: bytes) -> None:
        self.data, self.at = data, 5
        self.range, self.code = 0xFFFFFFFF, int.from_bytes(data[1:5], "big")

    def _next(self) -> int:
        b = self.data[self.at] if self.at < len(self.data) else 0
        self.at += 1
        return b

    def bit(self, probs: list[int], i: int) -> int:
        bound = (self.range >> BITS) * _p0(probs, i)
        if self.code < bound:
            self.range = bound
            out = 0
        else:
            self.code -= bound
            self.range -= bound
            out = 1
        _count(probs, i, out)
        while self.range < TOP:
            self.range = (self.range << 8) & 0xFFFFFFFF
            self.code = ((self.code << 8) | self._next()) & 0xFFFFFFFF
        return out

    def direct(self, count: int) -> int:
        value = 0
        for _ in range(count):
            self.range >>= 1
            bit = int(self.code >= self.range)
            self.code -= self.range * bit
            value = (value << 1) | bit
            while self.range < TOP:
                self.range = (self.range << 8) & 0xFFFFFFFF
                self.code = ((self.code << 8) | self._next()) & 0xFFFFFFFF
        return value


def _p0(counts: list[int], i: int) -> int:
    """The 12-bit probability of a 0 of context ``i`` (counts of zeros at 2i, of ones at 2i + 1): the
    Krichevsky-Trofimov estimate (n0 + 1/2) / (n + 1), kept within 1 and 4095."""
    n0, n1 = counts[2 * i], counts[2 * i + 1]
    return min(max(((2 * n0 + 1) << BITS) // (2 * (n0 + n1) + 2), 1), (1 << BITS) - 1)


def _count(counts: list[int], i: int, bit: int) -> None:
    counts[2 * i + bit] += 1
    if counts[2 * i] + counts[2 * i + 1] >= LIMIT:
        counts[2 * i] = (counts[2 * i] + 1) >> 1
        counts[2 * i + 1] = (counts[2 * i + 1] + 1) >> 1


def _contexts(levels: int) -> tuple[list[int], list[int]]:
    return [0] * (2 * levels * 3 * LENGTHS), [0] * (2 * levels * 3 * LENGTHS)


def encode(residuals: np.ndarray, contexts: bool = True) -> bytes:
    """``residuals`` (E, 3) integers within 2^52, range-coded."""
    levels = cl.CLIP + 1
    unary, top = _contexts(levels)
    enc = Encoder()
    ctx = cl.prev_contexts(residuals) if contexts else np.zeros(residuals.shape, dtype=np.int64)
    for row, crow in zip(residuals.tolist(), ctx.tolist()):
        for axis in range(3):
            r, c = row[axis], crow[axis] * 3 + axis
            m = abs(r)
            b = m.bit_length()
            base = c * LENGTHS
            for j in range(min(b + 1, LENGTHS - 1)):
                enc.bit(unary, base + j, int(j < b))
            if b:
                enc.direct(int(r < 0), 1)
            if b >= 2:
                enc.bit(top, base + b, (m >> (b - 2)) & 1)
                enc.direct(m & ((1 << (b - 2)) - 1), b - 2)
    return enc.finish()


def decode(data: bytes, count: int, contexts: bool = True) -> np.ndarray:
    """The ``count`` rows of residuals :func:`encode` coded in ``data``."""
    levels = cl.CLIP + 1
    unary, top = _contexts(levels)
    dec = Decoder(data)
    out = np.zeros((count, 3), dtype=np.int64)
    rows = out.tolist()
    previous = 0
    for k in range(count):
        row = rows[k]
        largest = 0
        for axis in range(3):
            level = previous if axis == 0 else largest
            c = (min(level, cl.CLIP) if contexts else 0) * 3 + axis
            base = c * LENGTHS
            b = 0
            while b < LENGTHS - 1 and dec.bit(unary, base + b):
                b += 1
            m, negative = 0, 0
            if b:
                negative = dec.direct(1)
                m = 1
            if b >= 2:
                m = (m << 1) | dec.bit(top, base + b)
                m = (m << (b - 2)) | dec.direct(b - 2)
            row[axis] = -m if negative else m
            largest = max(largest, min(b, cl.CLIP))
        previous = largest
    return np.array(rows, dtype=np.int64).reshape(-1, 3)


def main(argv: list[str]) -> int:
    import planefmt
    from compare import load
    from planefmt.container import shellwalk

    corpus = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "bench-corpus")
    cache = json.load(open(os.path.join(os.path.dirname(__file__), "draco-errors.json")))
    for rel in argv:
        scene, _, _ = load(os.path.join(corpus, rel))
        data, seen = cl._encode_with_sources(scene, max(cache[f"{rel}@14"]["error"], 1e-12))
        with planefmt.open(io.BytesIO(data)) as r:
            groups = [g for g in r.part_groups() if g.kind in shellwalk.WALK_KINDS and np.asarray(g.shell.explicit).any()]
        totals = dict(brotli=0, flat=0, ctx=0, model_flat=0.0, model_ctx=0.0, E=0)
        for g in groups:
            src = cl._sources(g.shell, seen)
            w = cl.Walk(g.kind, g.shell, src if src is not None else np.zeros((len(g.shell.explicit), 3)))
            res, _ = w.residuals(w.mode)
            totals["E"] += len(res)
            totals["brotli"] += len(brotli.compress(w.fields["tables"] + w.fields["coordinates"], quality=11))
            for name, on in (("flat", False), ("ctx", True)):
                coded = encode(res, on)
                if not np.array_equal(decode(coded, len(res), on), res):
                    raise RuntimeError(f"{rel}: range-coded residuals do not decode back")
                totals[name] += len(coded) + (len(w.fields["tables"]) if w.mode & shellwalk.MODE_TABLES else 0)
            ax = np.arange(3)[None, :]
            tables = len(w.fields["tables"]) if w.mode & shellwalk.MODE_TABLES else 0
            totals["model_flat"] += cl.adaptive_bits(res, np.zeros(res.shape, dtype=np.int64) + ax) / 8.0 + tables
            totals["model_ctx"] += cl.adaptive_bits(res, cl.prev_contexts(res) * 3 + ax) / 8.0 + tables
        # The coder's and the model's bytes both hold a mode's tables as the writer stores them (raw varints).
        print(f"{rel}: {totals['E']} corners; Brotli-11 {totals['brotli']} B; range coder {totals['flat']} B, "
              f"with contexts {totals['ctx']} B; model estimate "
              f"{totals['model_flat']:.0f} B, with contexts {totals['model_ctx']:.0f} B", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
