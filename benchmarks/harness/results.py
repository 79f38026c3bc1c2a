"""A benchmark's results: ``NAME.json`` (``{"meta": ..., **data}``) and ``NAME.md`` (a title, one line that
says how, where and from what the numbers were measured, then the script's tables), written the same way by
every script.

``start`` sets the devices up and notes the start; ``write`` adds the facts at the end (machine, software,
revision, load average at start and end, total wall time) and writes both files.
"""

from __future__ import annotations

import datetime as _dt
import json
import time
from pathlib import Path
from typing import Iterable, NamedTuple, Sequence

from harness import devices as _devices
from harness import machine

RESULTS_DIR = Path(__file__).resolve().parents[1] / "results"


class Run(NamedTuple):
    """A benchmark run under way: how it was started."""

    command: str  # python benchmarks/NAME.py ARGS
    started_utc: str
    load_average_start: list[float]
    start_s: float  # time.perf_counter() at the start
    devices: dict  # what devices.set_up set


def start(devices: _devices.Devices = _devices.Devices(), argv: list[str] | None = None) -> Run:
    """Set the devices up (before JAX starts its backend) and note the command, time and load."""
    record = _devices.set_up(devices)
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return Run(machine.command_line(argv), now, machine.load_average(), time.perf_counter(), record)


def write(stem: Path, run: Run, title: str, data: dict, body: Sequence[str], facts: dict | None = None) -> str:
    """Write ``stem.json`` and ``stem.md`` of a run that ends now; return the Markdown.

    ``data``: the measurements (JSON-ready); ``body``: the Markdown under the header line; ``facts``: the
    script's own facts for ``meta`` (a peer's version, whether the run was quick).
    """
    meta = {"command": run.command, "date_utc": run.started_utc, "wall_s": time.perf_counter() - run.start_s,
            "load_average": {"start": run.load_average_start, "end": machine.load_average()},
            **run.devices, **machine.facts(), **(facts or {})}
    return save(stem, meta, title, data, body)


def save(stem: Path, meta: dict, title: str, data: dict, body: Sequence[str]) -> str:
    """Write ``stem.json`` and ``stem.md`` with ``meta`` as ``write`` made it (the tables of an earlier run
    written again keep the facts of that run); return the Markdown."""
    text = "\n".join([f"# {title}", "", header(meta), "", *body]).rstrip("\n") + "\n"
    stem.parent.mkdir(parents=True, exist_ok=True)
    stem.with_suffix(".json").write_text(json.dumps({"meta": meta, **data}, indent=1) + "\n")
    stem.with_suffix(".md").write_text(text)
    return text


def read(stem: Path) -> tuple[dict, dict]:
    """(meta, data) of ``stem.json`` as ``write`` wrote it (meta empty for a file from before the harness)."""
    data = json.loads(stem.with_suffix(".json").read_text())
    return data.pop("meta", {}), data


def header(meta: dict) -> str:
    """The line under a results file's title: the command, when, from which source, on what."""
    load = meta["load_average"]
    return (f"`{meta['command']}`, {meta['date_utc']}, {meta['wall_s']:.0f} s; geojax {meta['geojax']} at "
            f"{short_revision(meta['source_revision'])}; {len(meta['cores'])} of {meta['cpu_count']} cores "
            f"({meta['cpu_model']}), load average {load['start'][0]:.1f} at the start and {load['end'][0]:.1f} at "
            f"the end; {meta['device']}; JAX {meta['jax']}, jaxlib {meta['jaxlib']}; "
            f"`XLA_FLAGS={meta['xla_flags']}`.")


def short_revision(revision: str) -> str:
    """``6b1d79f`` of ``6b1d79f…+dirty`` (``+dirty`` kept: uncommitted changes)."""
    commit, plus, rest = revision.partition("+")
    return commit[:7] + plus + rest


def table(head: Sequence[str], rows: Iterable[Sequence], align: str | None = None) -> list[str]:
    """A Markdown table: ``align`` one letter a column, ``l`` or ``r`` (default: the first left, the rest right)."""
    align = align or "l" + "r" * (len(head) - 1)
    rule = "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"
    return ["| " + " | ".join(head) + " |", rule, *("| " + " | ".join(str(c) for c in row) + " |" for row in rows)]


def ratios(values: dict[str, float], peers: dict[str, float]) -> dict[str, dict[str, float]]:
    """{name: {peer: value / peer's value}}: rates measured in the same run, each over each peer's."""
    return {name: {peer: value / other for peer, other in peers.items()} for name, value in values.items()}


def ratio_table(table_of_ratios: dict[str, dict[str, float]], corner: str, digits: str = ".3g") -> list[str]:
    """``ratios``' dict as a Markdown table: a row a name, a column a peer."""
    peers = list(next(iter(table_of_ratios.values())))
    return table([corner, *(f"/ {p}" for p in peers)],
                 [[name, *(f"{row[p]:{digits}}" for p in peers)] for name, row in table_of_ratios.items()])


def add_arguments(parser, out: Path = RESULTS_DIR) -> None:
    """The flags every benchmark takes: ``--out`` (the results folder) and ``--platform``."""
    shown = out.relative_to(RESULTS_DIR.parents[1]) if out.is_relative_to(RESULTS_DIR.parents[1]) else out
    parser.add_argument("--out", type=Path, default=out, help=f"folder for the results files (default: {shown})")
    parser.add_argument("--platform", help="JAX platform to run on (cpu, cuda, ...; default: JAX's choice)")
