"""What a batch conversion converts: files, folders walked recursively, lists of paths, fsspec URLs.

A file named on the command line or in a list is converted whatever it holds (a file that is no mesh
fails with its reason); a folder contributes the mesh files under it, recognised by a readable
format's extension or, for other names, by content (a format's sniffer over the first bytes). Hidden
files and folders are passed over, so are the run's own scratch folders and ledger, and the output
folder where it lies inside a source folder. Each source keeps its path relative to the folder it was
found in, which the output keeps under ``-d OUTDIR``; a file named directly goes to the top of OUTDIR.

A name with ``://`` is an fsspec URL (``s3://bucket/meshes``, ``file:///data``), read through fsspec
where it is installed; ``-`` as the list file is standard input.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from planefmt.errors import PlnError

from . import remote


@dataclass(frozen=True)
class Source:
    """One input: ``path`` as named (a local path or a URL) and ``rel``, the output's path under
    OUTDIR without its extension (``"parts/bolt"``)."""

    path: str
    rel: str


def listed(list_file: str) -> list[str]:
    """The paths in ``list_file`` (``-``: standard input), one a line; blank lines and ``#`` comments
    are passed over."""
    try:
        if list_file == "-":
            text = sys.stdin.read()
        else:
            with open(list_file, encoding="utf-8") as f:
                text = f.read()
    except OSError as exc:
        raise PlnError(f"cannot read the list of inputs: {exc.strerror or exc}", code="CONVERSION_FAILED",
                       file=list_file) from exc
    except UnicodeDecodeError as exc:
        raise PlnError("the list of inputs is not UTF-8 text", code="CONVERSION_FAILED", file=list_file) from exc
    return [line.strip() for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]


def expand(names: Iterable[str], outdir: str) -> list[Source]:
    """Every input of ``names``: a folder (local or URL) becomes the mesh files under it, sorted."""
    sources: list[Source] = []
    for name in names:
        if remote.is_url(name):
            if remote.isdir(name):
                sources.extend(_walk_url(name))
            else:
                sources.append(Source(name, PurePosixPath(name.rstrip("/")).stem))
        elif os.path.isdir(name):
            sources.extend(_walk(Path(name), outdir))
        else:
            sources.append(Source(name, Path(name).stem))
    return sources


def _walk(root: Path, outdir: str) -> Iterator[Source]:
    skip = {os.path.realpath(outdir)} if not remote.is_url(outdir) else set()
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if not d.startswith(".") and os.path.realpath(os.path.join(folder, d)) not in skip]
        for name in files:
            path = Path(folder) / name
            if not name.startswith(".") and _is_mesh(name, lambda: (_head(path), path.stat().st_size)):
                found.append(path)
    for path in sorted(found):
        rel = path.relative_to(root)
        yield Source(str(path), str(rel.with_suffix("")) if rel.suffix else str(rel))


def _walk_url(root: str) -> Iterator[Source]:
    fs, base = remote.filesystem(root)
    base = base.rstrip("/")
    for path in sorted(fs.find(base)):
        rel = PurePosixPath(path).relative_to(base)
        if any(part.startswith(".") for part in rel.parts):
            continue
        if _is_mesh(rel.name, lambda: (fs.cat_file(path, start=0, end=_sniff_bytes()), fs.size(path))):
            url = remote.url(fs, path)
            yield Source(url, str(rel.with_suffix("")) if rel.suffix else str(rel))


def _is_mesh(name: str, head: Callable[[], tuple[bytes, int]]) -> bool:
    """A readable format's extension, or content one of the formats recognises (``head()``: the
    file's first bytes and its size, read only when the extension does not tell)."""
    from planefmt_converters import registry

    if registry.for_extension(name) is not None:
        return True
    if Path(name).suffix.lower() in (".jsonl", ".bin"):  # ledgers and glTF buffers: never meshes themselves
        return False
    try:
        data, size = head()
    except OSError:
        return False
    return bool(data) and registry.sniff(data, size) is not None


def _head(path: Path) -> bytes:
    with open(path, "rb") as f:
        return f.read(_sniff_bytes())


def _sniff_bytes() -> int:
    from planefmt_converters import registry

    return registry.SNIFF_BYTES
