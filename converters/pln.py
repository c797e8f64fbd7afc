"""The .pln format itself, through planefmt's codec, as one more registry entry."""

from __future__ import annotations

import os
import warnings

from planefmt.errors import PlnWarning, SkippedGroupsWarning
from planefmt.model import Scene

SIGNATURE_TAIL = b"PLN"


def sniff(head: bytes, size: int) -> bool:
    """The .pln signature, also when a text-mode transfer damaged it (the reader then says so)."""
    return len(head) >= 4 and head[1:4] == SIGNATURE_TAIL and head[0] in (0x89, 0x09)


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    # The codec (scipy) loads only when a .pln is decoded or encoded, not for `pln info`.
    from planefmt import codec

    # Decoding warns of what it skipped (groups of a newer minor version's kinds): that was dropped.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlnWarning)
        scene = codec.decode_scene(path)
    return scene, [w.what if isinstance(w, SkippedGroupsWarning) else str(w) for w in _pln_warnings(caught)]


def write(scene: Scene, path: str | os.PathLike[str], *, tolerance: float = 1e-6, bits=None, coding=None,
          delta: float | None = None, tau: float | None = None, compress: bool = False,
          compact: bool = False, watertight: bool = True, scheme: str = "shell") -> list[str]:
    """Encode ``scene`` (atomically); face colours go into cOLR chunks, one colour per plane.

    Returns what the encoder gave up (its :class:`PlnWarning` lines): with
    ``watertight=False``, the closedness of solids that planes cannot close.
    """
    from planefmt import codec

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlnWarning)
        codec.encode_scene(scene, path, tolerance=tolerance, bits=bits, coding=coding, delta=delta, tau=tau,
                           compress=compress, compact=compact, watertight=watertight, scheme=scheme)
    return [str(w) for w in _pln_warnings(caught)]


def _pln_warnings(caught: list[warnings.WarningMessage]) -> list[PlnWarning]:
    """The :class:`PlnWarning` instances among ``caught``; other warnings are issued again."""
    for w in caught:
        if not issubclass(w.category, PlnWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return [w.message for w in caught if issubclass(w.category, PlnWarning)]
