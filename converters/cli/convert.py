"""``pln convert``: between any two supported formats, .pln on either side.

    pln convert IN OUT [--units cm] [--tolerance T] [--bits N] [--scheme shell|paper] [--allow-open] [--keep-corners] [--keep-triangles]
        [--lossy --delta D --tau A] [-v] [--force]
    pln convert A B C -d OUTDIR --to glb [--jobs N]
    pln convert meshes/ -d OUTDIR [--resume] [--engine local|dask]   (see batch.py: ledger, limits)

``-`` reads standard input (format detected from the content) or writes
standard output (``--to`` names the format). Outputs are written atomically:
an error, Ctrl-C or SIGTERM leaves nothing under the target name, and the
input is never touched: an output that is an input, two inputs with one
output name, or a file beside the output it does not own (a .gltf's .bin,
without --force) are refused before any work.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from planefmt.container.limits import Limits
from planefmt.errors import GeometryError, PlnError
from planefmt_converters import interrupts
from planefmt_converters.cli import limits
from planefmt_converters.cli.progress import Status, summary

if TYPE_CHECKING:
    from planefmt.model import Scene
    from planefmt_converters.registry import Format


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("convert", help="convert between mesh formats and .pln", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("paths", nargs="*", metavar="PATH", help="IN OUT, or inputs (files, folders) with -d")
    p.add_argument("-d", "--outdir", help="batch: write each input into this folder (or fsspec URL)")
    p.add_argument("--to", help="output format name (glb, gltf, obj, ply, stl, off, usda, usdc, usdz, pln; "
                               "batch: pln by default)")
    p.add_argument("--from", dest="from_", help="input format name instead of detecting it")
    p.add_argument("--units", choices=sorted(UNIT_NAMES),
                   help="the length unit of a source that does not say (OBJ, PLY, STL, OFF; a .pln or USD file "
                        "without one): recorded in a .pln, scaled to metres in glTF, metersPerUnit in USD. A source "
                        "that says other units is refused")
    p.add_argument("--jobs", type=_at_least_one, default=1,
                   help="batch: convert this many files at once (processes here, or LocalCluster workers)")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="end with a summary line (bytes in and out, error bound, seconds) also when stderr is "
                        "not a terminal")
    p.add_argument("--force", action="store_true",
                   help="replace a file the output writes beside itself (a .gltf's .bin) even when it "
                        "belongs to another file, and an output file that is write-protected")
    p.add_argument("--salvage", action="store_true",
                   help="a damaged .pln input: convert every intact object and part group, list the losses "
                        "on stderr and exit 1")
    g = p.add_argument_group(".pln output")
    g.add_argument("--tolerance", type=float, default=1e-6,
                   help="largest error allowed, a fraction of the bbox diagonal, at most 0.1 (default 1e-6)")
    g.add_argument("--bits", type=int, help="force quantized coding with this many bits per component")
    g.add_argument("--coding", choices=["float32", "float64", "quantized"], help="force a triplet coding")
    g.add_argument("--compress", action=argparse.BooleanOptionalAction, default=True,
                   help="deflate or Brotli-compress body segments (version 5: plane and group payloads), whichever "
                        "is smaller, where that saves bytes (spec §6; the default)")
    g.add_argument("--compact", action=argparse.BooleanOptionalAction, default=True,
                   help="write version 6.0 (spec/pln.md; the default): bit-packed or predicted plane codes, "
                        "whichever is smaller, varint group bodies and chunk heads, transforms entry by entry. "
                        "--no-compact writes version 1.0, for readers of 1.x only, where the groups allow: shell "
                        "and sealed groups need version 3 or later (--major), and a warning says which was written")
    g.add_argument("--major", type=int, choices=[3, 4, 5, 6], default=6,
                   help="6 (the default): version 6.0, every record in compressed body segments; 5: the lowest "
                        "of versions 5.0 to 5.2 that holds the file, for readers of 5.x; 4: the lowest of versions 4.0 to 4.2 that holds the file, "
                        "for readers of 4.x (32-bit chunk lengths, a mETA up axis, float64 shell grids); 3: the "
                        "lowest of 3.0 to 3.4, for readers of 3.x (deflate only, transforms as 16 doubles)")
    g.add_argument("--allow-open", action="store_true",
                   help="store a closed mesh that planes cannot close as an open surface (distance and area "
                        "kept, not watertight; marked lossy) instead of failing")
    g.add_argument("--scheme", choices=["shell", "paper"], default="shell",
                   help="shell (default): convex bodies as convex groups, the rest as one shell group, fast, "
                        "error by construction; paper: BSP trees, sealed groups and patches, verified by a "
                        "certified Hausdorff search (minutes for a few thousand CAD triangles)")
    g.add_argument("--keep-corners", action="store_true",
                   help="at a tolerance above 1e-6, keep the corners that carry no shape (inside one plane, or on a "
                        "straight crease between two) and every triangle, which are otherwise dropped: the "
                        "surface is the same either way")
    g.add_argument("--keep-triangles", action="store_true",
                   help="decode to the source's own triangles, one to one (every body a shell, every corner kept); "
                        "by default a convex body is stored as its planes alone and its triangles are made from "
                        "them, the same surface and topology")
    g.add_argument("--lossy", action="store_true", help="allow the paper's lossy options below")
    g.add_argument("--delta", type=float, help="lossy: drop planes of faces under delta x total area")
    g.add_argument("--tau", type=float, help="lossy: merge neighbour planes whose normals differ < tau radians")
    from planefmt_converters.cli import batch

    limits.add_arguments(p)
    batch.add_arguments(p)
    p.set_defaults(func=run)


def _at_least_one(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text} is not a count of 1 or more")
    return value


#: --units names: SI symbols and the inch and foot.
UNIT_NAMES = {"m": "METRE", "cm": "CENTIMETRE", "mm": "MILLIMETRE", "um": "MICROMETRE", "km": "KILOMETRE",
              "in": "INCH", "ft": "FOOT"}


class _Usage(PlnError):
    """A usage mistake: reported like bad input (one line, exit 2)."""


#: Largest --tolerance: a tenth of the diagonal. Beyond it the decoded surface may be another shape, which
#: a file marked lossless "within its tolerance" would misrepresent.
MAX_TOLERANCE = 0.1


def _pln_options(args: argparse.Namespace) -> dict:
    if (args.delta is not None or args.tau is not None) and not args.lossy:
        raise _Usage("--delta and --tau change the geometry: add --lossy to allow it", code="CONVERSION_FAILED")
    if not 0 < args.tolerance <= MAX_TOLERANCE:
        raise _Usage(f"--tolerance {args.tolerance:g} is outside (0, {MAX_TOLERANCE:g}]: it is a fraction of the "
                     "bounding-box diagonal (default 1e-6)", code="CONVERSION_FAILED")
    from planefmt.model import Coding

    opts = {"tolerance": args.tolerance, "compress": args.compress, "compact": args.compact,
            "watertight": not args.allow_open, "scheme": args.scheme, "major": args.major,
            "keep_corners": args.keep_corners, "keep_triangles": args.keep_triangles}
    if args.bits is not None:
        opts["bits"] = args.bits
    if args.coding:
        opts["coding"] = Coding[args.coding.upper()]
    if args.lossy:
        opts["delta"], opts["tau"] = args.delta, args.tau
    if args.units:
        opts["units"] = args.units
    if limits.raised(args):
        opts[READ_LIMITS] = limits.raised(args)
    return opts


def _with_units(scene: Scene, units: str | None, src_name: str) -> Scene:
    """``scene`` in the ``--units`` given, where its source says none; a source that says others is refused."""
    from dataclasses import replace

    from planefmt.model import Units

    if units is None:
        return scene
    given = Units[UNIT_NAMES[units]]
    if scene.units not in (Units.UNSPECIFIED, given):
        raise _Usage(f"--units {units}: the file says its unit is the {scene.units.name.lower()}; drop --units "
                     "for it", code="CONVERSION_FAILED", file=src_name)
    return replace(scene, units=given)


#: The key of ``pln_opts`` that carries the --max options to the reading of a .pln input (a dict of
#: :class:`planefmt.Limits` fields, JSON-safe for batch jobs); every other key is the writer's.
READ_LIMITS = "read_limits"


def convert_one(src: str, dst: str, to: str | None, from_: str | None, pln_opts: dict,
                salvage: bool = False, *, src_name: str | None = None, dst_name: str | None = None,
                status: Status | None = None, facts: dict | None = None) -> tuple[list[str], list[str]]:
    """Convert one file; returns warning lines (what was dropped) and, with ``salvage``, what was lost.

    ``src_name`` and ``dst_name`` are what messages call ``src`` and ``dst`` (``<stdin>`` for a
    temporary copy of standard input); ``status`` is told the stages; ``facts`` is given the source's
    ``triangles``. Raises PlnError on bad input.
    """
    names = {src: src_name or src, dst: dst_name or dst}
    try:
        warnings, lost = _convert(src, dst, to, from_, pln_opts, salvage, names[src], names[dst],
                                  status or Status(sys.stderr, enabled=False), {} if facts is None else facts)
    except PlnError as exc:
        exc.file = names.get(exc.file, exc.file)
        raise
    return warnings, lost


def _convert(src: str, dst: str, to: str | None, from_: str | None, pln_opts: dict, salvage: bool,
             src_name: str, dst_name: str, status: Status, facts: dict) -> tuple[list[str], list[str]]:
    from planefmt import progress
    from planefmt_converters import registry

    lost: list[str] = []
    status.update(f"reading {src_name}")
    pln_opts = dict(pln_opts)
    caps = Limits(**pln_opts.get(READ_LIMITS, {}))
    fmt_in = registry.get(from_) if from_ else registry.detect(src)
    if salvage:
        if fmt_in.name != "pln":
            raise _Usage(f"--salvage reads damaged .pln files; {src_name} is {fmt_in.name}",
                         code="UNKNOWN_FORMAT")
        from planefmt import codec

        scene, lost = codec.salvage_scene(src, limits=caps)
        dropped: list[str] = []
    else:
        scene, dropped = registry.read(src, from_, **({"limits": caps} if fmt_in.name == "pln" else {}))
    scene = _with_units(scene, pln_opts.get("units"), src_name)
    facts["triangles"] = sum(len(node.mesh.faces) for node in scene.nodes if node.mesh is not None)
    fmt = _output_format(dst, to)
    # Conflicts beside the output were refused before any work, or --force allowed them.
    status.update("encoding" if fmt.name == "pln" else f"writing {dst_name}")
    try:
        with progress.reporting(status.update):
            options = ({key: value for key, value in pln_opts.items() if key not in ("units", READ_LIMITS)}
                       if fmt.name == "pln" else {})
            notes = registry.write(scene, dst, fmt.name, force=True, **options)
    except GeometryError as exc:
        exc.file = src  # what the input holds (or a tolerance it cannot meet), not the output
        raise
    facts["rounding"] = fmt.rounding(scene) if fmt.rounding is not None else 0.0
    warnings = []
    if dropped:
        warnings.append(f"{src_name}: dropped {'; '.join(dropped)} (not carried into {Path(dst_name).name})")
    if notes:
        warnings.append(f"{dst_name}: not kept by {fmt.name}: {', '.join(notes)}")
    if fmt.name == "pln" and not pln_opts.get("compact", True):
        from planefmt_converters.pln import beyond_version_1

        version, kinds = beyond_version_1(dst)
        if kinds:
            warnings.append(f"{dst_name}: written as version {version[0]}.{version[1]}, not 1.0 (--no-compact): "
                            f"version 1.0 has no {', '.join(kinds)} groups; it holds convex groups, cells, trees "
                            "and patches, which --scheme paper makes where it can")
    return warnings, [f"{src_name}: {line}" for line in lost]


def run(args: argparse.Namespace) -> int:
    with interrupts.handled():
        try:
            opts = _pln_options(args)
            if args.outdir:
                from planefmt_converters.cli import batch

                code = batch.run(args, opts)
            elif args.from_list or any(os.path.isdir(path) for path in args.paths):
                raise _Usage("folders and --from-list convert into a folder: add -d OUTDIR", code="CONVERSION_FAILED")
            elif len(args.paths) != 2:
                raise _Usage("give IN OUT, or several inputs with -d OUTDIR --to FORMAT", code="CONVERSION_FAILED")
            else:
                _refuse_conflicts([(args.paths[0], args.paths[1])], args)
                refuse_protected([args.paths[1]], args)
                code = _run_single(args.paths[0], args.paths[1], args, opts)
        except PlnError:
            # The error may be what a swallowed KeyboardInterrupt turned into: report the signal.
            interrupts.check()
            raise
        interrupts.check()
        return code


def _refuse_conflicts(pairs: list[tuple[str, str]], args: argparse.Namespace) -> None:
    """Before any work: no output (sidecars included) replaces an input or a file an input uses, none is
    written twice, and none replaces a file beside its target that the target does not use (without
    ``--force``). The atomic rename would otherwise lose that file only after a possibly long run."""
    from planefmt_converters import registry

    inputs: dict[tuple, str] = {}  # file identity: how the message names it
    for src, _ in pairs:
        if src == "-":
            continue
        inputs[registry.file_identity(src)] = f"the input {src}"
        try:
            fmt_in = registry.get(args.from_) if args.from_ else registry.detect(src)
        except PlnError:
            continue  # unreadable: its own conversion reports it, the others of a batch go on
        for used in fmt_in.references(src) if fmt_in.references else ():
            inputs.setdefault(registry.file_identity(used), f"a file the input {src} uses")
    written: dict[tuple, str] = {}
    for src, dst in pairs:
        if dst == "-":
            continue
        fmt = _output_format(dst, args.to)
        for out in (dst, *(fmt.sidecars(dst) if fmt.sidecars else ())):
            key = registry.file_identity(out)
            if key in inputs:
                raise PlnError(f"this output is the same file as {inputs[key]}; inputs are never overwritten: "
                               "choose another output name", code="OUTPUT_CONFLICT", file=out)
            if key in written:
                raise PlnError(f"{written[key]} and {src} would both be written here, one result lost: "
                               "convert them into different folders or rename one", code="OUTPUT_CONFLICT",
                               file=out)
            written[key] = src
        unclaimed = [] if args.force else registry.unclaimed_sidecars(dst, fmt)
        if unclaimed:
            raise PlnError(f"writing {dst} would replace this file, which {dst} does not use: move it, or "
                           "add --force to replace it", code="OUTPUT_CONFLICT", file=unclaimed[0])


def refuse_protected(outputs: list[str], args: argparse.Namespace) -> None:
    """Before any work: without ``--force``, no output (sidecars included) replaces a write-protected file,
    as ``cp`` refuses to. The atomic rename would replace it, since it needs only the folder writable."""
    import stat

    if args.force:
        return
    for dst in outputs:
        if dst == "-":
            continue
        fmt = _output_format(dst, args.to)
        for out in (dst, *(fmt.sidecars(dst) if fmt.sidecars else ())):
            try:
                mode = os.stat(out).st_mode
            except OSError:
                continue
            # a file no one may write is protected also from root, whom access() lets write anything
            if stat.S_ISREG(mode) and (not mode & 0o222 or not os.access(out, os.W_OK)):
                raise PlnError("this output file is write-protected: make it writable, or add --force to replace "
                               "it", code="OUTPUT_CONFLICT", file=out)


def _output_format(dst: str, to: str | None) -> Format:
    """The format ``dst`` is written in: ``--to``, else by extension. An extension of another format than
    ``--to`` names is refused (GLB bytes in ``x.pln`` mislead every later reader); one of no format is the
    user's choice."""
    from planefmt_converters import registry

    by_extension = registry.for_extension(dst, writable=True)
    fmt = registry.get(to) if to else by_extension
    if fmt is None:
        raise _Usage(f"cannot tell the output format from {dst!r}: name it with --to", code="UNKNOWN_FORMAT")
    suffix = Path(dst).suffix.lower()
    if by_extension is not None and suffix not in fmt.extensions:
        raise _Usage(f"--to {fmt.name} writes {fmt.name}, but {suffix} is the extension of {by_extension.name}: "
                     f"name the output {Path(dst).stem}{fmt.extensions[0]} or drop --to", code="UNKNOWN_FORMAT",
                     file=dst)
    return fmt


