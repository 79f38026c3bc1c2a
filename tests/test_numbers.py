"""Every number of our results in the tables of studies/README.md and docs/ comes from a results file.

Independent check: the results files (``studies/*/results/``, ``benchmarks/results/``) are written by the scripts
that measured them; a table's number is looked up, to the digits it is printed with, among the numbers of the
results files its section names (a script ``li2022/one_year.py`` names ``li2022/results/one_year*``, a path
``.../results/x.md`` names itself), and every number of a cell must be in one and the same file.  A number changed in a page and not in its results file, or a results file
regenerated without its page, fails here.  Columns that hold a paper's claims (the header names the paper, "paper"
or "claim") are not ours and are skipped; so are the agree/differ columns' derived percentages.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NUMBER = re.compile(r"(?<![\w.])[−+-]?\d+(?:\.\d+)?(?:e[−+-]?\d+)?")
THEIRS = re.compile(r"paper|claim|published|expected|agree|cause|note|Li 2022|Katz|Ye 2022|Gazzino|Ma &|figure|what", re.I)
PAGES = [ROOT / "studies" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def parse(token: str) -> float:
    return float(token.replace("−", "-"))


def half_unit(token: str) -> float:
    """Half a unit in the last printed digit of ``token`` ("0.0062" -> 5e-5, "4e-8" -> 5e-9)."""
    mantissa, _, exponent = token.replace("−", "-").partition("e")
    digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10.0 ** (int(exponent or 0) - digits)


def results_files(section: str) -> list[Path]:
    found = set()
    for name in re.findall(r"([\w/\-]+\.py|[\w/\-]+/results/[\w.\-]+)", section):
        for path in [ROOT / name, ROOT / "studies" / name, *(ROOT / "studies").glob(f"*/{name}")]:
            if path.is_file() and path.suffix == ".py":
                found |= {f for f in (path.parent / "results").glob(f"{path.stem}*")
                          if f.is_file() and f.suffix in (".md", ".json")}
            elif path.is_file() and path.suffix in (".md", ".json"):
                found.add(path)
    return sorted(found)


def our_cells(section: str):
    """(row label, cell) of every table cell of ours in ``section``."""
    header = None
    for line in section.splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        elif not re.fullmatch(r"\|[\s:|-]+\|?", line.strip()):
            for title, cell in zip(header[1:], cells[1:]):
                if not THEIRS.search(title) or re.search(r"geojax|ours", title, re.I):
                    yield cells[0], cell


def found_in(tokens: list[str], numbers: list[float]) -> bool:
    return all(any(abs(abs(k) - abs(parse(t))) <= half_unit(t) * (1 + 1e-9) for k in numbers) for t in tokens)


def unsourced(text: str, label: str) -> list[str]:
    """The cells of ours in ``text`` whose numbers are not all in one results file of their section."""
    misses = []
    for section in re.split(r"\n(?=#+ )", text):
        files = results_files(section)
        if not files or "|" not in section:
            continue
        numbers = [[parse(t) for t in NUMBER.findall(f.read_text(errors="ignore"))] for f in files]
        for row, cell in our_cells(section):
            tokens = NUMBER.findall(cell)
            if tokens and not any(found_in(tokens, pool) for pool in numbers):
                misses.append(f"{label}: row {row[:50]!r}: the numbers of {cell[:120]!r} are not all in any one of "
                              f"{', '.join(str(f.relative_to(ROOT)) for f in files)}")
    return misses


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_number_of_ours_has_a_results_file(page):
    misses = unsourced(page.read_text(), str(page.relative_to(ROOT)))
    assert not misses, "\n".join(misses)


def test_the_check_catches_a_changed_number():
    """The checker itself: a cell copied from a results file passes; the same cell with one number changed in its
    last printed digit (to a value the file does not hold) fails, as does a number from no file."""
    source = "studies/li2022/results/uncontrolled_year.md"
    numbers = [n for n in NUMBER.findall((ROOT / source).read_text()) if "." in n and len(n) >= 6][:3]
    assert len(numbers) == 3
    page = f"## A section\n\nFrom `{source}`:\n\n| case | geojax |\n|---|---|\n| row | {' / '.join(numbers)} |\n"
    assert unsourced(page, "page") == []
    pool = [parse(n) for n in NUMBER.findall((ROOT / source).read_text())]
    last = numbers[-1]
    changed = next(last[:-1] + d for d in "0123456789" if not found_in([last[:-1] + d], pool))
    assert unsourced(page.replace(last, changed), "page")
    assert unsourced(page.replace(" |\n", " / 123.456789 |\n"), "page")
