"""Malformed sweep, tuning and scenario files, generated from valid ones by a seeded mutator.

Each mutation is malformed by construction (an unknown key, a value of the wrong type, a value out of any
sensible range, a table where a value belongs or the reverse), and the check for every one is the contract
of the command line for bad input: exit status 2, one line on stderr naming the fault, no traceback, and the
folder unchanged.  The run functions are replaced by ones that fail the test, so a file that is accepted is
reported as such instead of running a simulation.
"""

from __future__ import annotations

import os
import random

import pytest

from geojax import cli, scenario, sweep, tune
from geojax.runner import rollout
from geojax.scenario import tomllib

SWEEP = """
name = "fuzz"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 2
seed = 3
cycles = false
[set]
"duration.days" = 2.0
"errors.h_rv" = 1.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
[dispersion]
mee_1sigma = [0.1, 1e-6, 1e-6, 1e-6, 1e-6, 1e-5]
"""

TUNING = """
scenario = "katz2025-discrete"
parameters = ["k_h", "k_e"]
starts = 2
iterations = 2
days = 2.0
"""

CASES = int(os.environ.get("GEOJAX_FUZZ_CASES", "40"))  # per file kind; a larger campaign: set it higher
BAD_SCALARS = ["text", -1.0e30, 1.0e30, float("nan"), float("inf"), [1.0, "x"], {"nested": 1.0}]


def _leaves(table: dict, prefix=()):
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _leaves(value, prefix + (key,))
        else:
            yield prefix + (key,), value


def _get_parent(table: dict, path):
    for key in path[:-1]:
        table = table[key]
    return table


def _bad_value(key: str, value, rng: random.Random):
    """A replacement for ``value`` that no field of its kind accepts."""
    if isinstance(value, bool):
        return rng.choice(["yes", 2.5, [True], {"on": True}])
    if isinstance(value, (int, float)):
        return rng.choice(BAD_SCALARS)
    if isinstance(value, str):
        free_text = key in ("name", "description")
        return rng.choice([12.5, ["a", "b"], {"table": "x"}] + ([] if free_text else ["no-such-" + value]))
    if isinstance(value, list):
        return rng.choice(["not a list", [], [[1.0], [2.0]], [{"x": 1}], {"x": [1.0]}])
    return "not a table"


def mutate(raw: dict, rng: random.Random) -> tuple[dict, str]:
    """One malformed copy of ``raw`` and a description of the change."""
    raw = tomllib.loads(_dump(raw))  # deep copy
    leaves = list(_leaves(raw))
    kind = rng.choice(["unknown key", "bad value", "bad value", "scalar for table", "table for scalar"])
    if kind == "unknown key":
        tables = [()] + [path for path, _ in _leaves_tables(raw)]
        where = rng.choice(tables)
        target = _get_parent(raw, where + ("_",))
        if where and where[-1] == "grid":  # a grid key is a scenario key: misspell one
            target["thrusters.beta_maxx_deg"] = [60.0]
        elif where and where[-1] == "set":
            target[rng.choice(["days", "duration.dayz", "nosuch.table"])] = 5.0
        else:
            target[rng.choice(["bogus", "Seed", "repetition"])] = 1
        return raw, f"unknown key in {'.'.join(where) or 'top level'}"
    if kind == "table for scalar" or not [p for p, _ in _leaves_tables(raw)]:
        path, value = rng.choice(leaves)
        _get_parent(raw, path)[path[-1]] = {"nested": value}
        return raw, f"{'.'.join(path)}: a table"
    if kind == "scalar for table":
        path, _ = rng.choice(list(_leaves_tables(raw)))
        _get_parent(raw, path)[path[-1]] = rng.choice([5, "x", [1, 2]])
        return raw, f"{'.'.join(path)}: a scalar for a table"
    path, value = rng.choice(leaves)
    bad = _bad_value(path[-1], value, rng)
    _get_parent(raw, path)[path[-1]] = bad
    return raw, f"{'.'.join(path)} = {bad!r}"


def _leaves_tables(table: dict, prefix=()):
    for key, value in table.items():
        if isinstance(value, dict):
            yield prefix + (key,), value
            yield from _leaves_tables(value, prefix + (key,))


def _dump(raw: dict) -> str:
    return scenario.to_toml(raw)


def _must_not_run(*args, **kwargs):
    raise AssertionError("a malformed file was accepted and the run started")


@pytest.fixture
def no_runs(monkeypatch):
    monkeypatch.setattr(sweep, "run_sweep", _must_not_run)
    monkeypatch.setattr(tune, "tune", _must_not_run)
    monkeypatch.setattr(rollout, "simulate", _must_not_run)


def _check(tmp_path, capsys, command, text, description) -> str | None:
    """None if the malformed file got the bad-input treatment, else what went wrong."""
    folder = tmp_path / "work"
    folder.mkdir(exist_ok=True)
    spec = folder / "input.toml"
    spec.write_text(text)
    before = sorted(p.name for p in folder.iterdir())
    out = folder / "out.h5"
    argv = {"sweep": ["sweep", str(spec), "--out", str(out)], "tune": ["tune", str(spec), "--out", str(out)],
            "simulate": ["simulate", str(spec), "--out", str(out)]}[command]
    try:
        code = cli.main(argv)
    except BaseException as err:  # noqa: BLE001  (any escape is a finding)
        code = f"{type(err).__name__}: {err}"
    captured = capsys.readouterr()
    left = sorted(p.name for p in folder.iterdir()) != before
    spec.unlink()
    if code != 2:
        return f"{description}: exit {code}"
    if captured.err.count("\n") != 1 or "Traceback" in captured.err:
        return f"{description}: stderr {captured.err!r}"
    if left:
        return f"{description}: left files"
    return None


@pytest.mark.parametrize("command, base", [("sweep", SWEEP), ("tune", TUNING),
                                           ("simulate", scenario.read_text("li2022-fompc")),
                                           ("simulate", scenario.read_text("katz2025-discrete"))])
def test_malformed_files_exit_2_with_one_line_and_leave_nothing(tmp_path, capsys, no_runs, command, base):
    raw = tomllib.loads(base)
    rng = random.Random(f"{command}-{raw.get('name', '')}-malformed")  # seeded: the same campaign every run
    findings = []
    for _ in range(CASES):
        bad, description = mutate(raw, rng)
        findings.append(_check(tmp_path, capsys, command, _dump(bad), description))
    assert not [f for f in findings if f], "\n".join(f for f in findings if f)