def _run_single(src: str, dst: str, args: argparse.Namespace, opts: dict) -> int:
    with contextlib.ExitStack() as stack:
        src_name = dst_name = None
        if src == "-":
            src, src_name = stack.enter_context(_temporary("")), "<stdin>"
            with open(src, "wb") as f:
                shutil.copyfileobj(sys.stdin.buffer, f)
        to_stdout = dst == "-"
        if to_stdout:
            if not args.to:
                raise _Usage("writing to standard output needs --to FORMAT", code="UNKNOWN_FORMAT")
            from planefmt_converters import registry

            dst, dst_name = stack.enter_context(_temporary(registry.get(args.to).extensions[0])), "<stdout>"
        elif not os.path.isdir(os.path.dirname(dst) or "."):
            raise _Usage(f"the folder {os.path.dirname(dst)} does not exist", code="CONVERSION_FAILED", file=dst)
        status = Status(sys.stderr, enabled=sys.stderr.isatty())
        facts: dict = {}
        try:
            warnings, lost = convert_one(src, dst, args.to, args.from_, opts, args.salvage,
                                         src_name=src_name, dst_name=dst_name, status=status, facts=facts)
        finally:
            status.close()  # before any message, so that it starts on a clean line
        if status.enabled or args.verbose:
            print(_summary(src, dst, src_name or src, dst_name or dst, args, status.elapsed, facts.get("rounding", 0.0)),
                  file=sys.stderr)
        for line in warnings:
            print(f"pln: warning: {line}", file=sys.stderr)
        for line in lost:
            print(f"pln: lost: {line}", file=sys.stderr)
        if to_stdout:
            with open(dst, "rb") as f:
                shutil.copyfileobj(f, sys.stdout.buffer)
            sys.stdout.buffer.flush()
    return 1 if lost else 0


