"""One plain line for a failure inside a third-party library (trimesh, usd-core, numpy).

Messages on the command line name no Python exception class and no temporary file: a reader of
``pln: model.obj: cannot read as OBJ: ...`` should learn what is wrong with the file, not which
line of which library noticed it. The original exception stays chained for debugging.
"""

from __future__ import annotations


def describe(exc: BaseException) -> str:
    """What ``exc`` says about the data, in one line, without its class name or a path."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror  # its filename may be a temporary; the caller names the file
    if isinstance(exc, ImportError) and exc.name:
        return f"it needs the Python module {exc.name}, which is not installed"
    if isinstance(exc, UnicodeError):
        return "the text is in no encoding this reader knows"
    first = _first_line(exc)
    if isinstance(exc, IndexError):
        return f"an index points past the end of its data ({first})" if first else \
            "an index points past the end of its data"
    if isinstance(exc, KeyError):
        return f"a required entry is missing ({first})" if first else "a required entry is missing"
    return first or "the data is malformed"


def _first_line(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines()
    return lines[0].strip() if lines else ""
