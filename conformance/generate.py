"""Rebuild every golden file of the suite, byte for byte: ``python -m conformance.generate [DIR]``.

Writes ``valid/*.pln`` and ``invalid/*.pln``, each with its expected-result
JSON beside it, and ``manifest.tsv``, into DIR (default: this package's
folder), after removing the .pln and .json files a previous run left there.
Nothing depends on time, randomness or the machine, except the deflate
output of the zlib build (see README.md).
"""

from __future__ import annotations

import sys
from pathlib import Path

from . import cases_invalid, cases_valid
from .build import dumps

HERE = Path(__file__).resolve().parent
MANIFEST_HEAD = "path\texpected\tlevel\tdescription\n"


def files() -> dict[str, bytes]:
    """Every generated file, by path relative to the suite's folder."""
    out: dict[str, bytes] = {}
    rows = []
    for case in cases_valid.CASES:
        data, expected = cases_valid.build(case)
        out[f"valid/{case.name}.pln"] = data
        out[f"valid/{case.name}.json"] = (dumps(expected) + "\n").encode()
        rows.append((f"valid/{case.name}.pln", "ok", "container", case.description))
    for case in cases_invalid.CASES:
        out[f"invalid/{case.name}.pln"] = case.make()
        expected = {"error": case.error, "also": list(case.also)}
        out[f"invalid/{case.name}.json"] = (dumps(expected) + "\n").encode()
        rows.append((f"invalid/{case.name}.pln", "|".join((case.error,) + case.also), case.level,
                     case.description))
    out["manifest.tsv"] = (MANIFEST_HEAD + "".join("\t".join(r) + "\n" for r in rows)).encode()
    return out


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    root = Path(argv[0]) if argv else HERE
    generated = files()
    for folder in ("valid", "invalid"):
        (root / folder).mkdir(parents=True, exist_ok=True)
        for old in [*(root / folder).glob("*.pln"), *(root / folder).glob("*.json")]:
            old.unlink()
    for name, data in generated.items():
        (root / name).write_bytes(data)
    print(f"{sum(n.endswith('.pln') for n in generated)} files written to {root}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
