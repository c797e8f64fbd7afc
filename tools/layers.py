"""Checks the layering of planefmt that anyone can verify from the source (issue 32).

Prints one line per fact and exits 1 if any fails:

* no import cycles among planefmt's modules: every ``import`` counts, those
  inside functions too (a lazy import is still a dependency);
* no module over :data:`MAX_LINES` lines;
* at least :data:`MIN_PACKAGES` sub-packages;
* ``spec/pln.md`` present;
* imports go one way (:data:`FORBIDDEN`): container never imports geometry,
  groups or the codec; geometry never groups or the codec; groups never the
  codec;
* ``converters/`` uses no private name (leading underscore) of planefmt.

A module's edges are the planefmt modules it names: ``from .x import y``
depends on ``x``, or on ``x.y`` where that is a module itself. Importing a
submodule runs its package's ``__init__`` too, but that is not counted as an
edge: a package that re-exports its submodules' names would otherwise cycle
with each of them.

Usage: ``python tools/layers.py [repository root]``.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

MAX_LINES = 800
MIN_PACKAGES = 3

#: (importing layer, imported layer) pairs that are not allowed; a layer is the first component
#: of a module's name under planefmt (``container``, ``geometry``, ``groups``, ``codec``).
FORBIDDEN = {
    ("container", "geometry"), ("container", "groups"), ("container", "codec"),
    ("geometry", "groups"), ("geometry", "codec"),
    ("groups", "codec"),
}


def module_name(path: Path, package_root: Path) -> str:
    parts = list(path.relative_to(package_root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules(package_root: Path) -> dict[str, Path]:
    return {module_name(p, package_root): p for p in sorted(package_root.rglob("*.py"))}


def is_package(name: str, known: dict[str, Path]) -> bool:
    return known[name].name == "__init__.py"


def imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The planefmt modules that module ``name`` imports."""
    package = name if is_package(name, known) else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name in known)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target not in known:
                continue
            subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in known]
            found.update(subs)
            if len(subs) < len(node.names):
                found.add(target)
    found.discard(name)
    return found


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def layer(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def private_uses(converters: Path, known: dict[str, Path]) -> list[str]:
    """``file:line name`` for each private planefmt name the converters use."""
    found = []
    for path in sorted(converters.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        bound: set[str] = set()  # local names bound to planefmt modules
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").startswith("planefmt"):
                for a in node.names:
                    if a.name.startswith("_") and not a.name.startswith("__"):
                        found.append(f"{path.name}:{node.lineno} {node.module}.{a.name}")
                    if f"{node.module}.{a.name}" in known:
                        bound.add(a.asname or a.name)
            elif isinstance(node, ast.Import):
                bound.update((a.asname or a.name).split(".")[0] for a in node.names if a.name in known)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
                    and isinstance(node.value, ast.Name) and node.value.id in bound):
                found.append(f"{path.name}:{node.lineno} {node.value.id}.{node.attr}")
    return found


def check(root: Path) -> list[tuple[bool, str]]:
    package_root = root / "planefmt"
    known = modules(package_root)
    graph = {name: imports(name, path, known) for name, path in known.items()}
    results = []

    found = cycles(graph)
    results.append((not found, f"import cycles among {len(known)} planefmt modules: {len(found)}"
                    + "".join(f"\n    {' <-> '.join(c)}" for c in found)))

    lines = {name: len(path.read_text().splitlines()) for name, path in known.items()}
    largest = max(lines, key=lines.get)
    results.append((lines[largest] <= MAX_LINES,
                    f"largest module: {largest}, {lines[largest]} lines (at most {MAX_LINES})"))

    packages = sorted(n for n in known if n.count(".") == 1 and is_package(n, known))
    results.append((len(packages) >= MIN_PACKAGES,
                    f"sub-packages: {len(packages)} ({', '.join(p.split('.')[1] for p in packages)}; "
                    f"at least {MIN_PACKAGES})"))

    spec = root / "spec" / "pln.md"
    results.append((spec.is_file(), f"spec/pln.md: {'present' if spec.is_file() else 'missing'}"))

    wrong = sorted(f"{a} -> {b}" for a, deps in graph.items() for b in deps
                   if (layer(a), layer(b)) in FORBIDDEN)
    results.append((not wrong, f"imports against the layering (container < geometry < groups < codec): "
                    f"{len(wrong)}" + "".join(f"\n    {w}" for w in wrong)))

    private = private_uses(root / "converters", known)
    results.append((not private, f"private planefmt names used by converters/: {len(private)}"
                    + "".join(f"\n    {p}" for p in private)))
    return results


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    root = Path(args[0]) if args else Path(__file__).resolve().parent.parent
    results = check(root)
    for ok, line in results:
        print(f"{'ok  ' if ok else 'FAIL'} {line}")
    return 0 if all(ok for ok, _ in results) else 1


if __name__ == "__main__":
    sys.exit(main())
