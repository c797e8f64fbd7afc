"""The ``pln`` command line: ``main(argv) -> exit code``, one module per subcommand.

Exit codes: 0 ok, 1 findings (validation errors or warnings), 2 bad input or
usage. Bad input gives one line on stderr, ``pln: FILE: chunk X at byte N:
reason``, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import warnings

from .. import interrupts

#: Subcommand modules of this package; each defines ``add_parser(subparsers)``.
SUBCOMMANDS = ("info", "convert", "validate", "preview", "report")

EXIT_OK, EXIT_FINDINGS, EXIT_BAD_INPUT = 0, 1, 2


def version_line() -> str:
    """``pln --version``: the package's version and the format versions its reader knows."""
    from planefmt import __version__
    from planefmt.container.versions import VERSIONS

    newest = f"{max(VERSIONS)}.{VERSIONS[max(VERSIONS)]}"
    return f"pln {__version__} (planefmt; reads .pln {min(VERSIONS)}.0-{newest}, writes {newest})"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pln", description="Read, write and convert .pln plane meshes.")
    parser.add_argument("--version", action="version", version=version_line())
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            continue
        module.add_parser(sub)
    return parser


def quiet_library_warnings() -> None:
    """Keep numpy's and the libraries' own warnings (RuntimeWarning: overflow, invalid value...) off
    stderr: they name no file and are not the user's to act on. What a conversion gave up is reported
    as ``pln: warning:`` lines (:class:`planefmt.PlnWarning`), which this leaves alone."""
    warnings.filterwarnings("ignore", category=RuntimeWarning)


#: The root logger's handler :func:`route_library_logs` installed (replaced by each call).
_log_handler: logging.Handler | None = None


def route_library_logs(verbose: bool) -> None:
    """Send the libraries' log records (trimesh's "failed to process extension ...") to stderr as
    ``pln: library:`` lines with ``-v``, else nowhere: without a handler Python prints any warning of
    theirs bare on the user's terminal, beside the one line that says what went wrong."""
    global _log_handler
    root = logging.getLogger()
    if _log_handler is not None:
        root.removeHandler(_log_handler)
    if verbose:
        _log_handler = logging.StreamHandler(sys.stderr)
        _log_handler.setFormatter(logging.Formatter("pln: library: %(name)s: %(message)s"))
        _log_handler.setLevel(logging.WARNING)
    else:
        _log_handler = logging.NullHandler()
    root.addHandler(_log_handler)


def _hint(exc: Exception, args: argparse.Namespace) -> str:
    """What to try next, for errors a user can do something about."""
    from planefmt.errors import ConversionError

    # --salvage reads damaged .pln files; a cut mesh file of another format is no .pln
    if (exc.code in ("TRUNCATED", "CRC_MISMATCH", "BAD_CHUNK_TYPE") and getattr(args, "salvage", True) is False
            and not isinstance(exc, ConversionError)):
        return f"; pln {args.command} --salvage reads what is intact"
    return ""


def main(argv: list[str] | None = None) -> int:
    # Building the parser imports every subcommand's module and planefmt's errors, model and chunk framing
    # (their own numpy, trimesh or codec only when they run): a Ctrl-C or SIGTERM then ends the command as
    # one later would, not with an import traceback or an aborted extension.
    try:
        with interrupts.handled():
            parser = build_parser()
            from planefmt.errors import PlnError

            interrupts.check()
    except KeyboardInterrupt:
        print("pln: interrupted", file=sys.stderr)
        return 130
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return EXIT_OK if exc.code in (0, None) else EXIT_BAD_INPUT
    quiet_library_warnings()
    route_library_logs(getattr(args, "verbose", False))
    try:
        return args.func(args)
    except PlnError as exc:
        print(f"pln: {exc}{_hint(exc, args)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("pln: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except OSError as exc:
        print(f"pln: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
