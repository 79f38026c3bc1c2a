"""The papers' published numbers sit in one module (``geojax.papers``), with their sources; the command line,
the studies and the benchmarks read them there instead of keeping copies."""

import io
import tokenize
from pathlib import Path

from geojax import papers

ROOT = Path(__file__).resolve().parents[1]


def distinctive_numbers() -> set[float]:
    """The published values of three significant digits or more (0.09 or 0.03 would be found everywhere)."""
    values = [*(v for row in papers.LI2022.values() for v in row.values()), *papers.MA2023.values(),
              *(row[0] for row in papers.YE2022_TABLE3.values()), *papers.GAZZINO2016.values(),
              *(x for pair in papers.SOOP1994_EQUILIBRIA_DEG.values() for x in pair)]
    out = set()
    for value in values:
        text = str(value).lstrip("~+-")
        if len(text.replace(".", "").lstrip("0")) >= 3:
            out.add(abs(float(text)))
    return out


def literals(path: Path):
    """(line, number) of every numeric literal, and of every string literal that is a number alone."""
    for token in tokenize.generate_tokens(io.StringIO(path.read_text()).readline):
        text = token.string
        if token.type == tokenize.STRING:
            text = text.strip("\"'")
        try:
            yield token.start[0], abs(float(text))
        except ValueError:
            continue


def test_no_copy_of_a_published_number_outside_the_papers_module():
    wanted = distinctive_numbers()
    assert {60.2, 54.2, 728.0, 29.7, 44.04, 81.6} <= wanted
    copies = [f"{path.relative_to(ROOT)}:{line}: {number}"
              for folder in ("geojax", "studies", "benchmarks") for path in sorted((ROOT / folder).rglob("*.py"))
              if path.name != "papers.py" for line, number in literals(path) if number in wanted]
    assert not copies, copies


def test_the_published_numbers_of_a_run_and_how_this_run_differs():
    config = {"controller": {"kind": "fompc"}, "duration": {"days": 20.0}}
    table, source = papers.published("li2022-fompc", config)
    assert source == "Li 2022" and table["dv_per_year_mps"] == "54.2"
    assert papers.published("gazzino2016", config) == ({}, "")
    assert papers.departures(config, 0, {"controller": {"kind": "fompc"}, "duration": {"days": 365.25}}) == [
        "duration.days = 20.0"]
    assert papers.departures(config, 2, None) == ["the scenario (a file of one's own)"]
    assert papers.departures(config, 2, config) == ["seed = 2"]
    assert papers.published("katz2025-discrete", {"controller": {"thrust_mode": "discrete"}})[1] == "Katz 2025"
