"""Validation of a .pln file's container: findings as data (code, severity, message, location).

``validate`` reads the whole file as the spec's reader must (every CRC, every
structural rule of spec §12.2) and runs the checks it is given on each part
group: the geometry checks live with the decoders
(:func:`planefmt.codec.validate`), which the container does not import. A
container error ends the reading (what follows cannot be trusted); a check's
findings are reported per part group and reading goes on.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import BinaryIO

from ..errors import CODES, PlnError
from ..model import PartGroup
from . import reader
from .chunks import Limits


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


#: A check of one part group: called with each part group (planes resolved) and the reader;
#: returns findings.
GroupCheck = Callable[[PartGroup, "reader.Reader"], list[Finding]]


def validate(source: str | os.PathLike | BinaryIO, *, checks: Sequence[GroupCheck] = (),
             limits: Limits | None = None) -> list[Finding]:
    """All container findings for ``source``, and those of ``checks`` on each part group; an empty
    list means a conforming container."""
    findings: list[Finding] = []
    name = None
    try:
        with reader.open(source, limits=limits) as r:
            name = r.name
            for group in r.part_groups():
                for check in checks:
                    findings.extend(check(group, r))
            findings.extend(Finding(code, CODES[code].severity, message, file=name) for code, message in r.findings)
    except PlnError as exc:
        findings.append(Finding(exc.code, CODES[exc.code].severity, exc.reason, file=exc.file or name,
                                chunk=exc.chunk, offset=exc.offset))
    return findings


def has_errors(findings: list[Finding]) -> bool:
    return any(f.severity == "error" for f in findings)
