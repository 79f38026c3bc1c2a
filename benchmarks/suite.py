"""The test suite's time, per tier and per file: where the suite's minutes go.

Runs ``python -m pytest -q`` (the default tier, what the README and CI run) and, with ``--slow``, the slow tier
(``-m slow``), each with a JUnit report, and writes ``benchmarks/results/suite.{md,json}``: the wall time of
each tier, the summed test time, and the slowest files and tests.  ``--junit NAME=FILE`` reads a report an
earlier run wrote instead of running that tier (the results then name the file it came from); ``--keep NAME``
keeps that tier's summary from the results file as it is (its source then says from which run).  Tests share one
compilation cache per run (``tests/conftest.py``), so a file's time is mostly the XLA compilations it is the
first to ask for; the slowest files are where a shared fixture or a shorter run saves the most.

    python benchmarks/suite.py                # the default tier, about as long as the README says
    python benchmarks/suite.py --slow         # both tiers
    python benchmarks/suite.py --junit default=ci.xml --keep slow   # a CI run's report, the last slow tier kept
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from harness import results

ROOT = Path(__file__).resolve().parents[1]
TIERS = {"default": [], "slow": ["-m", "slow"]}


def read_junit(path: Path) -> tuple[list[tuple[str, str, float]], float]:
    """(file, test, seconds) of every test case of a JUnit report (setup and teardown included, as pytest
    counts them), and the run's wall time as pytest reports it (its ``testsuite`` time), s."""
    root = ET.parse(path).getroot()
    suite = root if root.tag == "testsuite" else root.find("testsuite")
    cases = [(case.get("classname").split(".")[-1] + ".py", case.get("name"), float(case.get("time")))
             for case in root.iter("testcase")]
    return cases, float(suite.get("time"))


def run_tier(name: str, report: Path) -> None:
    """Run one tier with a JUnit report."""
    subprocess.run([sys.executable, "-m", "pytest", "-q", *TIERS[name], f"--junitxml={report}"], cwd=ROOT)


def tier_summary(cases, wall_s: float | None, source: str, top: int) -> dict:
    by_file = collections.Counter()
    counts = collections.Counter()
    for file, _, seconds in cases:
        by_file[file] += seconds
        counts[file] += 1
    return {"source": source, "wall_s": wall_s, "tests": len(cases), "test_s": sum(s for *_, s in cases),
            "files": [{"file": f, "tests": counts[f], "test_s": s} for f, s in by_file.most_common(top)],
            "slowest": [{"test": f"{f}::{t}", "test_s": s} for f, t, s in sorted(cases, key=lambda c: -c[2])[:top]]}


def markdown(summaries: dict) -> list[str]:
    lines = ["| tier | tests | wall | summed test time | source |", "|---|---:|---:|---:|---|"]
    for name, s in summaries.items():
        wall = f"{s['wall_s'] / 60:.1f} min"
        lines.append(f"| {name} | {s['tests']} | {wall} | {s['test_s'] / 60:.1f} min | {s['source']} |")
    for name, s in summaries.items():
        lines += ["", f"## {name}: the slowest files", "", "| file | tests | s |", "|---|---:|---:|"]
        lines += [f"| {f['file']} | {f['tests']} | {f['test_s']:.0f} |" for f in s["files"]]
        lines += ["", f"## {name}: the slowest tests", "", "| test | s |", "|---|---:|"]
        lines += [f"| `{t['test']}` | {t['test_s']:.0f} |" for t in s["slowest"]]
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slow", action="store_true", help="run the slow tier too")
    parser.add_argument("--junit", action="append", default=[], metavar="TIER=FILE",
                        help="read this tier's JUnit report instead of running it")
    parser.add_argument("--keep", action="append", default=[], metavar="TIER",
                        help="keep this tier's summary from the results file (not run, not read from a report)")
    parser.add_argument("--top", type=int, default=20, help="files and tests listed per tier")
    parser.add_argument("--out", type=Path, default=results.RESULTS_DIR)
    args = parser.parse_args(argv)
    run = results.start()
    given = dict(item.split("=", 1) for item in args.junit)
    unknown = set(given) - set(TIERS)
    if unknown:
        parser.error(f"--junit: tiers are {', '.join(TIERS)}, got {', '.join(sorted(unknown))}")
    unknown = set(args.keep) - set(TIERS)
    if unknown:
        parser.error(f"--keep: tiers are {', '.join(TIERS)}, got {', '.join(sorted(unknown))}")
    kept = {}
    if args.keep:
        before = json.loads((args.out / "suite.json").read_text())
        for name in args.keep:
            kept[name] = dict(before["tiers"][name])
            if not kept[name]["source"].startswith("kept from"):
                kept[name]["source"] = (f"kept from the run of {before['meta']['date_utc']} at "
                                        f"{before['meta']['source_revision'][:7]} ({kept[name]['source']})")
    summaries = {}
    for name in TIERS:
        if name in kept:
            summaries[name] = kept[name]
        elif name in given:
            summaries[name] = tier_summary(*read_junit(Path(given[name])), given[name], args.top)
        elif name == "default" or args.slow:
            report = args.out / f"suite-{name}.xml"
            run_tier(name, report)
            summaries[name] = tier_summary(*read_junit(report), "this run", args.top)
            report.unlink()
    print(results.write(args.out / "suite", run, "The test suite's time", {"tiers": summaries}, markdown(summaries)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