def _summary(src: str, dst: str, src_name: str, dst_name: str, args: argparse.Namespace, seconds: float,
             rounding: float = 0.0) -> str:
    """The line a conversion ends with; the error bound is the output's, else the one its .pln input
    records (what it was decoded within) plus ``rounding``, how far writing the output moved the surface
    (float32 coordinates), both fractions of the diagonal."""
    import planefmt
    from planefmt_converters import registry

    fmt = registry.get(args.to) if args.to else registry.for_extension(dst, writable=True)
    written = [dst, *(fmt.sidecars(dst) if fmt.sidecars else ())]
    bytes_out = sum(os.path.getsize(path) for path in written if os.path.exists(path))
    fmt_in = registry.get(args.from_) if args.from_ else registry.detect(src)
    pln_in = fmt_in.name == "pln"
    error = None
    if fmt.name == "pln" or pln_in:
        try:
            with planefmt.open(dst if fmt.name == "pln" else src) as f:
                error = f.header.error_bound
        except planefmt.PlnError:  # a damaged input, converted with --salvage: no bound to quote
            pass
    bytes_in = sum(os.path.getsize(path) for path in registry.input_files(src, fmt_in))
    return summary(src_name, dst_name, bytes_in, bytes_out, error, seconds,
                   recorded_in_input=fmt.name != "pln", rounding=rounding)


@contextlib.contextmanager
def _temporary(suffix: str) -> Iterator[str]:
    """A temporary file standing for standard input or output, since readers and writers take paths.

    Only these conversions make one, and a file rather than a folder: a SIGKILL, which allows no clean-up,
    leaves at most this one file in the system's temporary folder.
    """
    fd, name = tempfile.mkstemp(prefix="pln-", suffix=suffix)
    os.close(fd)
    try:
        yield name
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(name)
