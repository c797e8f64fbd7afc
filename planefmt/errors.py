"""The exception tree and the catalogue of error codes (spec §12).

Every error the library raises for bad input is a :class:`PlnError`. Each
carries a stable ``code`` from :data:`CODES`, and where known the file name,
the chunk type and the byte offset of the chunk it concerns, so that
``str(err)`` reads ``model.pln: chunk GRUP at byte 1234: reason``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Code:
    """One catalogued finding: a stable identifier, its severity and meaning."""

    code: str
    severity: str  # "error" | "warning" | "info"
    summary: str


_CATALOGUE = [
    # framing (spec §3, §4)
    Code("BAD_SIGNATURE", "error", "the file does not start with the .pln signature"),
    Code("TEXT_MODE_DAMAGE", "error", "the signature shows line-ending or 7-bit text-mode damage"),
    Code("TRUNCATED", "error", "the file ends inside a chunk or before the end chunk"),
    Code("CRC_MISMATCH", "error", "a chunk's CRC-32 does not match its type and payload"),
    Code("BAD_CHUNK_TYPE", "error", "a chunk type tag is not four ASCII letters"),
    Code("CHUNK_TOO_LONG", "error", "a chunk length exceeds 2^31-1 or the reader's limit"),
    Code("BAD_CHUNK_LENGTH", "error", "a version 5 chunk length that is not a minimal varint"),
    Code("UNKNOWN_CRITICAL_CHUNK", "error", "a critical chunk type this reader does not know"),
    Code("UNKNOWN_ANCILLARY_CHUNK", "info", "an ancillary chunk type this reader skipped"),
    Code("CHUNK_ORDER", "error", "a chunk appears where the spec does not allow it"),
    Code("MISSING_HEADER", "error", "the first chunk is not PHDR"),
    Code("DUPLICATE_HEADER", "error", "a second PHDR chunk"),
    Code("MISSING_END", "error", "the stream ends without a PEND chunk"),
    Code("TRAILING_DATA", "error", "bytes follow the PEND chunk"),
    Code("BAD_PAYLOAD", "error", "a chunk payload does not match its declared structure"),
    # header (spec §5)
    Code("UNSUPPORTED_VERSION", "error", "the major version is not 1, 2, 3, 4 or 5"),
    Code("NEWER_MINOR_VERSION", "info", "the file has a newer minor version; unknown parts were ignored"),
    Code("UNSUPPORTED_CODING", "error", "the triplet coding is unknown or its bit widths are invalid"),
    Code("BAD_HEADER_VALUE", "error", "a header field is out of its allowed range"),
    Code("COUNT_MISMATCH", "error", "header counts disagree with the chunks present"),
    # payloads (spec §6–§10)
    Code("BAD_COMPRESSION", "error", "unknown compression method, or a corrupt deflate or Brotli stream"),
    Code("SIZE_MISMATCH", "error", "a payload's size disagrees with its declared count or raw size"),
    Code("LIMIT_EXCEEDED", "error", "a declared size exceeds the reader's configured limits"),
    Code("BAD_TRIPLET", "error", "a plane triplet is NaN, infinite or outside its range (float or quantized)"),
    Code("PLANE_INDEX_MISMATCH", "error", "a PLNS block does not continue the plane table"),
    Code("BAD_PLANE_REFERENCE", "error", "a part group references a plane not yet defined"),
    Code("BAD_OBJECT", "error", "an object record is malformed (index, parent, name or transform)"),
    Code("BAD_OBJECT_REFERENCE", "error", "a part group names an object not yet defined"),
    Code("GROUP_INDEX_MISMATCH", "error", "part groups are not numbered 0, 1, 2, ... in file order"),
    Code("UNKNOWN_GROUP_KIND", "error", "a part group kind unknown in a file of this reader's version"),
    Code("SKIPPED_GROUP_KIND", "warning", "a part group of a kind from a newer minor version was skipped"),
    Code("BAD_GROUP_STRUCTURE", "error", "cells, tree or sealed triangles of a part group are malformed"),
    Code("BAD_COLOURS", "error", "a cOLR chunk does not match its part group"),
    Code("BAD_METADATA", "error", "a mETA chunk is malformed, repeats a keyword, follows geometry or has a bad value"),
    Code("BAD_INDEX", "error", "the iNDX chunk points outside the file or at the wrong chunk"),
    # geometry (spec §11)
    Code("EMPTY_POLYTOPE", "error", "the half-spaces of a part group have an empty intersection"),
    Code("UNBOUNDED_POLYTOPE", "error", "the half-spaces of a part group do not bound a finite region"),
    Code("BAD_VERTEX", "error", "the three planes of a sealed group's vertex do not meet in one point"),
    Code("REDUNDANT_PLANE", "warning", "a plane of a convex group bounds no face"),
    Code("GEOMETRY_NOT_CHECKED", "info", "a part group of a kind this decoder cannot decode yet was not checked"),
    Code("DEGENERATE_GEOMETRY", "error", "the input geometry is degenerate (NaN, no area, no faces)"),
    Code("TOLERANCE_NOT_MET", "error", "the decoded surface is farther from the source than the tolerance"),
    # converters and CLI
    Code("UNKNOWN_FORMAT", "error", "the input format could not be detected"),
    Code("CONVERSION_FAILED", "error", "a converter could not read or write the mesh"),
    Code("OUTPUT_CONFLICT", "error", "an output would replace an input, another output or a file not named"),
    # batch conversion: limits a run puts on each input
    Code("TIMEOUT", "error", "a conversion ran longer than the time allowed per input"),
    Code("MEMORY_LIMIT", "error", "a conversion needed more memory than allowed per input"),
    Code("WORKER_LOST", "error", "the process converting an input ended before it reported"),
]

CODES: dict[str, Code] = {c.code: c for c in _CATALOGUE}


class PlnError(Exception):
    """Root of every error planefmt raises for bad input or impossible requests."""

    default_code = "BAD_PAYLOAD"

    def __init__(
        self,
        reason: str,
        *,
        code: str | None = None,
        file: str | None = None,
        chunk: str | None = None,
        offset: int | None = None,
    ) -> None:
        self.reason = reason
        self.code = code or self.default_code
        if self.code not in CODES:
            raise ValueError(f"uncatalogued error code {self.code!r}")
        self.file = file
        self.chunk = chunk
        self.offset = offset
        super().__init__(reason)

    def located(self, *, file: str | None = None, chunk: str | None = None,
                offset: int | None = None) -> "PlnError":
        """Fill in location fields that are still unknown; returns self."""
        if self.file is None:
            self.file = file
        if self.chunk is None:
            self.chunk = chunk
        if self.offset is None:
            self.offset = offset
        return self

    def __str__(self) -> str:
        parts = []
        if self.file is not None:
            parts.append(self.file)
        where = []
        if self.chunk is not None:
            where.append(f"chunk {self.chunk}")
        if self.offset is not None:
            where.append(f"at byte {self.offset}")
        if where:
            parts.append(" ".join(where))
        parts.append(self.reason)
        return ": ".join(parts)


class FormatError(PlnError):
    """The bytes do not follow the container structure of the spec."""


class TruncatedError(FormatError):
    """The data ends before a structure it started is complete."""

    default_code = "TRUNCATED"


class ChecksumError(FormatError):
    """A chunk's CRC-32 does not match."""

    default_code = "CRC_MISMATCH"


class VersionError(PlnError):
    """The file's major version (or a coding it needs) is not supported."""

    default_code = "UNSUPPORTED_VERSION"


class LimitError(PlnError):
    """A declared size or count exceeds the configured resource limits."""

    default_code = "LIMIT_EXCEEDED"


class GeometryError(PlnError):
    """Planes that do not describe a valid solid or patch, or degenerate input."""

    default_code = "DEGENERATE_GEOMETRY"


class ConversionError(PlnError):
    """A converter failed to read or write another mesh format."""

    default_code = "CONVERSION_FAILED"


class PlnWarning(UserWarning):
    """Something the encoder did that the caller allowed but may not expect (the call succeeded)."""


class SkippedGroupsWarning(PlnWarning):
    """Part groups of kinds from a newer minor version that decoding skipped, as spec §13 asks of a
    reader; ``what`` names them."""

    def __init__(self, what: str, file: str | None = None) -> None:
        super().__init__(f"{file}: {what} skipped" if file else f"{what} skipped")
        self.what = what
