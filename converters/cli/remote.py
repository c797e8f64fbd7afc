"""Inputs and outputs of a batch run named by fsspec URLs (``s3://bucket/meshes``, ``file:///data``).

Converters read and write local paths, so a worker copies a URL source into its scratch folder and
uploads its outputs: each to a temporary name in the target's folder (``.pln-batch-…``, like the
local scratch folders, so a resumed run finds and removes the ones a killed run left), then moved
onto the target; on an object store the upload itself appears whole or not at all.
"""

from __future__ import annotations

import os
from typing import Any

from planefmt.errors import PlnError

#: What a batch run's temporaries start with, locally and at URLs: ``--resume`` removes what a killed
#: run left of them.
SCRATCH_PREFIX = ".pln-batch-"


def is_url(name: str) -> bool:
    return "://" in name


def filesystem(url: str) -> tuple[Any, str]:
    """The fsspec file system of ``url`` and the path within it."""
    try:
        import fsspec
    except ImportError as exc:
        raise PlnError("URLs need fsspec: pip install fsspec (and s3fs, gcsfs... for their protocols)",
                       code="CONVERSION_FAILED", file=url) from exc
    try:
        return fsspec.core.url_to_fs(url)
    except (ImportError, ValueError) as exc:
        raise PlnError(f"cannot open this URL: {exc}", code="CONVERSION_FAILED", file=url) from exc


def url(fs: Any, path: str) -> str:
    """The URL of ``path`` on the fsspec file system ``fs``."""
    return fs.unstrip_protocol(path)


def isdir(name: str) -> bool:
    fs, path = filesystem(name)
    return fs.isdir(path)


def exists(name: str) -> bool:
    if not is_url(name):
        return os.path.exists(name)
    fs, path = filesystem(name)
    return fs.exists(path)


def identity(name: str) -> tuple[int, int | None]:
    """Size and modification time (ns, None where the store keeps none) of the file ``name``."""
    if not is_url(name):
        st = os.stat(name)
        return st.st_size, st.st_mtime_ns
    fs, path = filesystem(name)
    try:
        info = fs.info(path)
    except FileNotFoundError as exc:
        raise PlnError("cannot open: no such file", code="CONVERSION_FAILED", file=name) from exc
    mtime = info.get("mtime", info.get("LastModified", info.get("created")))
    if hasattr(mtime, "timestamp"):
        mtime = mtime.timestamp()
    return int(info["size"]), None if mtime is None else int(float(mtime) * 1e9)


def download(name: str, local: str) -> None:
    fs, path = filesystem(name)
    try:
        fs.get_file(path, local)
    except FileNotFoundError as exc:
        raise PlnError("cannot open: no such file", code="CONVERSION_FAILED", file=name) from exc


def upload(local: str, name: str, token: str) -> None:
    """Put the file ``local`` at the URL ``name`` whole: under a temporary name beside it, then moved."""
    fs, path = filesystem(name)
    folder, base = path.rsplit("/", 1) if "/" in path else ("", path)
    temp = f"{folder}/{SCRATCH_PREFIX}{token}-{base}" if folder else f"{SCRATCH_PREFIX}{token}-{base}"
    if folder:
        fs.makedirs(folder, exist_ok=True)
    fs.put_file(local, temp)
    fs.mv(temp, path)


def remove_scratch(root: str) -> int:
    """Remove the temporaries a killed run left under the URL ``root``; returns how many."""
    fs, base = filesystem(root)
    if not fs.exists(base):
        return 0
    stale = [p for p in fs.find(base) if os.path.basename(p).startswith(SCRATCH_PREFIX)]
    for p in stale:
        fs.rm_file(p)
    return len(stale)
