"""``pln report``: what a batch run's ledger says, in a few lines.

    pln report OUTDIR/pln-report.jsonl [--json] [--top N]

Counts by status, bytes in and out and what was saved, the output/input ratio per source extension,
the slowest inputs and the failed ones with their reason. Each source counts once, by its last line
(a resumed run's ``skipped`` line stands for the conversion an earlier run did). A torn last line, a
killed run's, is passed over. Exit status 1 when any input failed, else 0.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import PurePosixPath

from planefmt.errors import PlnError

from . import ledger


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="summarise the ledger of a batch conversion", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("ledger", metavar="FILE.jsonl", help="the ledger pln convert -d wrote (--report)")
    p.add_argument("--json", action="store_true", help="the summary as one JSON object")
    p.add_argument("--top", type=int, default=5, help="how many of the slowest and failed inputs to list (5)")
    p.set_defaults(func=run)


def summarise(path: str) -> dict:
    """The summary of the ledger at ``path`` as plain data."""
    try:
        last = {entry["source"]: entry for entry in ledger.read(path)}
    except OSError as exc:
        raise PlnError(f"cannot read the ledger: {exc.strerror or exc}", code="CONVERSION_FAILED", file=path) from exc
    entries = list(last.values())
    converted = [e for e in entries if e["status"] in ("ok", "skipped")]
    counts = Counter(e["status"] for e in entries)
    by_ext: dict[str, dict] = {}
    for e in converted:
        ext = PurePosixPath(e["source"]).suffix.lower() or "(none)"
        row = by_ext.setdefault(ext, {"files": 0, "bytes_in": 0, "bytes_out": 0})
        row["files"] += 1
        row["bytes_in"] += e.get("bytes_in") or 0
        row["bytes_out"] += e.get("bytes_out") or 0
    for row in by_ext.values():
        row["ratio"] = row["bytes_out"] / row["bytes_in"] if row["bytes_in"] else None
    bytes_in = sum(e.get("bytes_in") or 0 for e in converted)
    bytes_out = sum(e.get("bytes_out") or 0 for e in converted)
    timed = sorted((e for e in entries if e["status"] == "ok"), key=lambda e: -(e.get("seconds") or 0))
    return {
        "inputs": len(entries), "ok": counts["ok"], "skipped": counts["skipped"], "failed": counts["failed"],
        "bytes_in": bytes_in, "bytes_out": bytes_out, "bytes_saved": bytes_in - bytes_out,
        "ratio": bytes_out / bytes_in if bytes_in else None,
        "seconds": round(sum(e.get("seconds") or 0 for e in entries), 3),
        "by_extension": dict(sorted(by_ext.items())),
        "failures_by_code": dict(Counter(e.get("code") for e in entries if e["status"] == "failed").most_common()),
        "slowest": [{"source": e["source"], "seconds": e.get("seconds"), "peak_mb": e.get("peak_mb")} for e in timed],
        "failed_inputs": [{"source": e["source"], "code": e.get("code"), "message": e.get("message")}
                          for e in entries if e["status"] == "failed"],
    }


def run(args: argparse.Namespace) -> int:
    summary = summarise(args.ledger)
    if args.json:
        print(json.dumps(summary, indent=1))
        return 1 if summary["failed"] else 0
    ratio = "" if summary["ratio"] is None else f" (output {summary['ratio']:.2f}x the input)"
    lines = [f"{summary['inputs']} inputs: {summary['ok']} converted, {summary['skipped']} skipped (converted by "
             f"an earlier run), {summary['failed']} failed",
             f"{summary['bytes_in']:,} B in, {summary['bytes_out']:,} B out, {summary['bytes_saved']:,} B saved"
             f"{ratio}; {summary['seconds']:.1f} s of conversion"]
    if summary["by_extension"]:
        lines.append("by source extension:  files      bytes in     bytes out   out/in")
        for ext, row in summary["by_extension"].items():
            r = "-" if row["ratio"] is None else f"{row['ratio']:.3f}"
            lines.append(f"  {ext:<18} {row['files']:>5} {row['bytes_in']:>13,} {row['bytes_out']:>13,} {r:>8}")
    if summary["slowest"]:
        lines.append("slowest:")
        lines += [f"  {e['seconds']:8.2f} s  {e['source']}" for e in summary["slowest"][:args.top]]
    if summary["failed"]:
        codes = ", ".join(f"{code} {n}" for code, n in summary["failures_by_code"].items())
        lines.append(f"failed ({codes}):")
        lines += [f"  {e['message'] or e['source']}" for e in summary["failed_inputs"][:args.top]]
        if summary["failed"] > args.top:
            lines.append(f"  ... and {summary['failed'] - args.top} more (pln report --json lists them all)")
    print("\n".join(lines), file=sys.stdout)
    return 1 if summary["failed"] else 0
