"""Where the tests find the mesh corpus: ``tests/corpus/`` in the repository (37 public meshes,
``SOURCES.md`` gives their origins and licences), or the folder ``PLN_CORPUS`` names instead.

The one definition of that path. ``conftest.py`` stops the session before any
test runs when the corpus is missing or a category of it is empty, so a test
that reads the corpus never skips for want of it and no parametrized list of
corpus files is silently empty.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ["PLN_CORPUS"]) if os.environ.get("PLN_CORPUS") else ROOT / "tests" / "corpus"
#: The corpus's folders (``SOURCES.md`` describes them); each must hold at least one mesh.
CATEGORIES = ("cad", "convex", "gltf_scene", "nonconvex_watertight", "open", "smooth_dense", "usd")
#: Files that are parts of another file (a .gltf's buffer), not meshes of their own.
SIDECARS = {".bin"}


def files(category: str | None = None) -> list[Path]:
    """The corpus's mesh files, of one category or of all, sorted."""
    folders = [category] if category else CATEGORIES
    return sorted(p for c in folders for p in (CORPUS / c).glob("*") if p.is_file() and p.suffix not in SIDECARS)


def ids(paths: list[Path]) -> list[str]:
    """``category/name`` of each path, for parametrized test ids."""
    return [f"{p.parent.name}/{p.name}" for p in paths]


def problem() -> str | None:
    """Why the corpus cannot be used, or None."""
    if not CORPUS.is_dir():
        return (f"the mesh corpus is missing: the tests expect it at {CORPUS} (tests/corpus in the "
                f"repository, or where PLN_CORPUS points)")
    empty = [c for c in CATEGORIES if not files(c)]
    if empty:
        return f"the mesh corpus at {CORPUS} has no files in {', '.join(empty)}"
    return None
