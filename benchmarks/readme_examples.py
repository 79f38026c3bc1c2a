"""The README's example commands as written, timed: what ``docs/measured_times.json``'s ``readme_examples`` holds.

    python benchmarks/readme_examples.py [--missing] [--only TEXT ...] [--write]

Runs each command of the README's "One example per command" block (a shell line, redirection included) in one
scratch folder, in the README's order (a later command may read an earlier one's file), each with an empty
compilation cache folder of its own (*cold*: a new user's first run, its programs compiled), and prints its wall
time, exit status, the load average before and after, and its last line of output.  ``--missing``: only the
commands ``docs/measured_times.json`` has no time for; ``--only``: those containing TEXT.  ``--write`` records
the times in ``readme_examples.runs`` (replacing an entry of the same command), each with how it was measured
(date, commit, cold cache, cores, load); ``tests/test_readme.py`` checks that every command has a time under two
minutes.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TIMES = ROOT / "docs" / "measured_times.json"


def readme_lines() -> list[str]:
    """The block's command lines, their comments cut (as ``tests/test_readme.py`` reads them)."""
    block = re.search(r"## One example per command\n\n```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    return [line.split("#")[0].strip() for line in block.group(1).splitlines() if line.strip()]


def key(line: str) -> str:
    """The command as ``measured_times.json`` names it: the words before any redirection."""
    return shlex.join(shlex.split(line.split(">")[0]))


def timed(line: str, folder: Path) -> dict:
    cache = tempfile.mkdtemp(prefix="cache-", dir=folder)
    env = {**{k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}, "GEOJAX_CACHE_DIR": cache}
    before = os.getloadavg()[0]
    begun = time.perf_counter()
    done = subprocess.run(["bash", "-c", line], cwd=folder / "work", env=env, capture_output=True, text=True)
    wall_s = time.perf_counter() - begun
    lines = [x for x in (done.stdout + done.stderr).splitlines() if x.strip()]
    return {"command": key(line), "wall_s": round(wall_s, 1), "exit": done.returncode,
            "load": [round(before, 1), round(os.getloadavg()[0], 1)], "printed": lines[-1][:160] if lines else ""}


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--missing", action="store_true", help="only the commands without a measured time")
    parser.add_argument("--only", nargs="+", default=[], help="only the commands containing one of these")
    parser.add_argument("--write", action="store_true", help="record the times in docs/measured_times.json")
    args = parser.parse_args(argv)
    measured = json.loads(TIMES.read_text())
    have = {run["command"] for run in (*measured["runs"], *measured["readme_examples"]["runs"])
            if run["wall_s"] is not None}
    lines = [line for line in readme_lines() if not (args.missing and key(line) in have)
             and (not args.only or any(text in line for text in args.only))]
    runs = []
    with tempfile.TemporaryDirectory(prefix="readme-") as scratch:
        folder = Path(scratch)
        (folder / "work").mkdir()
        for line in lines:
            run = timed(line, folder)
            runs.append(run)
            print(f"{run['wall_s']:7.1f} s  exit {run['exit']}  load {run['load']}  {line}\n           {run['printed']}",
                  flush=True)
    if args.write:
        examples = measured["readme_examples"]
        kept = [r for r in examples["runs"] if r["command"] not in {run["command"] for run in runs}]
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                                text=True).stdout.strip()
        when = time.strftime("%Y-%m-%d", time.gmtime())
        examples["runs"] = kept + [
            {"command": run["command"], "wall_s": run["wall_s"], "printed": run["printed"],
             "measured": f"benchmarks/readme_examples.py, {when}, {commit}, cold cache, {os.cpu_count()} CPU cores, "
                         f"load {run['load'][0]} before and {run['load'][1]} after"} for run in runs]
        TIMES.write_text(json.dumps(measured, indent=2, ensure_ascii=False) + "\n")
        print(f"wrote {TIMES.relative_to(ROOT)}")
    return 0 if all(run["exit"] == 0 for run in runs) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
