"""``pln validate FILE``: every finding with its code and severity; exit 1 on errors."""

from __future__ import annotations

import argparse
import json
import sys

from . import limits


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="check a .pln file against the spec", description=__doc__)
    p.add_argument("file", help="a .pln file, or - for standard input")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-geometry", action="store_true", help="check the container only, do not decode")
    limits.add_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from planefmt.container.validate import has_errors

    if args.no_geometry:  # the container's checks alone (the codec's with geometry=False): scipy not imported
        from planefmt.container.validate import validate
    else:
        from planefmt.codec import validate
    findings = validate(args.file, limits=limits.limits_of(args))
    ok = not has_errors(findings)
    if args.json:
        json.dump({"file": args.file, "valid": ok, "findings": [f.as_dict() for f in findings]}, sys.stdout,
                  indent=2)
        sys.stdout.write("\n")
    else:
        for f in findings:
            where = ": ".join(x for x in (f.file, f"chunk {f.chunk}" if f.chunk else None,
                                          f"at byte {f.offset}" if f.offset is not None else None,
                                          f"group {f.group}" if f.group is not None else None) if x)
            print(f"{f.severity}: {f.code}: {where}: {f.message}" if where else f"{f.severity}: {f.code}: {f.message}")
        print(f"{args.file}: {'valid' if ok else 'INVALID'} ({len(findings)} findings)")
    return 0 if ok else 1
