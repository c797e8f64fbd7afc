"""The .pln format itself, through planefmt's codec, as one more registry entry."""

from __future__ import annotations

import os

from planefmt.model import Scene

SIGNATURE_TAIL = b"PLN"


def sniff(head: bytes, size: int) -> bool:
    """The .pln signature, also when a text-mode transfer damaged it (the reader then says so)."""
    return len(head) >= 4 and head[1:4] == SIGNATURE_TAIL and head[0] in (0x89, 0x09)


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    # The codec (scipy) loads only when a .pln is decoded or encoded, not for `pln info`.
    from planefmt import codec

    return codec.decode_scene(path), []


def write(scene: Scene, path: str | os.PathLike[str], *, tolerance: float = 1e-6, bits=None, coding=None,
          delta: float | None = None, tau: float | None = None, compress: bool = False,
          compact: bool = False) -> list[str]:
    """Encode ``scene`` (atomically); face colours go into cOLR chunks, one colour per plane."""
    from planefmt import codec

    codec.encode_scene(scene, path, tolerance=tolerance, bits=bits, coding=coding, delta=delta, tau=tau,
                       compress=compress, compact=compact)
    return []
