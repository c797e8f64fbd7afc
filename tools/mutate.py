"""Plant small bugs in the guarantees, one at a time, and check that the tests catch each (`make mutate`).

    python tools/mutate.py [--keep] [NAME ...]

The repository's files (no .git, .venv or caches) are copied to a scratch
folder, its ``tests/corpus`` a link to the repository's (the mutants leave it alone);
each mutant is one or two text replacements in that copy, then the test files
that guard what it breaks run against the copy (``PYTHONPATH`` puts the copy's
``planefmt`` and, through a ``planefmt_converters`` link to ``converters/``,
its converters ahead of the editable install). A mutant is killed when one of those
tests fails; the copy is restored before the next. Prints one line per mutant
and exits 1 if any was not killed, or if the tests fail on the unmutated copy.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class Mutant:
    name: str
    path: str  # relative to the repository
    edits: tuple[tuple[str, str], ...]  # (old, new): old occurs exactly once
    tests: tuple[str, ...]  # test files or node ids


MUTANTS = (
    Mutant("crc check skipped", "planefmt/container/chunks.py",
           (('        if crc != int.from_bytes(tail, "little"):', "        if False:"),),
           ("tests/test_container.py",)),
    Mutant("recorded error bound = verifier's lower bound", "planefmt/codec/verifying.py",
           (("    return (upper if upper <= target else math.inf), max(lower - shift, 0.0)",
             "    lower = max(lower - shift, 0.0)\n    return (lower if upper <= target else math.inf), lower"),),
           ("tests/test_error_bound.py",)),
    Mutant("convex corner bound one way only", "planefmt/geometry/convexbound.py",
           (("    return max(ab, ba), max(ab_low, ba_low)", "    return ab, ab_low"),),
           ("tests/test_convexbound.py",)),
    Mutant("float32 outputs keep their flat triangles", "converters/assemble.py",
           (("        if welded is not None:\n            faces, colours, flat = _flip_flat(",
             "        if False:\n            faces, colours, flat = _flip_flat("),),
           ("tests/test_roundtrip.py",)),
    Mutant("shell error bound halved", "planefmt/codec/choosing.py",
           (("        bound = err / diagonal if diagonal > 0 else 0.0",
             "        bound = 0.5 * err / diagonal if diagonal > 0 else 0.0"),),
           ("tests/test_error_bound.py", "tests/test_shells.py")),
    Mutant("watertightness check disabled", "planefmt/codec/preparing.py",
           (("        if topology and not is_closed_manifold(mesh.faces, len(mesh.vertices)):", "        if False:"),),
           ("tests/test_watertight.py",
            "tests/test_codec_bodies.py::test_a_closed_source_that_decodes_open_is_refused_with_the_reason")),
    Mutant("atomic write replaced by direct write", "planefmt/container/writer.py",
           (('            os.fchmod(fd, mode)\n            self._fp: BinaryIO = os.fdopen(fd, "wb")',
             '            os.close(fd)\n            os.unlink(self._tmp)\n            self._tmp = str(self._path)\n'
             '            self._fp: BinaryIO = open(self._path, "wb")'),),
           ("tests/test_container.py",)),
    Mutant("quantization width off by one (h)", "planefmt/container/quantize.py",
           (("    m_h = float((1 << q.bits_h) - 1)", "    m_h = float((1 << (q.bits_h - 1)) - 1)"),),
           ("tests/test_container.py",)),
    Mutant("runner comparison disabled", "conformance/runner.py",
           (("def compare_valid(want: dict, got: dict, level: str) -> str | None:\n",
             "def compare_valid(want: dict, got: dict, level: str) -> str | None:\n    return None\n"),),
           ("tests/test_conformance.py::test_the_runner_fails_an_implementation_that_reports_a_wrong_value",
            "tests/test_conformance.py::test_the_runner_fails_a_reader_whose_plane_is_half_a_unit_off")),
    Mutant("salvage keeping a corrupt group", "planefmt/container/salvage.py",
           (('        if crc32(payload, crc32(head[:4])) != int.from_bytes(self.data[end:end + 4], "little"):',
             '        if crc32(payload, crc32(head[:4])) != int.from_bytes(self.data[end:end + 4], "little") \\\n'
             '                and head[:4] != b"GRUP":'),),
           ("tests/test_salvage.py",)),
)

#: Left out of the copy: version control, environments, caches, outputs.
IGNORED = (".git", ".venv", ".tools", "__pycache__", ".pytest_cache", ".hypothesis", "*.egg-info", "out",
           "corpus", "artifacts")


def scratch_copy(into: Path) -> Path:
    """The repository copied to ``into/repo``, its mesh corpus linked, not copied (12 MB)."""
    repo = into / "repo"
    shutil.copytree(ROOT, repo, ignore=shutil.ignore_patterns(*IGNORED), symlinks=True)
    (repo / "tests" / "corpus").symlink_to(ROOT / "tests" / "corpus", target_is_directory=True)
    # pyproject.toml installs converters/ as planefmt_converters; the link lets PYTHONPATH find it.
    (repo / "planefmt_converters").symlink_to("converters", target_is_directory=True)
    return repo


def environment(repo: Path) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(repo), os.environ.get("PYTHONPATH")])))


def check_imports(repo: Path) -> None:
    """Stop unless the copy's packages are the ones imported, not the editable install's."""
    code = "import planefmt, planefmt_converters; print(planefmt.__file__); print(planefmt_converters.__file__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=repo,
                         env=environment(repo)).stdout.split()
    if not all(Path(p).resolve().is_relative_to(repo.resolve()) for p in out):
        raise SystemExit(f"mutate: the copy's packages are not the ones imported ({out})")


def run_tests(repo: Path, tests: tuple[str, ...], jobs: str) -> str:
    """``passed``, ``failed: TEST`` (TEST the first that failed) or why there is no verdict."""
    p = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-rf", "-p", "no:cacheprovider", "-n", jobs, *tests],
                       cwd=repo, env=environment(repo), capture_output=True, text=True)
    # With -x, xdist ends the session as interrupted (exit 2) at the first failure: its FAILED line tells.
    failed = [line for line in p.stdout.splitlines() if line.startswith("FAILED ")]
    if p.returncode == 1 or (p.returncode == 2 and failed):
        return "failed: " + (failed[0][len("FAILED "):].split(" - ")[0] if failed else "")
    return "passed" if p.returncode == 0 else f"pytest exit {p.returncode}: {(p.stdout + p.stderr).strip()[-300:]}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tools/mutate.py", description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="mutants to plant (default: all); a substring of the name")
    parser.add_argument("--jobs", default="2", help="pytest-xdist workers per run (default 2)")
    parser.add_argument("--keep", action="store_true", help="keep the scratch copy")
    args = parser.parse_args(argv)
    chosen = [m for m in MUTANTS if not args.names or any(n in m.name for n in args.names)]
    scratch = Path(tempfile.mkdtemp(prefix="planefmt-mutate-"))
    try:
        repo = scratch_copy(scratch)
        check_imports(repo)
        # Every test run unmutated first: a mutant counts as killed only by tests that pass without it.
        baseline = tuple(dict.fromkeys(a for m in chosen for a in m.tests))
        start = time.monotonic()
        outcome = run_tests(repo, baseline, args.jobs)
        if outcome != "passed":
            print(f"mutate: the tests do not pass on the unmutated copy ({outcome}): {' '.join(baseline)}")
            return 1
        print(f"unmutated: passed ({time.monotonic() - start:.0f} s)", flush=True)
        survived = 0
        for m in chosen:
            path = repo / m.path
            original = path.read_text(encoding="utf-8")
            text = original
            for old, new in m.edits:
                if text.count(old) != 1:
                    print(f"mutate: {m.name}: the text to replace occurs {text.count(old)} times in {m.path}")
                    return 1
                text = text.replace(old, new)
            path.write_text(text, encoding="utf-8")
            start = time.monotonic()
            try:
                outcome = run_tests(repo, m.tests, args.jobs)
            finally:
                path.write_text(original, encoding="utf-8")
            killed = outcome.startswith("failed")
            verdict = "killed" if killed else "SURVIVED" if outcome == "passed" else f"no verdict ({outcome})"
            survived += not killed
            print(f"{verdict:8}  {m.name}  ({m.path}; {time.monotonic() - start:.0f} s)"
                  + (f"  by {outcome[len('failed: '):]}" if killed else ""), flush=True)
        print(f"{len(chosen) - survived} of {len(chosen)} mutants killed")
        return 1 if survived else 0
    finally:
        if args.keep:
            print(f"scratch copy kept: {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
