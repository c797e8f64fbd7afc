"""``--max-triangles``, ``--max-vertices``, ``--max-planes``: the reader's limits of spec §12.4, shared by
every command that reads a .pln file."""

from __future__ import annotations

import argparse

from planefmt.container.limits import Limits

#: Each option and the :class:`Limits` field it sets.
OPTIONS = {"--max-triangles": "max_triangles", "--max-vertices": "max_vertices", "--max-planes": "max_planes"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    defaults = Limits()
    g = p.add_argument_group("reader limits (spec §12.4)")
    for flag, field in OPTIONS.items():
        what = field.removeprefix("max_")
        g.add_argument(flag, type=_count, dest=field, metavar="N",
                       help=f"read a .pln whose decode makes up to N {what} (default {getattr(defaults, field):,})"
                       if what != "planes" else
                       f"read a .pln whose plane table holds up to N planes (default {defaults.max_planes:,})")


def raised(args: argparse.Namespace) -> dict[str, int]:
    """The limits the options set, by :class:`Limits` field (JSON-safe: batch jobs carry them)."""
    return {field: getattr(args, field) for field in OPTIONS.values() if getattr(args, field, None) is not None}


def limits_of(args: argparse.Namespace) -> Limits:
    return Limits(**raised(args))


def _count(text: str) -> int:
    try:
        n = int(text.replace(",", "").replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"{text} is negative")
    return n
