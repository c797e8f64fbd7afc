"""The decode budget (spec §12.4): the triangles and vertices one decode of a file may produce.

A group that declares its counts (sealed, shells, shell trees and walks) is charged when its counts
are read, before anything of their size is allocated; any other group once decoded. A copy is
charged its source's counts again.
"""

from __future__ import annotations

from collections.abc import Callable

from ..errors import LimitError
from .chunks import Limits

#: What a reader's kind decoders call with a group's declared counts: ``charge(vertices=V, triangles=T)``.
Charge = Callable[..., None]


class Budget:
    """The running totals of one decode against ``limits.max_vertices`` and ``limits.max_triangles``."""

    def __init__(self, limits: Limits) -> None:
        self.limits = limits
        self.vertices = 0
        self.triangles = 0
        #: ``(vertices, triangles)`` of each group charged once decoded, for the copies that name it.
        self.decoded: dict[int, tuple[int, int]] = {}

    def charge(self, group: int, *, vertices: int = 0, triangles: int = 0) -> None:
        """Add group ``group``'s output, or raise ``LimitError`` (vertices checked first) without adding it."""
        for what, have, more, limit, option in (
                ("vertices", self.vertices, vertices, self.limits.max_vertices, "max_vertices"),
                ("triangles", self.triangles, triangles, self.limits.max_triangles, "max_triangles")):
            if have + more > limit:
                flag = option.replace("_", "-")
                raise LimitError(f"part group {group}: its {more:,} {what} bring the file's output to "
                                 f"{have + more:,}, above this reader's limit of {limit:,} {what} (raise it with "
                                 f"Limits({option}=...) or pln --{flag})")
        self.vertices += vertices
        self.triangles += triangles

    @property
    def triangles_left(self) -> int:
        """What the decode may still produce: a decoder whose output outgrows its body stops at it."""
        return self.limits.max_triangles - self.triangles

    def charge_decoded(self, group, vertices: int, triangles: int) -> None:
        """Charge a decoded ``group`` (a ``PartGroup``) whose kind declares no counts (the reader charged
        those that do); a copy's source's counts are remembered for the copies that follow."""
        if declared(group) is not None:
            return
        if group.source is None:
            self.decoded[group.index] = (vertices, triangles)
        self.charge(group.index, vertices=vertices, triangles=triangles)

    def of(self, group: int) -> Charge:
        """``charge`` bound to ``group``, for a kind decoder that knows no group index."""
        return lambda *, vertices=0, triangles=0: self.charge(group, vertices=vertices, triangles=triangles)


def declared(group) -> tuple[int, int] | None:
    """``(vertices, triangles)`` a sealed or shell ``group`` (a ``PartGroup``) declares, None for a kind
    whose output is known only once decoded."""
    if group.shell is not None:
        return len(group.shell.explicit), len(group.shell.facets)
    if group.vertex_planes is not None and group.facets is not None:
        return len(group.vertex_planes), len(group.facets)
    return None
