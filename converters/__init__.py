"""planefmt_converters: OBJ, PLY, STL, OFF, glTF/GLB and USD to and from planefmt's model.

Installed from the repository's ``converters/`` folder as the import package
``planefmt_converters`` (a top-level ``converters`` would clash with an
unrelated PyPI distribution of that name).

    from planefmt_converters import read, write
    scene, dropped = read("model.glb")       # dropped: what the model could not hold
    notes = write(scene, "model.usdz")       # notes: what the format could not hold

The format table, detection and the ``planefmt.converters`` entry-point
group for third-party formats are in :mod:`planefmt_converters.registry`;
the external validators (Khronos glTF-Validator, USD validation) in
:mod:`planefmt_converters.validators`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .registry import Format, detect, formats, get, read, register, write

__all__ = ["Format", "detect", "formats", "get", "read", "register", "write"]


def __getattr__(name: str) -> object:
    # Lazy (PEP 562): importing the package, as the ``pln`` script does before it can install its
    # signal handlers, must not import numpy, trimesh and planefmt (a third of a second).
    if name in __all__:
        from . import registry

        return getattr(registry, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
