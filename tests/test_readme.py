"""The Python examples of the README and the documentation run as written (in a fresh folder, one after another
in each page, as a reader would), and every command the README shows parses."""

import re
import shlex
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def python_examples(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


def test_the_documentation_has_its_examples():
    counts = {page.name: len(python_examples(page)) for page in PAGES}
    assert counts["README.md"] >= 1
    assert counts["python.md"] >= 3  # a batch, a controller of one's own (simulate, sweep, tuning), reading results


# python.md runs a year-long sweep and tuning: the slow tier
@pytest.mark.parametrize("page", [pytest.param(p, marks=[pytest.mark.slow] if p.name == "python.md" else [])
                                  for p in PAGES if python_examples(p)], ids=lambda p: p.name)
def test_the_python_examples_run_as_written(page, tmp_path, monkeypatch, capsys):
    """Each example in a namespace of its own (a reader copies one block; its files stay for the next)."""
    monkeypatch.chdir(tmp_path)
    seen = {}  # every example's names, the later ones last (each example still runs in a namespace of its own)
    for number, code in enumerate(python_examples(page), 1):
        namespace = {"__name__": "__docs__"}
        exec(compile(code, f"{page.name}, Python example {number}", "exec"), namespace)
        seen.update(namespace)
        if page.name == "python.md" and number == 1:  # the batch stays in the box: every status 0, as it says
            assert capsys.readouterr().out.splitlines()[0] == "[100   0   0   0   0   0]"
    if page.name == "python.md":
        assert (tmp_path / "mine.h5").is_file()
        assert seen["ds"].dv_per_year_mps.dims == ("controller", "controller.k_inc_per_s", "repetition")
    if page.name == "README.md":
        assert seen["result"].metrics["dv_per_year_mps"] > 0
        assert (tmp_path / "qffc.h5").is_file()


def readme_commands() -> list[list[str]]:
    block = re.search(r"## One example per command\n\n```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    return [shlex.split(line.split("#")[0].split(">")[0]) for line in block.group(1).splitlines() if line.strip()]


def test_every_command_the_readme_shows_parses_and_names_files_that_exist():
    """The README's one example per command: each parses with the real parser, and the files it names exist."""
    from geojax import cli, scenario

    commands = readme_commands()
    shown = {argv[1] for argv in commands}
    subparsers = [a for a in cli._parser()._actions if a.__class__.__name__ == "_SubParsersAction"][0]
    assert shown >= set(subparsers.choices) - {"demo"}  # the demo is in the set-up commands
    for argv in commands:
        assert argv[0] == "geojax"
        args = cli._parser().parse_args(argv[1:])
        for name in ("scenario", "file"):
            value = getattr(args, name, None)
            if value and value.endswith(".toml"):
                assert (ROOT / value).is_file(), argv
            elif value and name == "scenario":
                assert value in scenario.available() or value.startswith("ma2023"), argv


def test_no_readme_command_is_one_measured_to_take_over_two_minutes():
    """The README's examples run in under two minutes as written: a command docs/measured_times.json records
    (the original measurements and those of the cut examples) must have been measured under 120 s, so the
    README cannot go back to the 14.5-minute sweep or the year-long tuning without this failing."""
    import json

    measured = json.loads((ROOT / "docs" / "measured_times.json").read_text())
    runs = [*measured["runs"], *measured["readme_examples"]["runs"]]
    times = {tuple(shlex.split(run["command"])): run["wall_s"] for run in runs}
    shown = {tuple(argv) for argv in readme_commands()}
    assert {("geojax", "sweep"), ("geojax", "tune"), ("geojax", "bound")} <= {argv[:2] for argv in shown & times.keys()}
    for argv in shown & times.keys():
        assert times[argv] is not None and times[argv] < 120, " ".join(argv)
    unmeasured = sorted(" ".join(argv) for argv in shown - times.keys())
    assert not unmeasured, f"no measured time (python benchmarks/readme_examples.py --missing --write): {unmeasured}"
