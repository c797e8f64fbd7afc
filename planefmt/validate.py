"""Validation of a .pln file: findings as data (code, severity, message, location).

``validate`` reads the whole file as the spec's reader must (every CRC, every
structural rule of spec §12.2) and, with ``geometry=True``, decodes every part
group so that empty and unbounded polytopes and redundant planes are found too.
A container error ends the reading (what follows cannot be trusted); geometry
errors are reported per part group and reading goes on.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import BinaryIO

from . import reader
from .chunks import Limits
from .errors import CODES, PlnError
from .model import PartGroup


@dataclass(frozen=True)
class Finding:
    """One validation finding; ``code`` is from the catalogue in ``planefmt.errors``."""

    code: str
    severity: str
    message: str
    file: str | None = None
    chunk: str | None = None
    offset: int | None = None
    group: int | None = None

    def as_dict(self) -> dict:
        return {k: v for k, v in asdict(self).items() if v is not None}


#: A geometry check: called with each part group (planes resolved) and the reader; returns
#: findings. The codec registers the decoder here so this module does not depend on it.
GroupCheck = Callable[[PartGroup, "reader.Reader"], list[Finding]]
GROUP_CHECKS: list[GroupCheck] = []


def validate(source: str | os.PathLike | BinaryIO, *, geometry: bool = True,
             limits: Limits | None = None) -> list[Finding]:
    """All findings for ``source``; an empty list means a conforming file."""
    if geometry:
        # The codec registers its decoder in GROUP_CHECKS when imported; it imports this module.
        from . import codec  # noqa: F401
    findings: list[Finding] = []
    name = None
    try:
        with reader.open(source, limits=limits) as r:
            name = r.name
            for group in r.part_groups():
                if geometry:
                    for check in GROUP_CHECKS:
                        findings.extend(check(group, r))
            findings.extend(Finding(code, CODES[code].severity, message, file=name) for code, message in r.findings)
    except PlnError as exc:
        findings.append(Finding(exc.code, CODES[exc.code].severity, exc.reason, file=exc.file or name,
                                chunk=exc.chunk, offset=exc.offset))
    return findings


def has_errors(findings: list[Finding]) -> bool:
    return any(f.severity == "error" for f in findings)
