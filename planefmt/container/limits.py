"""The reader's resource caps (spec §12.4), in a module of their own: the command line's parsers state
the defaults without importing the framing's construct."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Limits:
    """Resource caps of a reader (spec §12.4). Like Pillow's ``MAX_IMAGE_PIXELS``, the defaults keep
    one decode within a few hundred MB; a caller raises them for larger meshes
    (``Limits(max_triangles=50_000_000)``).

    ``max_triangles`` and ``max_vertices`` bound the output of a whole decode: every group of every
    object, a copy (kind 11) counting its source's again.
    """

    max_chunk_length: int = 256 << 20
    max_raw_size: int = 256 << 20  # uncompressed size of one payload
    max_compression_ratio: int = 1100  # deflate's own ceiling is about 1032
    max_planes: int = 1 << 22
    max_refs_per_group: int = 1 << 24
    max_objects: int = 1 << 24
    max_triangles: int = 1 << 22
    max_vertices: int = 1 << 22
