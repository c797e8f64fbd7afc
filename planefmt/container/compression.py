"""Payload compression (spec §6): deflate and Brotli on writing, and on reading a stored payload back to
exactly its declared raw size, held once and checked against the reader's limits (spec §12.4)."""

from __future__ import annotations

import hashlib
import zlib

import brotli

from . import schema
from .chunks import Limits
from .recent import Recent
from ..errors import FormatError, LimitError

#: Deflate level of shell tree bodies (spec 3.3 §8.10): level 9's longer match search gains 1% on their
#: small-alphabet links and codes at 14 times the time (smooth_dense/bun_zipper.ply at draco-14's
#: error: 132.1 kB in 1.9 s, against 133.5 kB in 0.14 s at level 6); every other payload is deflated at 9.
SHELL_TREE_LEVEL = 6


#: Brotli-compressed payloads packed lately, by digest and arguments: an encode writes the same segment
#: several times (a candidate sized in the trials, sized again among the closest, then written), and
#: Brotli's densest quality is most of an encode's time (kuka_kr10r1420_link_4.stl at 1e-6: 3 of its 11
#: segment compressions were repeats of earlier ones).
_PACKED: Recent[tuple[int, bytes]] = Recent(32)


#: Smallest payload whose size is estimated (a quality given to :func:`pack`): under it, the written size
#: costs little (Brotli's quality 11 took 1.4-2.1 ms per raw kB here) and the estimate errs more; estimated, the
#: 2.4 kB file of kuka_kr10r1100sixx_link_6.stl at Draco-14's error came out 1.7 % larger (bench corpus).
ESTIMATED_MIN_BYTES = 16 * 1024


def forget() -> None:
    """Drop the payloads kept from earlier packs (an encode starts cold, so a repeated one costs the same)."""
    _PACKED.clear()


def pack(data: bytes, compress: bool, level: int = 9, brotli_allowed: bool = False,
         quality: int | None = None) -> tuple[int, bytes]:
    """(compression method, stored bytes): deflate at ``level``, or Brotli where ``brotli_allowed``
    (version 4), whichever is smallest, and only where that saves bytes and stays within the ratio
    every reader accepts (spec §6). ``quality``: Brotli's, if not the writer's
    (:func:`schema.brotli_quality`), for an estimate of the size: deflate is then not tried. Payloads
    under :data:`ESTIMATED_MIN_BYTES` are packed as written whatever ``quality`` says."""
    if quality is not None and len(data) < ESTIMATED_MIN_BYTES:
        quality = None
    if not (compress and brotli_allowed):
        return _pack(data, compress, level, brotli_allowed, quality)
    return _PACKED.get((hashlib.blake2b(data, digest_size=16).digest(), len(data), level, quality),
                       lambda: _pack(data, compress, level, brotli_allowed, quality))


def _pack(data: bytes, compress: bool, level: int, brotli_allowed: bool, quality: int | None) -> tuple[int, bytes]:
    best = (schema.COMPRESSION_NONE, data)
    if compress:
        # An estimate (a quality given) is Brotli's alone: deflate at level 9 took four times as long as
        # Brotli's quality 5 on the encoder's trial segments and came under it on 3 of 129 (nine bench-corpus
        # meshes at three tolerances).
        estimate = brotli_allowed and quality is not None
        candidates = [] if estimate else [(schema.COMPRESSION_ZLIB, zlib.compress(data, level))]
        if brotli_allowed:
            candidates.append((schema.COMPRESSION_BROTLI, brotli.compress(
                data, quality=schema.brotli_quality(len(data)) if quality is None else quality)))
        for method, stored in candidates:
            if len(stored) < len(best[1]) and len(data) <= schema.MAX_WRITTEN_RATIO * len(stored):
                best = (method, stored)
    return best


#: Output of one decompression step (spec §6): a payload is decompressed in pieces of at most this many
#: bytes into a buffer of its raw size, so that it is held once, not once in pieces and once joined; and
#: its stored bytes are fed in pieces of :data:`UNPACK_INPUT`, so that what a decompressor copies of the
#: input it has not consumed stays small.
UNPACK_STEP = 1 << 20
UNPACK_INPUT = 1 << 16


