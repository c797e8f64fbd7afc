"""The table of mesh formats, and reading or writing a file by detected format.

Each :class:`Format` names a format, its file extensions, a ``sniff``
function over the file's first bytes, a ``read`` and a ``write`` function::

    read(path) -> (Scene, dropped)            # dropped: list[str], what the model could not hold
    write(scene, path, **options) -> notes    # notes: list[str], what the format could not hold
    sniff(head: bytes, size: int) -> bool     # head: the first SNIFF_BYTES bytes; size: file size
    rounding(scene) -> float                  # how far a write moves the surface (float32 coordinates),
                                              # a fraction of the diagonal: added to the error bound
    sidecars(path) -> paths                   # the other files a write of path creates beside it
    references(path) -> paths                 # the other files the existing file at path uses

Readers and writers raise :class:`planefmt.errors.ConversionError` for bad
input and write atomically (:mod:`.atomic`). Detection tries every format's
``sniff`` in table order (strong signatures first, the OBJ text heuristic
last) and falls back to the extension; a file neither recognises is an
``UNKNOWN_FORMAT`` error. Writing picks the format from the extension (the
first format listing it: ``.usd`` is written as crate) unless named.

Format modules import their heavy dependency (trimesh, pxr) on first use, so
a missing optional dependency fails only when its format is used.

Third-party formats
-------------------
A distribution adds formats through the entry-point group
``planefmt.converters``; each entry point names a :class:`Format`, or a
callable returning one or a sequence of them::

    [project.entry-points."planefmt.converters"]
    x3d = "planefmt_x3d:FORMAT"

Entry points are loaded on the first lookup, not at import. They come after
the built-in formats (also in detection order) and cannot replace one; an
entry point that fails to load is skipped and reported by
:func:`plugin_errors`. :func:`register` adds a format at run time.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from planefmt.errors import ConversionError, PlnError
from planefmt.model import Scene

from . import gltf, obj, off, pln, ply, stl, usd
from .failures import describe

ENTRY_POINT_GROUP = "planefmt.converters"

#: How many leading bytes the sniffers see.
SNIFF_BYTES = 65536

Sniffer = Callable[[bytes, int], bool]
Reader = Callable[[str], tuple[Scene, list[str]]]
Writer = Callable[..., list[str]]


@dataclass(frozen=True)
class Format:
    """One mesh format: ``extensions`` are lower case with the dot (``".obj"``).

    ``sniff``, ``read`` or ``write`` may be None when the format cannot be
    recognised by content, read, or written; ``sidecars`` and ``references``
    are None for a format stored in one file; ``rounding`` is None for a format that stores coordinates as
    they are.
    """

    name: str
    extensions: tuple[str, ...]
    sniff: Sniffer | None = None
    read: Reader | None = None
    write: Writer | None = None
    description: str = ""
    sidecars: Callable[[str], tuple[str, ...]] | None = None
    references: Callable[[str], tuple[str, ...]] | None = None
    rounding: Callable[[Scene], float] | None = None


#: The built-in formats, in detection order.
BUILTIN: tuple[Format, ...] = (
    Format("pln", (".pln",), pln.sniff, pln.read, pln.write, "planes (this library's format)"),
    Format("glb", (".glb",), gltf.sniff_glb, gltf.read_glb, gltf.write_glb, "binary glTF 2.0",
           rounding=gltf.rounding),
    Format("usdc", (".usdc", ".usd"), usd.sniff_usdc, usd.read, usd.write, "USD crate (binary)", rounding=usd.rounding),
    Format("usdz", (".usdz",), usd.sniff_usdz, usd.read, usd.write, "USD zip package", rounding=usd.rounding),
    Format("usda", (".usda", ".usd"), usd.sniff_usda, usd.read, usd.write, "USD text", rounding=usd.rounding),
    Format("ply", (".ply",), ply.sniff, ply.read, ply.write, "Stanford PLY", rounding=ply.rounding),
    Format("gltf", (".gltf",), gltf.sniff_gltf, gltf.read_gltf, gltf.write_gltf,
           "glTF 2.0 JSON with a .bin buffer", gltf.sidecars, gltf.references, gltf.rounding),
    Format("off", (".off",), off.sniff, off.read, off.write, "Object File Format"),
    Format("stl", (".stl",), stl.sniff, stl.read, stl.write, "STL, binary or ASCII", rounding=stl.rounding),
    Format("obj", (".obj",), obj.sniff, obj.read, obj.write, "Wavefront OBJ", references=obj.references),
)

_registered: list[Format] = []
_plugins: list[Format] | None = None
_plugin_errors: list[str] = []


def formats() -> tuple[Format, ...]:
    """Every known format in detection order: built-in, registered, entry points."""
    return BUILTIN + tuple(_registered) + tuple(_load_plugins())


def register(fmt: Format) -> None:
    """Add ``fmt`` to the table (after the built-ins); its name must be new."""
    if any(known.name == fmt.name for known in formats()):
        raise ValueError(f"a format named {fmt.name!r} is already registered")
    _registered.append(fmt)


def plugin_errors() -> list[str]:
    """One line per ``planefmt.converters`` entry point that could not be used."""
    _load_plugins()
    return list(_plugin_errors)


def _load_plugins() -> list[Format]:
    global _plugins
    if _plugins is not None:
        return _plugins
    _plugins = []
    taken = {fmt.name for fmt in BUILTIN + tuple(_registered)}
    for entry in metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            loaded: Any = entry.load()
            if not isinstance(loaded, Format) and callable(loaded):
                loaded = loaded()
            found = [loaded] if isinstance(loaded, Format) else list(loaded)
            if not all(isinstance(fmt, Format) for fmt in found):
                raise TypeError("it does not give Format objects")
        except Exception as exc:  # noqa: BLE001 - a broken plugin must not break the rest
            _plugin_errors.append(f"entry point {entry.name} ({entry.value}): {exc}")
            continue
        for fmt in found:
            if fmt.name in taken:
                _plugin_errors.append(
                    f"entry point {entry.name}: format name {fmt.name!r} is already taken")
                continue
            taken.add(fmt.name)
            _plugins.append(fmt)
    return _plugins


def get(name: str) -> Format:
    """The format called ``name`` (case-insensitive)."""
    for fmt in formats():
        if fmt.name == name.lower():
            return fmt
    known = ", ".join(fmt.name for fmt in formats())
    raise ConversionError(f"unknown format {name!r} (known: {known})", code="UNKNOWN_FORMAT")


def for_extension(path: str | os.PathLike[str], *, writable: bool = False) -> Format | None:
    """The first format listing the extension of ``path`` (and a writer, if asked)."""
    suffix = Path(path).suffix.lower()
    for fmt in formats():
        if suffix in fmt.extensions and (fmt.write if writable else fmt.read) is not None:
            return fmt
    return None


def detect(path: str | os.PathLike[str]) -> Format:
    """The readable format of the file at ``path``: by content, else by extension."""
    file = os.fspath(path)
    try:
        with open(file, "rb") as handle:
            head = handle.read(SNIFF_BYTES)
            size = os.fstat(handle.fileno()).st_size
    except OSError as exc:
        raise ConversionError(f"cannot open: {exc.strerror or exc}", file=file) from exc
    if size == 0:
        raise ConversionError("the file is empty", file=file)
    fmt = sniff(head, size) or for_extension(file)
    if fmt is None:
        raise ConversionError("unknown format: neither the content nor the extension "
                              "is one of a known mesh format", code="UNKNOWN_FORMAT", file=file)
    return fmt


def sniff(head: bytes, size: int) -> Format | None:
    """The first readable format that recognises ``head``, the first bytes of a file of ``size`` bytes."""
    for fmt in formats():
        if fmt.sniff is not None and fmt.read is not None and _sniffs(fmt.sniff, head, size):
            return fmt
    return None


def _sniffs(sniff: Sniffer, head: bytes, size: int) -> bool:
    try:
        return bool(sniff(head, size))
    except Exception:  # noqa: BLE001 - a faulty (plugin) sniffer just does not match
        return False


def read(path: str | os.PathLike[str], format: str | None = None, **options: Any) -> tuple[Scene, list[str]]:
    """Read the mesh file at ``path`` into ``(scene, dropped)``.

    ``format`` names the format instead of detecting it; ``options`` go to its reader (.pln: ``limits``).
    ``dropped`` lists what the file held that the model cannot, in :mod:`.dropped`'s words: a caller
    shows it as one warning.
    """
    file = os.fspath(path)
    fmt = get(format) if format else detect(file)
    if fmt.read is None:
        raise ConversionError(f"format {fmt.name} cannot be read", code="UNKNOWN_FORMAT",
                              file=file)
    return _guarded(fmt, "read", file, lambda: fmt.read(file, **options))


def write(scene: Scene, path: str | os.PathLike[str], format: str | None = None, *,
          force: bool = False, **options: Any) -> list[str]:
    """Write ``scene`` to ``path`` atomically; returns what the format could not hold.

    The format comes from ``format`` or else from the extension of ``path``.
    ``options`` go to the format's writer (``ascii=True`` for PLY and STL,
    ``up_axis="Z"`` for USD); an option the writer lacks is an error. A file
    beside ``path`` that the write would replace (a ``.gltf``'s ``.bin``) is
    an ``OUTPUT_CONFLICT`` error unless the file now at ``path`` uses it or
    ``force`` is set (see :func:`unclaimed_sidecars`).
    """
    file = os.fspath(path)
    fmt = writer_for(file, format)
    unclaimed = [] if force else unclaimed_sidecars(file, fmt)
    if unclaimed:
        raise ConversionError(f"writing {file} would replace this file, which {file} does not use: "
                              "move it, or pass force=True", code="OUTPUT_CONFLICT", file=unclaimed[0])
    try:
        inspect.signature(fmt.write).bind(scene, file, **options)
    except TypeError as exc:
        raise ConversionError(f"format {fmt.name} does not take these options: {exc}",
                              file=file) from exc
    return _guarded(fmt, "write", file, lambda: fmt.write(scene, file, **options))


def writer_for(path: str | os.PathLike[str], format: str | None = None) -> Format:
    """The format that writes ``path``: ``format`` if given, else by extension."""
    file = os.fspath(path)
    fmt = get(format) if format else for_extension(file, writable=True)
    if fmt is None:
        raise ConversionError(f"no writable format has the extension {Path(file).suffix!r}",
                              code="UNKNOWN_FORMAT", file=file)
    if fmt.write is None:
        raise ConversionError(f"format {fmt.name} cannot be written", code="UNKNOWN_FORMAT",
                              file=file)
    return fmt


def unclaimed_sidecars(path: str | os.PathLike[str], fmt: Format) -> list[str]:
    """Existing files a write of ``path`` as ``fmt`` would replace besides ``path`` itself and that
    the file now at ``path`` does not use: replacing them would lose a file nobody named."""
    file = os.fspath(path)
    if fmt.sidecars is None:
        return []
    present = [sidecar for sidecar in fmt.sidecars(file) if os.path.lexists(sidecar)]
    if not present:
        return []
    used = set()
    if fmt.references is not None and os.path.exists(file):
        used = {file_identity(ref) for ref in fmt.references(file)}
    return [sidecar for sidecar in present if file_identity(sidecar) not in used]


def input_files(path: str | os.PathLike[str], fmt: Format) -> list[str]:
    """The files the input at ``path`` is made of: itself, then the existing files it refers to (a
    ``.gltf``'s buffers and images, an OBJ's material libraries and textures), each file once."""
    file = os.fspath(path)
    files, seen = [file], {file_identity(file)}
    for used in fmt.references(file) if fmt.references else ():
        key = file_identity(used)
        if key not in seen and os.path.isfile(used):
            files.append(used)
            seen.add(key)
    return files


def file_identity(path: str) -> tuple:
    """Equal for two paths to one file, also through symbolic or hard links: device and inode where
    the file exists, else the resolved path (a file that does not exist yet is no existing file)."""
    try:
        st = os.stat(path)
    except OSError:
        return ("path", os.path.realpath(path))
    return ("inode", st.st_dev, st.st_ino)


def _guarded(fmt: Format, action: str, file: str, call: Callable[[], Any]) -> Any:
    """Run a reader or writer; anything but a PlnError becomes a ConversionError.

    Built-in formats already raise ConversionError for bad input; this is the
    last line for plugins and unforeseen failures, so callers see one
    exception type (the original stays chained for debugging).
    """
    try:
        return call()
    except PlnError as exc:
        raise exc.located(file=file)
    except Exception as exc:  # noqa: BLE001
        raise ConversionError(f"cannot {action} {fmt.name}: {describe(exc)}", file=file) from exc