def unpack(method: int, stored: bytes, raw_size: int, limits: Limits, major: int = 3) -> bytes | bytearray:
    """The raw bytes of a stored payload, checked in the order of spec/pln.md §6, with the decompression-bomb
    caps of spec §12.4: the method (a defect of the file) before the reader's own limits. Brotli
    (method 2) exists from version 4 on."""
    methods = (schema.COMPRESSION_NONE, schema.COMPRESSION_ZLIB) + ((schema.COMPRESSION_BROTLI,) if major >= 4 else ())
    if method not in methods:
        raise FormatError(f"unknown compression method {method} in a version {major} file", code="BAD_COMPRESSION")
    if raw_size > limits.max_raw_size:
        raise LimitError(f"declared raw size {raw_size} exceeds the limit {limits.max_raw_size}")
    if method == schema.COMPRESSION_NONE:
        if len(stored) != raw_size:
            raise FormatError(f"raw size {raw_size} != stored size {len(stored)}", code="SIZE_MISMATCH")
        return stored
    if raw_size > max(len(stored), 1) * limits.max_compression_ratio:
        raise LimitError(f"declared raw size {raw_size} is over {limits.max_compression_ratio}x "
                         f"the {len(stored)} stored bytes")
    if method == schema.COMPRESSION_BROTLI:
        return _unbrotli(stored, raw_size)
    return _inflate(stored, raw_size)


class _Output:
    """A payload's raw bytes as they are decompressed, into one buffer of the declared raw size."""

    def __init__(self, raw_size: int, stream: str) -> None:
        self.raw = bytearray(raw_size)
        self.made = 0
        self.stream = stream

    def step(self) -> int:
        """The most output to ask of the next step: a piece, or one byte past raw size to see it passed."""
        return min(UNPACK_STEP, len(self.raw) + 1 - self.made)

    def add(self, piece: bytes) -> None:
        end = self.made + len(piece)
        if end > len(self.raw):
            raise FormatError(f"{self.stream} stream decompresses to more than {len(self.raw)} bytes",
                              code="SIZE_MISMATCH")
        self.raw[self.made:end] = piece
        self.made = end


def _inflate(stored: bytes, raw_size: int) -> bytearray:
    """A zlib stream (spec §6, method 1) that must inflate to exactly ``raw_size`` bytes and end with the
    last stored byte; at most raw size + 1 bytes are inflated."""
    d = zlib.decompressobj()
    out = _Output(raw_size, "deflate")
    view, fed, pending = memoryview(stored), 0, b""
    try:
        while not d.eof:
            if not pending and fed < len(view):
                pending, fed = view[fed:fed + UNPACK_INPUT], min(fed + UNPACK_INPUT, len(view))
            # Without input left, the inflater may still hold output (a match cut short by the step).
            piece = d.decompress(pending, out.step())
            out.add(piece)
            if not (piece or pending):
                break  # no input and no output: the stored bytes end inside the stream
            pending = d.unconsumed_tail
    except zlib.error as exc:
        raise FormatError(f"corrupt deflate stream ({exc})", code="BAD_COMPRESSION") from None
    if out.made != raw_size or not d.eof or d.unconsumed_tail or d.unused_data or fed < len(view):
        raise FormatError(f"deflate stream does not inflate to exactly {raw_size} bytes",
                          code="SIZE_MISMATCH")
    return out.raw


def _unbrotli(stored: bytes, raw_size: int) -> bytearray:
    """A Brotli stream (spec §6, method 2) that must decompress to exactly ``raw_size`` bytes and end
    with the last stored byte. Each step's output is capped (the decoder stops within a block of its own,
    about 32 KiB, past the cap), the last at raw size + 1: a stream that would decompress to more is
    refused before it does, whatever the ratio of its meta-blocks."""
    d = brotli.Decompressor()
    out = _Output(raw_size, "Brotli")
    view, fed = memoryview(stored), 0
    try:
        while not d.is_finished():
            piece = b""
            # Input only when the decoder takes it; without input left it may still hold output (it
            # can say it takes input while it does: measured with brotli 1.2.1).
            if d.can_accept_more_data() and fed < len(view):
                piece, fed = view[fed:fed + UNPACK_INPUT], min(fed + UNPACK_INPUT, len(view))
            got = d.process(piece, output_buffer_limit=out.step())
            out.add(got)
            if not (got or piece):
                break  # no input and no output: the stored bytes end inside the stream
    except brotli.error as exc:
        raise FormatError(f"corrupt Brotli stream, or bytes after its end ({exc})", code="BAD_COMPRESSION") from None
    if d.is_finished() and fed < len(view):
        raise FormatError(f"{len(view) - fed} stored bytes after the Brotli stream", code="BAD_COMPRESSION")
    if not d.is_finished() or out.made != raw_size:
        raise FormatError(f"Brotli stream does not decompress to exactly {raw_size} bytes", code="SIZE_MISMATCH")
    return out.raw
